#!/bin/sh
# Workers that dial in (portray-worker --connect, portray-master --accept),
# as systemd, Slurm or Kubernetes start them:
#  1. one worker started before the master (it retries until the master is
#     there), one after it started: both join, the image is the local one;
#  2. a worker dialling in with the wrong secret is refused, the render goes on;
#  3. a worker killed mid-render is replaced by one that dials in later;
#  4. one worker serves three jobs in a row (a long-lived pool);
#  5. --accept beyond loopback without a secret is refused at once.
. "$(dirname "$0")/farm_lib.inc"
printf 'dial-in test secret\n' >"$T/secret"
printf 'another secret\n' >"$T/wrong"
chmod 600 "$T/secret" "$T/wrong"
local_render "$SLOW" "$T/local.ppm" --size 192x144

# 1. before and after
P=$(free_port)
start_dialer early "127.0.0.1:$P" -j 1 --test-delay-ms 20 --secret-file "$T/secret"
sleep 0.7 # it has found no master at least once
"$BIN/portray-master" "$SLOW" --size 192x144 --tile 16 -o "$T/f1.ppm" --no-local --accept "127.0.0.1:$P" \
	--port-file "$T/m1.port" --secret-file "$T/secret" 2>"$T/m1.log" &
M=$!
PIDS="$PIDS $M"
wait_for "$T/m1.port" "$P" "the master to accept on port $P"
wait_for "$T/early.log" "job .*: started" "the early worker to start its job"
start_dialer late "127.0.0.1:$P" -j 1 --test-delay-ms 20 --secret-file "$T/secret"
# 2. the wrong secret, meanwhile
start_dialer liar "127.0.0.1:$P" -j 1 --secret-file "$T/wrong"
wait $M || fail "render with workers dialling in failed (exit $?)"
cmp "$T/local.ppm" "$T/f1.ppm" || fail "image differs with workers dialling in"
grep -q "trying again" "$T/early.log" || fail "the early worker did not wait for the master"
[ "$(grep -c "dialled in" "$T/m1.log")" -ge 3 ] || fail "the master did not log three workers dialling in"
n_early=$(sed -n 's/.*job .*: \([0-9]*\) tiles in.*/\1/p' "$T/early.log" | head -n 1)
wait_for "$T/late.log" "tiles in" "the late worker to log its job"
n_late=$(sed -n 's/.*job .*: \([0-9]*\) tiles in.*/\1/p' "$T/late.log" | head -n 1)
[ "${n_early:-0}" -gt 0 ] && [ "${n_late:-0}" -gt 0 ] || fail "both workers should have traced tiles ($n_early, $n_late)"
grep -q "authentication failed" "$T/m1.log" || fail "the master did not refuse the wrong secret"
wait_for "$T/liar.log" "authentication failed" "the liar to be told why"
echo "ok   early worker $n_early tiles, late worker $n_late tiles, wrong secret refused"
kill "$liar_PID" "$early_PID" "$late_PID" 2>/dev/null

# 3. a worker killed mid-render, replaced by one that dials in later
P=$(free_port)
start_dialer doomed "127.0.0.1:$P" -j 1 --test-delay-ms 30
"$BIN/portray-master" "$SLOW" --size 192x144 --tile 16 -o "$T/f3.ppm" --no-local --accept "127.0.0.1:$P" \
	2>"$T/m3.log" &
M=$!
PIDS="$PIDS $M"
wait_for "$T/doomed.log" "job .*: started" "the doomed worker to start"
sleep 0.3
kill -KILL "$doomed_PID"
wait_for "$T/m3.log" "gone" "the master to notice the killed worker"
kill -0 "$M" 2>/dev/null || fail "the master ended without workers (it should wait for more to dial in)"
start_dialer fresh "127.0.0.1:$P" -j 1
wait $M || fail "render after a worker was replaced failed (exit $?)"
cmp "$T/local.ppm" "$T/f3.ppm" || fail "image differs after a worker was replaced"
echo "ok   killed worker replaced by one dialling in later"
kill "$fresh_PID" 2>/dev/null

# 4. a pool: one worker, three jobs in a row
P=$(free_port)
start_dialer pool "127.0.0.1:$P" -j 1
for k in 1 2 3; do
	timeout 60 "$BIN/portray-master" "$SLOW" --size 192x144 --tile 16 -o "$T/p$k.ppm" --no-local \
		--accept "127.0.0.1:$P" 2>"$T/mp$k.log" || fail "pool job $k failed (exit $?)"
	cmp "$T/local.ppm" "$T/p$k.ppm" || fail "pool job $k: image differs"
done
wait_count "$T/pool.log" "tiles in .*done" 3 "the pool worker to log three jobs"
echo "ok   one worker served three jobs in a row"

# 5. beyond loopback without a secret: refused before anything else
"$BIN/portray-master" "$SCENE" -o "$T/x.ppm" --accept 0.0.0.0:0 2>"$T/m5.log"
[ $? -eq 64 ] || fail "--accept 0.0.0.0 without a secret: exit $?, expected 64"
grep -q "without --secret-file" "$T/m5.log" || fail "no reason given for refusing --accept"
echo ok
