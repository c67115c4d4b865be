#!/bin/sh
# bench/farm.sh - the farm's figures (make bench):
#  1. parallel efficiency: master + 2 workers (-j 1 each, --no-local) against
#     a local -j 2 render of balls_s4 at 1280x960 (target >= 90%);
#  2. master overhead: 1x1 tiles through 64 simulated workers (64 connections
#     to a worker that answers every tile at once with black pixels): tiles/s;
#  3. bytes on the wire per job (scene, tiles; a cache hit moves no scene).
# Processes on 127.0.0.1 with OS-chosen ports, all killed on exit.
BIN=${BIN:-bin}
SCENE=${SCENE:-tests/data/spd/balls_s4.sce}
SIZE=${SIZE:-1280x960}
T=$(mktemp -d "${TMPDIR:-/tmp}/portray-bench.XXXXXX")
PIDS=""
trap 'for p in $PIDS; do kill $p 2>/dev/null; done; wait 2>/dev/null; [ -n "${KEEP:-}" ] || rm -rf "$T"' EXIT
now() { date +%s.%N; }
start_worker() { # name, options: sets NAME_PORT
	n=$1
	shift
	"$BIN/portray-worker" --listen 127.0.0.1:0 --port-file "$T/$n.port" "$@" >/dev/null 2>"$T/$n.log" &
	pid=$!
	PIDS="$PIDS $pid"
	i=0
	while [ ! -s "$T/$n.port" ] && [ $i -lt 100 ]; do
		sleep 0.05
		i=$((i + 1))
	done
	eval "${n}_PORT=$(cat "$T/$n.port")"
	eval "${n}_PID=$pid"
}

start_worker a -j 1
start_worker b -j 1
P1=$a_PORT
P2=$b_PORT
W=127.0.0.1:$P1,127.0.0.1:$P2
# warm the workers' caches and the page cache, so both runs compare tracing
"$BIN/portray-master" "$SCENE" --size 64x48 -o "$T/warm.ppm" -w "$W" --no-local -q || exit 1

# best of 3 each, alternating, to damp the noise of a shared machine.
# Twice: without audits (the scheduler's own efficiency: on a LAN the master's
# audit thread runs on the master's machine, not the workers'), and with the
# default audits, which here share the same 2 cores with the workers.
efficiency() { # label, extra master options
	label=$1
	shift
	tl=999
	tf=999
	for i in 1 2 3; do
		t0=$(now)
		"$BIN/portray-master" "$SCENE" --size "$SIZE" -o "$T/local.ppm" -j 2 -q || exit 1
		t1=$(now)
		"$BIN/portray-master" "$SCENE" --size "$SIZE" -o "$T/farm.ppm" -w "$W" --no-local "$@" 2>"$T/farm.log" || exit 1
		t2=$(now)
		tl=$(awk -v a="$t0" -v b="$t1" -v m="$tl" 'BEGIN { d = b - a; print (d < m ? d : m) }')
		tf=$(awk -v a="$t1" -v b="$t2" -v m="$tf" 'BEGIN { d = b - a; print (d < m ? d : m) }')
	done
	same=differs
	cmp -s "$T/local.ppm" "$T/farm.ppm" && same=identical
	awk -v tl="$tl" -v tf="$tf" -v s="$SIZE" -v same="$same" -v label="$label" 'BEGIN {
		printf "farm efficiency (%s): %s at %s, best of 3: local -j 2 %.2f s, master + 2 workers (-j 1, --no-local) %.2f s: %.0f%% (target >= 90%%), image %s\n",
		       label, "balls_s4", s, tl, tf, 100 * tl / tf, same }'
}
efficiency "no audits" --audit 0
efficiency "default audits, on the same 2 cores"
# the same comparison in CPU seconds, which a loaded machine does not skew:
# the local render's CPU against the two workers' (from /proc)
# (times must run in this shell, not in a $(...) subshell)
child_cpu() { awk 'NR == 2 { split($1, u, /[ms]/); split($2, s, /[ms]/); print u[1] * 60 + u[2] + s[1] * 60 + s[2] }' "$T/times"; }
proc_cpu() { awk -v hz="$(getconf CLK_TCK)" '{ print ($14 + $15) / hz }' "/proc/$1/stat" 2>/dev/null || echo 0; }
if [ -r "/proc/$a_PID/stat" ]; then
	times >"$T/times"
	c0=$(child_cpu)
	"$BIN/portray-master" "$SCENE" --size "$SIZE" -o "$T/local.ppm" -j 2 -q || exit 1
	times >"$T/times"
	c1=$(child_cpu)
	a0=$(proc_cpu "$a_PID")
	b0=$(proc_cpu "$b_PID")
	"$BIN/portray-master" "$SCENE" --size "$SIZE" -o "$T/farm.ppm" -w "$W" --no-local -q || exit 1
	awk -v c0="$c0" -v c1="$c1" -v a0="$a0" -v a1="$(proc_cpu "$a_PID")" -v b0="$b0" -v b1="$(proc_cpu "$b_PID")" 'BEGIN {
		l = c1 - c0; w = (a1 - a0) + (b1 - b0);
		printf "  CPU: local render %.2f s (parse, build, trace), workers %.2f s: %.0f%%\n", l, w, (w > 0 ? 100 * l / w : 0) }'
fi
grep "farm: bytes sent" "$T/farm.log" | sed 's/^portray-master: /  /'
awk '/received/ { for (i = 1; i <= NF; i++) if ($i == "received") r += $(i + 1) } END { printf "  bytes received (tile results) %d\n", r }' "$T/farm.log"

# master overhead: NSIM connections to a black-tile worker, 1x1 tiles (no
# audits: black tiles would fail them)
NSIM=${NSIM:-64}
start_worker black -j 1 --test-fault black
PB=$black_PORT
L=""
for i in $(seq "$NSIM"); do L="$L${L:+,}127.0.0.1:$PB"; done
OS=${OVERHEAD_SIZE:-320x240}
t0=$(now)
"$BIN/portray-master" "$SCENE" --size "$OS" --tile 1 -o "$T/black.ppm" -w "$L" --no-local --audit 0 2>"$T/m_black.log" || exit 1
t1=$(now)
awk -v a="$t0" -v b="$t1" -v s="$OS" -v k="$NSIM" 'BEGIN {
	split(s, d, "x"); n = d[1] * d[2];
	printf "master overhead: %d 1x1 tiles through %d simulated workers in %.2f s: %.0f tiles/s (including %d handshakes and scene offers)\n", n, k, b - a, n / (b - a), k }'
grep "farm: bytes sent" "$T/m_black.log" | sed 's/^portray-master: /  /'

# bytes per job, scene cached: a second job
"$BIN/portray-master" "$SCENE" --size 320x240 -o "$T/c.ppm" -w "127.0.0.1:$P1" --no-local 2>"$T/c.log" || exit 1
printf 'bytes per job at 320x240 on one worker with the scene cached: '
sed -n 's/.*sent \([0-9]*\) B (scene \([0-9]*\) B, cache \([a-z]*\)).*received \([0-9]*\) B.*/sent \1 (scene \2, cache \3), received \4/p' "$T/c.log"
