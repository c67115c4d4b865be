#!/bin/sh
# bench/latency.sh - the farm over a slow link (make bench): master + 2
# workers (-j 1 each, --no-local, --audit 0), balls_s4 at 1280x960, tiles of
# 16, 32 and 64 pixels, each worker reached through its own delay proxy
# (tests/tools/delayproxy.c, $BUILD/tools/delayproxy) at 0, 2 and 20 ms one
# way. Reported per tile size, best of 3, the runs interleaved:
#   - the farm at 0 ms against a local -j 2 render (local/farm: 1.00 = as
#     fast as rendering here; the proxy's own cost is in it);
#   - the farm at 2 and 20 ms against the same farm at 0 ms (t0/td: 1.00 =
#     the latency costs nothing; the master sizes each worker's window of
#     tiles in flight from its round trip and tile rate to hide it; targets:
#     >= 0.9 at 2 ms with the default tile size, >= 0.8 at 20 ms);
#   - whether every image is byte-identical to the local render.
# Processes on 127.0.0.1 with OS-chosen ports, all killed on exit.
BIN=${BIN:-bin}
BUILD=${BUILD:-build}
PROXY=${PROXY:-$BUILD/tools/delayproxy}
SCENE=${SCENE:-tests/data/spd/balls_s4.sce}
SIZE=${SIZE:-1280x960}
TILES=${TILES:-16 32 64}
DELAYS="0 2 20"
ROUNDS=${ROUNDS:-3}
[ -x "$PROXY" ] || { echo "latency: $PROXY not built (make bench builds it)"; exit 1; }
T=$(mktemp -d "${TMPDIR:-/tmp}/portray-bench.XXXXXX")
PIDS=""
trap 'for p in $PIDS; do kill $p 2>/dev/null; done; wait 2>/dev/null; [ -n "${KEEP:-}" ] || rm -rf "$T"' EXIT
now() { date +%s.%N; }
# wait_port NAME PID: waits for $T/NAME.port, sets NAME_PORT
wait_port() {
	i=0
	while [ ! -s "$T/$1.port" ]; do
		i=$((i + 1))
		if [ $i -gt 200 ] || ! kill -0 "$2" 2>/dev/null; then
			echo "latency: $1 did not start"
			exit 1
		fi
		sleep 0.05
	done
	eval "${1}_PORT=$(cat "$T/$1.port")"
}
for w in a b; do
	"$BIN/portray-worker" --listen 127.0.0.1:0 --port-file "$T/$w.port" -j 1 2>"$T/$w.log" &
	PIDS="$PIDS $!"
	wait_port "$w" $!
done
# one proxy per worker and delay: wa0 wb0 wa2 wb2 wa20 wb20; W0 W2 W20 the -w lists
for d in $DELAYS; do
	list=""
	for w in a b; do
		eval "wp=\$${w}_PORT"
		"$PROXY" --listen 127.0.0.1:0 --port-file "$T/p$w$d.port" --to "127.0.0.1:$wp" --delay-ms "$d" -q \
			2>"$T/p$w$d.log" &
		PIDS="$PIDS $!"
		wait_port "p$w$d" $!
		eval "list=\"\$list\${list:+,}127.0.0.1:\$p$w${d}_PORT\""
	done
	eval "W$d=$list"
done
# the workers cache the scene at this size (every later job is a cache hit)
"$BIN/portray-master" "$SCENE" --size "$SIZE" -o "$T/warm.ppm" -w "$W0" --no-local --audit 0 -q || exit 1

# run OUT SECONDS-FILE [master options]: one render, its time kept if it is the best yet
run() {
	out=$1
	best=$2
	shift 2
	t0=$(now)
	"$BIN/portray-master" "$SCENE" --size "$SIZE" -o "$out" -q "$@" 2>>"$T/master.log" || {
		echo "latency: render failed: $*"
		exit 1
	}
	t1=$(now)
	awk -v a="$t0" -v b="$t1" -v f="$best" 'BEGIN {
		d = b - a; m = 1e9; if ((getline l < f) > 0) m = l + 0
		print (d < m ? d : m) > f }'
}

echo "farm over a slow link: $(basename "$SCENE" .sce) at $SIZE, master + 2 workers (-j 1, --no-local, --audit 0),"
echo "each worker through its own delay proxy; best of $ROUNDS, interleaved; t0/td: 1.00 = no slowdown"
printf '%-5s %-12s %-24s %-20s %-20s %s\n' tile "local -j 2" "farm 0 ms (local/farm)" "2 ms (t0/t2)" "20 ms (t0/t20)" images
for tile in $TILES; do
	rm -f "$T"/*.best
	for r in $(seq "$ROUNDS"); do
		run "$T/local.ppm" "$T/local.best" -j 2 --tile "$tile"
		for d in $DELAYS; do
			eval "list=\$W$d"
			run "$T/farm$d.ppm" "$T/farm$d.best" -w "$list" --no-local --audit 0 --tile "$tile"
			cmp -s "$T/local.ppm" "$T/farm$d.ppm" || echo "$d ms, round $r" >>"$T/differ.$tile"
		done
	done
	same="identical"
	[ -f "$T/differ.$tile" ] && same="DIFFER ($(tr '\n' ' ' <"$T/differ.$tile"))"
	awk -v tile="$tile" -v l="$(cat "$T/local.best")" -v f0="$(cat "$T/farm0.best")" \
		-v f2="$(cat "$T/farm2.best")" -v f20="$(cat "$T/farm20.best")" -v same="$same" 'BEGIN {
		printf "%-5s %-12s %-24s %-20s %-20s %s\n", tile, sprintf("%.2f s", l), sprintf("%.2f s (%.2f)", f0, l / f0),
		       sprintf("%.2f s (%.2f)", f2, f0 / f2), sprintf("%.2f s (%.2f)", f20, f0 / f20), same }'
done
echo "(images: every farm render compared with the local render of the same round, byte for byte)"
