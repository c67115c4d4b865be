#!/bin/sh
# One worker serves two masters at once and interleaves their tiles fairly:
# both jobs run side by side (neither waits for the other to finish) and
# both images are identical to the local render.
. "$(dirname "$0")/farm_lib.inc"
start_worker a -j 1 --test-delay-ms 20
local_render "$SCENE" "$T/local.ppm" --size 192x144
for m in 1 2; do
	"$BIN/portray-master" "$SCENE" -o "$T/f$m.ppm" --size 192x144 --tile 16 --no-local \
		-w "127.0.0.1:$a_PORT" 2>"$T/m$m.log" &
	eval "M$m=\$!"
	PIDS="$PIDS $!"
done
wait "$M1" || fail "master 1 failed"
wait "$M2" || fail "master 2 failed"
cmp "$T/local.ppm" "$T/f1.ppm" || fail "image 1 differs"
cmp "$T/local.ppm" "$T/f2.ppm" || fail "image 2 differs"
wait_count "$T/a.log" ' job .* 108 tiles in ' 2 "two jobs of 108 tiles"
[ "$(grep -c ' job .* 108 tiles in ' "$T/a.log")" -eq 2 ] || fail "expected two jobs of 108 tiles"
# fair interleaving: each job took most of the total time, not half of it
# (20 ms per tile: a master starting late on a loaded machine is a small skew)
awk '/ job / { for (i = 1; i <= NF; i++) if ($i == "in") t[++n] = $(i + 1) }
     END { if (n != 2) exit 1; lo = t[1] < t[2] ? t[1] : t[2]; hi = t[1] < t[2] ? t[2] : t[1];
	   printf "job times %.2f s and %.2f s\n", lo, hi; exit !(lo > 0.7 * hi) }' "$T/a.log" ||
	fail "jobs were not interleaved fairly"
echo ok
