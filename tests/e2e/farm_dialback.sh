#!/bin/sh
# farm_dialback.sh - a worker that dials a master which refuses it (another
# secret) must back off as dial.c promises (0.5 s doubling to 10 s), not
# redial every 0.5 s for ever with three log lines a time on each side:
# the connection ends before any job, which is no reason to reset the
# back-off. In 6 s the back-off allows attempts at 0, 0.5, 1.5, 3.5 s: 4
# (5 tolerated); without it there are about 12.
. "$(dirname "$0")/farm_lib.inc"
printf 'the master secret\n' >"$T/secret"
printf 'another secret\n' >"$T/wrong"
chmod 600 "$T/secret" "$T/wrong"
# a master that waits for workers for ever (--no-local), until we stop it
"$BIN/portray-master" "$SCENE" -o "$T/x.ppm" --no-local -q --accept 127.0.0.1:0 --port-file "$T/m.port" \
	--secret-file "$T/secret" 2>"$T/m.log" &
mpid=$!
PIDS="$PIDS $mpid"
wait_port m "$mpid"
start_dialer liar "127.0.0.1:$m_PORT" -j 1 --secret-file "$T/wrong"
sleep 6
kill -INT "$mpid"
n=$(grep -c "connected to master" "$T/liar.log")
grep -q "authentication failed" "$T/liar.log" || fail "the worker was not refused for its secret"
[ "$n" -le 5 ] || fail "$n attempts in 6 s against a master that refuses: no back-off"
echo "ok: $n attempts in 6 s"
