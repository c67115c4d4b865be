#!/bin/sh
# render_progress.sh - progress off and on a terminal:
#   stderr a pipe: a progress line every --progress-interval seconds and a
#   last one at 100%, no escape codes; none with -q, with
#   --progress-interval 0, or for a render shorter than the interval;
#   stderr a terminal (a pty from script(1), skipped without it): at 50
#   columns every redraw of the bar fits in 49 characters, for a local
#   render and for a farm line with six workers; after the terminal grows
#   to 100 columns the bar uses the room (the width is read at each redraw).
. "$(dirname "$0")/render_lib.inc"

slow_scene "$TMP/slow.sce" 240
# about 1.5 s on one thread
"$MASTER" -j1 --tile 16 -o "$TMP/p.ppm" --progress-interval 0.2 "$TMP/slow.sce" 2>"$TMP/p.log" ||
	fail "piped render failed"
n=$(grep -c '^portray-master: progress ' "$TMP/p.log")
[ "$n" -ge 3 ] || { cat "$TMP/p.log"; fail "$n progress lines, want at least 3"; }
grep '^portray-master: progress ' "$TMP/p.log" | tail -n 1 | grep -q '100% .*225/225 tiles.*ETA 0:00' ||
	{ cat "$TMP/p.log"; fail "the last progress line is not 100%"; }
grep -q '^portray-master: progress .* [0-9]*/225 tiles  0:0[0-9] elapsed  ETA [0-9-]' "$TMP/p.log" ||
	fail "progress lines lack tiles, elapsed or ETA"
grep -q "$(printf '\r')" "$TMP/p.log" && fail "carriage returns in piped output"
grep -q "$(printf '\033')" "$TMP/p.log" && fail "escape codes in piped output"

"$MASTER" -q -j1 --tile 16 -o "$TMP/q.ppm" --progress-interval 0.2 "$TMP/slow.sce" 2>"$TMP/q.log" || fail "-q render"
[ -s "$TMP/q.log" ] && fail "-q printed: $(cat "$TMP/q.log")"
"$MASTER" -j1 --tile 16 -o "$TMP/z.ppm" --progress-interval 0 "$TMP/slow.sce" 2>"$TMP/z.log" || fail "interval 0"
grep -q progress "$TMP/z.log" && fail "--progress-interval 0 printed progress"
# shorter than the default 10 s: only the summary, as before
"$MASTER" -o "$TMP/d.ppm" "$TMP/slow.sce" 2>"$TMP/d.log" || fail "default render"
grep -q progress "$TMP/d.log" && fail "a short render printed progress lines"
grep -q "d.ppm: 240x240" "$TMP/d.log" || fail "no summary"
for bad in -1 x 1e9; do
	"$MASTER" -o "$TMP/d.ppm" --progress-interval "$bad" "$TMP/slow.sce" 2>/dev/null
	[ $? -eq 64 ] || fail "--progress-interval $bad accepted"
done

# on a terminal
if ! command -v script >/dev/null 2>&1 || ! script -qec true /dev/null >/dev/null 2>&1; then
	echo "SKIP: no script(1) with -e -c for a pty test (the rest passed)"
	exit 77
fi
# bar_check LOG MAXLEN MIN: splits LOG at CR and LF, keeps the bar's redraws
# (the pieces with "ETA"), checks each is at most MAXLEN and that at least
# MIN were drawn
bar_check() {
	tr '\r' '\n' <"$1" | sed "s/$(printf '\033')\[K//g" | grep 'ETA' >"$TMP/bars" || true
	n=$(wc -l <"$TMP/bars")
	[ "$n" -ge "$3" ] || { cat "$1"; fail "$n redraws, want at least $3"; }
	long=$(awk -v m="$2" 'length($0) > m' "$TMP/bars" | head -n 1)
	[ -z "$long" ] || fail "a redraw of $(printf %s "$long" | wc -c) characters at $2 + 1 columns: '$long'"
}
script -qfec "stty cols 50 rows 20; $MASTER -j1 --tile 16 -o $TMP/t.ppm $TMP/slow.sce" /dev/null \
	>"$TMP/t.log" 2>&1 </dev/null || fail "render on a pty failed"
bar_check "$TMP/t.log" 49 3
grep -q '\[###' "$TMP/t.log" || fail "no bar drawn at 50 columns"
# six workers that refuse: the farm line still fits
W6=127.0.0.1:1,127.0.0.1:2,127.0.0.1:3,127.0.0.1:4,127.0.0.1:5,127.0.0.1:6
script -qfec "stty cols 50 rows 20; $MASTER -j1 --tile 16 -w $W6 -o $TMP/f.ppm $TMP/slow.sce" /dev/null \
	>"$TMP/f.log" 2>&1 </dev/null || fail "farm render on a pty failed"
bar_check "$TMP/f.log" 49 3
cmp -s "$TMP/t.ppm" "$TMP/f.ppm" || fail "the farm render with lost workers differs"
# the terminal grows during the render: later redraws use the room
script -qfec "stty cols 50 rows 20; (sleep 0.6; stty cols 100 </dev/tty) & $MASTER -j1 --tile 16 -o $TMP/g.ppm $TMP/slow.sce" \
	/dev/null >"$TMP/g.log" 2>&1 </dev/null || fail "render on a growing pty failed"
bar_check "$TMP/g.log" 99 3
tr '\r' '\n' <"$TMP/g.log" | sed "s/$(printf '\033')\[K//g" | grep 'ETA' | awk 'length($0) > 49' | grep -q . ||
	fail "the bar did not widen when the terminal did"
echo ok
