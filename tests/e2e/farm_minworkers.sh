#!/bin/sh
# --min-workers and farm faults under -q:
#   workers that are all refused (a wrong secret, nobody listening) with
#   --min-workers 1 and -q: exit 75, the refusals and the reason printed all
#   the same, no image written;
#   more workers asked for than named: exit 75 at once;
#   --accept with nobody dialling in: exit 75 after --join-timeout;
#   --accept and a worker dialling in a second late: it joins, the local
#   threads start then, the image is the local one;
#   enough workers: the render succeeds, the same bytes as a local render,
#   and its piped progress lines name the workers;
#   --min-workers without workers: usage error (64);
#   -q with a refused worker and no --min-workers: the refusal is printed,
#   the render completes locally.
. "$(dirname "$0")/farm_lib.inc"
printf 'correct horse battery staple\n' >"$T/secret"
printf 'something else\n' >"$T/wrong"
chmod 600 "$T/secret" "$T/wrong"
start_worker s -j 1 --secret-file "$T/secret"
start_worker a -j 1
start_worker b -j 1
DEAD=$(free_port)

# all refused: a wrong secret and a port nobody listens on
t0=$(now)
"$BIN/portray-master" "$SCENE" -o "$T/x.ppm" -q --min-workers 1 --secret-file "$T/wrong" \
	-w "127.0.0.1:$s_PORT,127.0.0.1:$DEAD" 2>"$T/m1.log"
rc=$?
[ $rc -eq 75 ] || fail "all refused, --min-workers 1: exit $rc, want 75"
within 20 "$t0" || fail "all refused: took $(elapsed "$t0") s to give up"
grep -q "worker 127.0.0.1:$s_PORT dropped: .*authentication failed" "$T/m1.log" || fail "-q hid the refusal"
grep -q "worker 127.0.0.1:$DEAD dropped: connect" "$T/m1.log" || fail "-q hid the unreachable worker"
grep -q -- "--min-workers 1: only 0 workers joined (every worker named failed); no image written" "$T/m1.log" ||
	fail "no reason given for exit 75"
[ -e "$T/x.ppm" ] && fail "an image was written after too few workers joined"

# with --no-local too: --min-workers' verdict (75), not "every worker lost" (69)
"$BIN/portray-master" "$SCENE" -o "$T/x.ppm" -q --no-local --min-workers 1 -w "127.0.0.1:$DEAD" 2>"$T/m9.log"
rc=$?
[ $rc -eq 75 ] || fail "--no-local --min-workers 1, nobody: exit $rc, want 75"

# more asked for than named (two addresses): at once
t0=$(now)
"$BIN/portray-master" "$SCENE" -o "$T/x.ppm" --min-workers 3 -w "127.0.0.1:$a_PORT,127.0.0.1:$b_PORT" \
	2>"$T/m2.log"
rc=$?
[ $rc -eq 75 ] || fail "--min-workers 3 of 2 named: exit $rc, want 75"
within 5 "$t0" || fail "--min-workers 3 of 2 named: not at once"
grep -q -- "--min-workers 3: only 2 workers named" "$T/m2.log" || fail "no reason for 3 of 2"

# one joins, the other never can: 75 once the dead one is dropped
"$BIN/portray-master" "$SCENE" -o "$T/x.ppm" --min-workers 2 -w "127.0.0.1:$a_PORT,127.0.0.1:$DEAD" \
	2>"$T/m3.log"
rc=$?
[ $rc -eq 75 ] || fail "one of two joins: exit $rc, want 75"
grep -q -- "--min-workers 2: only 1 worker joined (the other workers named failed)" "$T/m3.log" ||
	fail "no reason for 1 of 2"

# --accept and nobody dials in: the join timeout
t0=$(now)
"$BIN/portray-master" "$SCENE" -o "$T/x.ppm" -q --min-workers 1 --join-timeout 1 --accept 127.0.0.1:0 \
	2>"$T/m4.log"
rc=$?
[ $rc -eq 75 ] || fail "--accept, nobody: exit $rc, want 75"
within 10 "$t0" || fail "--join-timeout 1 took $(elapsed "$t0") s"
grep -q -- "--join-timeout passed" "$T/m4.log" || fail "no reason for the timeout"

# --accept: a worker dials in late, the render waits for it
P=$(free_port)
"$BIN/portray-master" "$SCENE" -o "$T/acc.ppm" --min-workers 1 --join-timeout 60 --accept "127.0.0.1:$P" \
	--progress-interval 0 2>"$T/m8.log" &
M=$!
PIDS="$PIDS $M"
sleep 1
kill -0 $M 2>/dev/null || fail "the master did not wait for a worker to dial in"
start_dialer late "127.0.0.1:$P" -j 1
wait $M || fail "--min-workers 1 with a worker dialling in failed (exit $?)"
local_render "$SCENE" "$T/local_acc.ppm"
cmp "$T/local_acc.ppm" "$T/acc.ppm" || fail "image differs with a worker dialling in"
grep -q "1 worker joined (--min-workers 1): the local threads start" "$T/m8.log" || fail "no word of the join"

# enough workers: success, the same bytes; piped progress lines name them
local_render "$SLOW" "$T/local.ppm" --size 320x240
"$BIN/portray-master" "$SLOW" -o "$T/ok.ppm" --size 320x240 -j 1 --min-workers 2 --progress-interval 0.1 \
	-w "127.0.0.1:$a_PORT,127.0.0.1:$b_PORT" 2>"$T/m5.log" || fail "--min-workers 2 with two workers failed"
cmp "$T/local.ppm" "$T/ok.ppm" || fail "--min-workers render differs from the local one"
grep -q "2 workers joined (--min-workers 2): the local threads start" "$T/m5.log" || fail "no word of the join"
grep -q "^portray-master: progress .*ETA.*| local [0-9.]* t/s | 127.0.0.1:$a_PORT [0-9.]* t/s | 127.0.0.1:$b_PORT" \
	"$T/m5.log" || fail "no progress line naming both workers"

# --min-workers without workers
"$BIN/portray-master" "$SCENE" -o "$T/x.ppm" --min-workers 1 2>"$T/m6.log"
[ $? -eq 64 ] || fail "--min-workers without workers: not a usage error"

# -q quiets progress, not faults: a refused worker is said, the render completes locally
# (a render long enough for the refusal to arrive before it ends)
"$BIN/portray-master" "$SLOW" -o "$T/q.ppm" -q -j 1 --size 320x240 --secret-file "$T/wrong" -w "127.0.0.1:$s_PORT" \
	2>"$T/m7.log" || fail "-q render with a refused worker failed"
grep -q "worker 127.0.0.1:$s_PORT dropped: .*authentication failed" "$T/m7.log" || fail "-q hid a refusal"
[ "$(wc -l <"$T/m7.log")" -le 3 ] || fail "-q printed more than the fault: $(cat "$T/m7.log")"
cmp "$T/local.ppm" "$T/q.ppm" || fail "local fallback differs"
echo ok
