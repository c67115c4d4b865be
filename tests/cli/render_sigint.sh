#!/bin/sh
# render_sigint.sh - SIGINT ends a render and writes the finished part: a
# valid image, unfinished tiles black, a message saying how much is done,
# exit 130; and the journal of the finished tiles beside it (--resume).
. tests/cli/render_lib.inc
slow_scene "$TMP/slow.sce" 600
"$MASTER" "$TMP/slow.sce" -o "$TMP/part.ppm" -j 1 --tile 20 2>"$TMP/err" &
pid=$!
# wait until the render has started (a temporary file never appears before the end)
sleep 1
kill -INT "$pid" || fail "render finished before SIGINT: machine too fast for this scene?"
wait "$pid"
rc=$?
[ "$rc" -eq 130 ] || fail "exit $rc after SIGINT, want 130: $(cat "$TMP/err")"
ppm_check "$TMP/part.ppm" 600 600
msg=$(grep 'interrupted:' "$TMP/err") || fail "no 'interrupted:' message: $(cat "$TMP/err")"
echo "$msg" | grep -Eq 'interrupted: [0-9]+ of 900 tiles \([0-9]+%\) written to .*part.ppm$' ||
	fail "message: $msg"
done_tiles=$(echo "$msg" | sed 's/.*interrupted: \([0-9]*\) of.*/\1/')
[ "$done_tiles" -lt 900 ] || fail "all tiles done: not an interrupted render"
# the last tile is unfinished: black; a finished tile (if any) is lit
[ "$(ppm_pixel "$TMP/part.ppm" 600 599 599)" = "0 0 0" ] || fail "unfinished pixel not black"
if [ "$done_tiles" -gt 0 ]; then
	[ "$(ppm_pixel "$TMP/part.ppm" 600 5 5)" != "0 0 0" ] || fail "finished pixel is black"
fi
# no temporary file left behind: the image and, with finished tiles, its journal
want=part.ppm
[ "$done_tiles" -gt 0 ] && want="part.ppm part.ppm.journal"
[ "$(ls "$TMP" | grep part | tr '\n' ' ')" = "$want " ] || fail "files: $(ls "$TMP"), want $want"
echo "render_sigint: ok ($msg)"
