#!/bin/sh
# bench/povray.sh - our trace time against POV-Ray 3.7's on the SPD scenes'
# POV-Ray twins ($PORTRAY_SHARED/spd/pov/NAME.twin.pov), same size and thread
# count, without anti-aliasing (ours: filter standard) and with it (ours:
# filter adaptive threshold 0.3 max-depth 1, POV-Ray: +A0.3; both then trace
# at most a 3x3 grid per pixel, POV-Ray's default +R3; AA_DEPTH=3 for the
# manual's default depth, up to 9x9). Times compared are each
# program's own trace time (POV-Ray's "Trace Time", our summary's "trace"), so
# POV-Ray's start-up and both parsers are left out. ratio = ours / POV-Ray's
# (below 1: we are faster). POV-Ray is only measured here; nothing needs it.
SHARED=${PORTRAY_SHARED:-../shared/data}
MASTER=${MASTER:-bin/portray-master}
SIZE_W=${POV_W:-640}
SIZE_H=${POV_H:-480}
if ! command -v povray >/dev/null 2>&1; then
	echo "povray not installed: skipped"
	exit 0
fi
POVDIR=$(cd "$SHARED/spd/pov" 2>/dev/null && pwd)
[ -n "$POVDIR" ] || POVDIR=/work/shared/data/spd/pov
if [ ! -d "$POVDIR" ]; then
	echo "no POV-Ray twins found ($SHARED/spd/pov): skipped"
	exit 0
fi
TMP=$(mktemp -d "${TMPDIR:-/tmp}/portray-pov.XXXXXX")
trap 'rm -rf "$TMP"' EXIT

# pov_time POVFILE THREADS AA: POV-Ray's trace seconds
pov_time() {
	aa=-A
	[ "$3" = aa ] && aa=+A0.3
	(cd "$TMP" && povray "+I$1" "+O$TMP/pov.png" +FN "+W$SIZE_W" "+H$SIZE_H" -D "$aa" "+WT$2" 2>&1) |
		sed -n 's/.*Trace Time:.*(\([0-9.]*\) seconds).*/\1/p' | head -n 1
}
# our_time SCENE THREADS: our trace seconds from the summary line
our_time() {
	"$MASTER" "$1" -o "$TMP/ours.png" -j "$2" --size "${SIZE_W}x${SIZE_H}" 2>&1 |
		sed -n 's/.*(parse [0-9.]*, build [0-9.]*, trace \([0-9.]*\)).*/\1/p'
}

echo "# ${SIZE_W}x${SIZE_H}; seconds of trace time; ratio = portray / POV-Ray"
for pov in "$POVDIR"/*.twin.pov; do
	name=$(basename "$pov" .twin.pov)
	sce=tests/data/spd/$name.sce
	[ -f "$sce" ] || sce=$SHARED/spd/$name.sce
	[ -f "$sce" ] || continue
	sed "s/filter standard/filter adaptive threshold 0.3 max-depth ${AA_DEPTH:-1}/" "$sce" >"$TMP/$name.aa.sce"
	for threads in 1 2; do
		for mode in plain aa; do
			if [ "$mode" = aa ]; then s=$TMP/$name.aa.sce; else s=$sce; fi
			p=$(pov_time "$pov" "$threads" "$mode")
			o=$(our_time "$s" "$threads")
			if [ -z "$p" ] || [ -z "$o" ]; then
				echo "$name -j$threads $mode: measurement failed (povray '$p', ours '$o')"
				continue
			fi
			ratio=$(awk -v o="$o" -v p="$p" 'BEGIN { if (p > 0) printf "%.2f", o / p; else print "inf" }')
			printf '%-9s threads %d %-5s portray %7.3f s  povray %7.3f s  ratio %s\n' \
				"$name" "$threads" "$mode" "$o" "$p" "$ratio"
		done
	done
done
