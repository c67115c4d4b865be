#!/bin/sh
# A worker that returns wrong pixels with a valid checksum (--test-fault lie:
# one pixel's low bit flipped on its 2nd, 6th, 10th ... tile, never the first)
# is caught by the master's audits, dropped, and every tile it delivered is
# rendered again: the image is identical to the local render. Without audits
# (--audit 0) the same lie reaches the image: the fault is real.
. "$(dirname "$0")/farm_lib.inc"
# 20 ms per tile: 108 tiles last > 1 s, so the liar takes part whatever the load
start_worker good -j 1 --test-delay-ms 20
start_worker liar -j 1 --test-delay-ms 20 --test-fault lie
local_render "$SCENE" "$T/local.ppm" --size 96x72
W="127.0.0.1:$good_PORT,127.0.0.1:$liar_PORT"

# --no-local: audits run on one local thread that takes no ordinary tile
timeout 120 "$BIN/portray-master" "$SCENE" -o "$T/farm.ppm" --size 96x72 --tile 8 --no-local -w "$W" 2>"$T/m1.log" ||
	fail "farm render with a lying worker failed (exit $?)"
cmp "$T/local.ppm" "$T/farm.ppm" || fail "image differs with a lying worker"
# the lie is on its second tile: within the probation, where every tile is audited
grep -q "worker 127.0.0.1:$liar_PORT returned wrong pixels for tile [0-9]* (audit): dropped; its [0-9]* tiles re-rendered" \
	"$T/m1.log" || fail "the lying worker was not reported"
grep -q " [1-9][0-9]* audits (1 failed)" "$T/m1.log" || fail "summary does not count the failed audit"
grep -q "^portray-master:   127.0.0.1:$liar_PORT  *0 tiles" "$T/m1.log" || fail "the liar's tiles were counted"
wait_for "$T/liar.log" "peer says: wrong pixels for tile [0-9]* (audit)" "the lying worker to be told"

# local threads as well (-j 1) against a liar as fast as they are (no delay,
# 16 samples per pixel): audits go first, the liar is caught, the image exact
start_worker liar2 -j 1 --test-fault lie
local_render "$SLOW" "$T/local_slow.ppm" --size 96x72
timeout 120 "$BIN/portray-master" "$SLOW" -o "$T/farm2.ppm" --size 96x72 --tile 8 -j 1 -w "127.0.0.1:$liar2_PORT" \
	2>"$T/m2.log" || fail "render with local threads and a lying worker failed (exit $?)"
cmp "$T/local_slow.ppm" "$T/farm2.ppm" || fail "image differs with local threads and a lying worker"
grep -q "worker 127.0.0.1:$liar2_PORT returned wrong pixels" "$T/m2.log" ||
	fail "the liar beside local threads was not caught"

# --audit 0: no audits, the honest worker alone keeps the image exact only if
# the liar delivered fewer than two tiles; it delivers many (its summary line)
timeout 120 "$BIN/portray-master" "$SCENE" -o "$T/farm0.ppm" --size 96x72 --tile 8 --no-local --audit 0 -w "$W" \
	2>"$T/m0.log" || fail "render with --audit 0 failed (exit $?)"
grep -q " 0 audits (0 failed)" "$T/m0.log" || fail "--audit 0 still audited"
n=$(sed -n "s/^portray-master:   127.0.0.1:$liar_PORT  *\([0-9]*\) tiles.*/\1/p" "$T/m0.log")
if [ "${n:-0}" -ge 2 ]; then
	cmp -s "$T/local.ppm" "$T/farm0.ppm" && fail "the lie did not reach the unaudited image: the fault is not exercised"
fi

# the sample: --audit 1 audits every tile, --audit 0.5 about half of them
# (4 + 0.5 x 104 expected, standard deviation 5: 30..90 fails one run in 10^6)
start_worker fast -j 1
timeout 120 "$BIN/portray-master" "$SCENE" -o "$T/a1.ppm" --size 96x72 --tile 8 --no-local --audit 1 \
	-w "127.0.0.1:$fast_PORT" 2>"$T/a1.log" || fail "render with --audit 1 failed (exit $?)"
cmp "$T/local.ppm" "$T/a1.ppm" || fail "image differs with --audit 1"
grep -q " 108 audits (0 failed)" "$T/a1.log" || fail "--audit 1 did not audit each of the 108 tiles"
timeout 120 "$BIN/portray-master" "$SCENE" -o "$T/a5.ppm" --size 96x72 --tile 8 --no-local --audit 0.5 \
	-w "127.0.0.1:$fast_PORT" 2>"$T/a5.log" || fail "render with --audit 0.5 failed (exit $?)"
n=$(sed -n 's/.* \([0-9]*\) audits (0 failed).*/\1/p' "$T/a5.log")
[ "${n:-0}" -ge 30 ] && [ "$n" -le 90 ] || fail "--audit 0.5 audited ${n:-no} tiles of 108"

"$BIN/portray-master" "$SCENE" --audit 1.5 -w "127.0.0.1:$good_PORT" -o "$T/x.ppm" 2>"$T/u.log"
[ $? -eq 64 ] || fail "--audit 1.5 was accepted"
grep -q "audit wants a fraction 0..1" "$T/u.log" || fail "no message for a bad --audit"
echo ok
