#!/bin/sh
# farm_lateauth.sh - a worker whose AUTH reaches the master only after the
# master's AUTH deadline has passed (here: the master is SIGSTOPped past it,
# so the proof and the due timer are seen in the same round of its loop),
# and which then never answers the SCENE_OFFER, must still be dropped: the
# OFFER's deadline is what is left of one heartbeat timeout since the OFFER
# left, and nothing left must not mean no deadline at all.
# A fake worker in python3 (skipped without it): HELLO, then after the
# master's AUTH it stops the master for 1.5 s, sends a valid AUTH, continues
# the master, and never says anything more. Expected: exit 69 within 15 s.
. "$(dirname "$0")/farm_lib.inc"
if ! command -v python3 >/dev/null 2>&1; then
	echo "python3 not installed"
	exit 77
fi
printf 'correct horse battery staple\n' >"$T/secret"
chmod 600 "$T/secret"
cat >"$T/late.py" <<'PY'
import hmac, hashlib, os, signal, socket, struct, sys, time
port_file, secret_file, pid_file = sys.argv[1:4]
secret = open(secret_file, 'rb').read().rstrip(b'\r\n')
ls = socket.socket()
ls.bind(('127.0.0.1', 0))
ls.listen(4)
open(port_file + '.tmp', 'w').write(str(ls.getsockname()[1]))
os.rename(port_file + '.tmp', port_file)
c, _ = ls.accept()
buf = b''
def frame():
    global buf
    while True:
        if len(buf) >= 12:
            _, _, typ, ln = struct.unpack('>IHHI', buf[:12])
            if len(buf) >= 12 + ln:
                p, buf = buf[12:12 + ln], buf[12 + ln:]
                return typ, p
        d = c.recv(65536)
        if not d:
            sys.exit(0)
        buf += d
def send(typ, p):
    c.sendall(struct.pack('>IHHI', 0x50524159, ver, typ, len(p)) + p)
typ, p = frame()
assert typ == 1, typ
ver = struct.unpack('>I', p[:4])[0]  # the master's protocol version: spoken back
mnonce = p[12:44]
blen = struct.unpack('>I', p[44:48])[0]
build = p[48:48 + blen]
wnonce = os.urandom(32)
send(1, struct.pack('>IBBHI', ver, 2, 1, 1, 0) + wnonce + struct.pack('>I', len(build)) + build)
typ, p = frame()
assert typ == 2, typ
while not os.path.getsize(pid_file):
    time.sleep(0.01)
pid = int(open(pid_file).read())
os.kill(pid, signal.SIGSTOP)
time.sleep(1.5)
send(2, hmac.new(secret, b'portray-auth-v1' + bytes([2]) + mnonce + wnonce, hashlib.sha256).digest())
time.sleep(0.2)
os.kill(pid, signal.SIGCONT)
sys.stderr.write('late AUTH sent\n')
while True:
    frame()
PY
: >"$T/master.pid"
python3 "$T/late.py" "$T/fake.port" "$T/secret" "$T/master.pid" 2>"$T/fake.log" &
PIDS="$PIDS $!"
wait_port fake $!
"$BIN/portray-master" "$SCENE" -o "$T/x.ppm" --no-local -q --heartbeat-timeout 1 --secret-file "$T/secret" \
	-w "127.0.0.1:$fake_PORT" 2>"$T/m.log" &
mpid=$!
PIDS="$PIDS $mpid"
echo "$mpid" >"$T/master.pid"
i=0
while kill -0 "$mpid" 2>/dev/null; do
	i=$((i + 1))
	[ $i -gt 300 ] && fail "the master still waits 15 s on a worker that never answers its OFFER"
	sleep 0.05
done
wait "$mpid"
rc=$?
grep -q "late AUTH sent" "$T/fake.log" || fail "the fake never sent its late AUTH"
[ $rc -eq 69 ] || fail "exit $rc, expected 69"
grep -q "dropped" "$T/m.log" || fail "the master did not say it dropped the worker"
echo "ok: $(grep -m 1 dropped "$T/m.log")"
