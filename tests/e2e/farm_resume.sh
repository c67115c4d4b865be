#!/bin/sh
# Checkpoint and resume (docs/resume.md) on a farm: master + 2 workers.
#  1. The master SIGKILLed at random points, then --resume'd several times
#     in a row: the final image is byte-identical to a one-go render; every
#     run starts from at least what the one before had journalled; the last
#     run says it took J tiles from the journal and traced M, J + M = all;
#     and the kept journal holds each tile exactly once (its size is header
#     + one record per tile: no run traced and journalled a tile twice).
#  2. SIGTERM and SIGHUP stop a render like SIGINT: exit 143 / 129, the
#     partial image and the journal written; --resume completes it identically.
#  3. A worker caught lying: the journal kept from that render is exact.
#  4. A journal of another scene, size or tile side is refused (exit 65,
#     before tracing: the output is not touched); a torn tail is dropped
#     (identical image); a damaged header is refused; --resume with -o -
#     is a usage error (64).
. "$(dirname "$0")/farm_lib.inc"
W=192
H=144
TILE=12
NT=$(( ((W + TILE - 1) / TILE) * ((H + TILE - 1) / TILE) )) # 192 tiles
start_worker a -j 1 --test-delay-ms 25
start_worker b -j 1 --test-delay-ms 25
WS="127.0.0.1:$a_PORT,127.0.0.1:$b_PORT"
local_render "$SCENE" "$T/ref.ppm" --size ${W}x$H
OUT=$T/out.ppm
J=$OUT.journal

# master LOG [options]: a farm render of SCENE to OUT in the background (pid in M)
master() {
	log=$1
	shift
	"$BIN/portray-master" "$SCENE" -o "$OUT" --size ${W}x$H --tile $TILE --no-local -w "$WS" \
		--checkpoint 0.1 "$@" 2>"$T/$log" &
	M=$!
	PIDS="$PIDS $M"
}

# 1. SIGKILL at random points, then resume
seed=$(date +%N | sed 's/^0*//')
echo "kill points from seed ${seed:-1}"
points=$(awk -v s="${seed:-1}" 'BEGIN { srand(s); for (i = 0; i < 4; i++) printf "%.2f ", 0.1 + rand() * 0.7 }')
prev=0
run=0
for p in $points; do
	run=$((run + 1))
	master "k$run.log" --resume --keep-journal # a run that finishes before its kill leaves it too
	# the kill point counts from the run's first job on worker a (a slow
	# start, as under a sanitizer, must not leave every run without tiles)
	wait_count "$T/a.log" " job .*: started" $run "run $run to start on worker a"
	sleep "$p"
	kill -KILL $M 2>/dev/null
	wait $M
	rc=$?
	[ $run -eq 1 ] || grep -q "resuming from\|no journal" "$T/k$run.log" || fail "run $run: no resume note"
	got=0
	if grep -q "resuming from" "$T/k$run.log"; then
		got=$(sed -n 's/.*resuming from .*: \([0-9]*\) of '$NT' tiles done, \([0-9]*\) to trace$/\1 \2/p' \
			"$T/k$run.log")
		set -- $got
		[ $(($1 + $2)) -eq $NT ] || fail "run $run: '$got' does not add up to $NT"
		got=$1
	fi
	[ "$got" -ge "$prev" ] || fail "run $run resumed from $got tiles, the run before from $prev"
	echo "run $run: killed $p s after its start (exit $rc), resumed from $got tiles"
	grep -q "damaged\|refused\|cannot" "$T/k$run.log" && fail "run $run: $(cat "$T/k$run.log")"
	prev=$got
	[ $rc -eq 0 ] && break # finished before the kill (a fast machine): nothing more to resume
done
master last.log --resume --keep-journal
wait $M || fail "last resume failed (exit $?): $(cat "$T/last.log")"
cmp "$T/ref.ppm" "$OUT" || fail "resumed image differs from the one-go render"
line=$(grep "resumed: " "$T/last.log") || fail "no 'resumed:' summary: $(cat "$T/last.log")"
echo "last run: $line"
set -- $(echo "$line" | sed -n 's/.*resumed: \([0-9]*\) tiles from the journal, \([0-9]*\) traced, \([0-9]*\) in all$/\1 \2 \3/p')
[ $# -eq 3 ] || fail "summary: $line"
[ "$3" -eq $NT ] && [ $(($1 + $2)) -eq $NT ] || fail "from the journal + traced != $NT: $line"
[ "$1" -ge "$prev" ] || fail "the last run took $1 tiles from the journal, fewer than the $prev before"
[ "$prev" -gt 0 ] || fail "no killed run left a journalled tile (kill points $points)"
# one record per tile: 112 header bytes, 12 + 16 a record, plus the pixels
[ -f "$J" ] || fail "--keep-journal: no journal"
size=$(wc -c <"$J")
[ "$size" -eq $((112 + 28 * NT + W * H * 3)) ] || fail "journal of $size bytes: some tile journalled twice (or missing)"
rm -f "$J"

# 2. SIGTERM and SIGHUP
hup_ignored=$(awk '/^SigIgn/ { print substr($2, length($2)) }' /proc/$$/status 2>/dev/null)
for sig in TERM HUP; do
	if [ $sig = HUP ] && [ -n "$hup_ignored" ] && [ $((0x$hup_ignored & 1)) -eq 1 ]; then
		echo "SIGHUP is ignored here (nohup?): a master keeps it so; not tested"
		continue
	fi
	rm -f "$OUT" "$J"
	master "$sig.log"
	wait_for "$T/a.log" " job .*: started" "worker a to start a job"
	sleep 0.5
	kill -0 $M 2>/dev/null || fail "SIG$sig: render ended before the signal: test too fast"
	kill -$sig $M
	wait $M
	rc=$?
	want=143
	[ $sig = HUP ] && want=129
	[ $rc -eq $want ] || fail "SIG$sig: exit $rc, want $want: $(cat "$T/$sig.log")"
	grep -Eq "(terminated|hung up): [0-9]+ of $NT tiles" "$T/$sig.log" || fail "SIG$sig: no message"
	[ -s "$OUT" ] || fail "SIG$sig: no partial image"
	[ "$(wc -c <"$OUT")" -eq $((15 + W * H * 3)) ] || fail "SIG$sig: partial image of the wrong size"
	[ -s "$J" ] || fail "SIG$sig: no journal"
	cmp -s "$T/ref.ppm" "$OUT" && fail "SIG$sig: the partial image is whole: test too fast"
	master "$sig-resume.log" --resume
	wait $M || fail "SIG$sig: resume failed (exit $?)"
	cmp "$T/ref.ppm" "$OUT" || fail "SIG$sig: resumed image differs"
	[ -f "$J" ] && fail "SIG$sig: journal left after a finished render"
	echo "SIG$sig: $(grep 'resumed:' "$T/$sig-resume.log")"
done

# 3. a worker caught lying (audits) during a journalled render: the kept
# journal resumes to the exact image (undone records: test_journal)
start_worker liar -j 1 --test-delay-ms 25 --test-fault lie
rm -f "$OUT" "$J"
"$BIN/portray-master" "$SCENE" -o "$OUT" --size ${W}x$H --tile $TILE --no-local --checkpoint 0.02 --keep-journal \
	-w "127.0.0.1:$a_PORT,127.0.0.1:$liar_PORT" 2>"$T/lie.log" || fail "render with a liar failed (exit $?)"
grep -q "returned wrong pixels" "$T/lie.log" || fail "the liar was not caught"
cmp "$T/ref.ppm" "$OUT" || fail "image differs with a liar"
rm -f "$OUT"
master lie-resume.log --resume
wait $M || fail "resume of the liar's journal failed (exit $?)"
grep -q "resumed: $NT tiles from the journal, 0 traced" "$T/lie-resume.log" || fail "liar: $(cat "$T/lie-resume.log")"
cmp "$T/ref.ppm" "$OUT" || fail "image resumed from the liar's journal differs"
echo "liar: journal replayed whole"

# 4. refusals and damage, on quick local renders (-j 1, no workers)
L=$T/loc.ppm
LJ=$L.journal
lrender() { "$BIN/portray-master" "$@" -j 1 2>"$T/l.log"; }
lrender "$SCENE" -o "$L" --size 96x64 --tile 8 --keep-journal || fail "local render with --keep-journal"
cp "$L" "$T/loc-ref.ppm"
cp "$LJ" "$T/loc.journal"
rm -f "$L"
refused() { # WHAT PATTERN: the last lrender was refused before tracing
	[ $rc -eq 65 ] || fail "$1: exit $rc, want 65: $(cat "$T/l.log")"
	grep -q "$2" "$T/l.log" || fail "$1: message: $(cat "$T/l.log")"
	[ -f "$L" ] && fail "$1: an image was written"
	cmp -s "$LJ" "$T/loc.journal" || fail "$1: the journal was changed"
}
sed 's/0\.5/0.55/' "$SCENE" >"$T/other.sce"
cmp -s "$SCENE" "$T/other.sce" && fail "other.sce is not another scene"
lrender "$T/other.sce" -o "$L" --size 96x64 --tile 8 --resume
rc=$?
refused "another scene" "another scene"
lrender "$SCENE" -o "$L" --size 96x72 --tile 8 --resume
rc=$?
refused "another size" "for a 96x64 image; this render is 96x72"
lrender "$SCENE" -o "$L" --size 96x64 --tile 16 --resume
rc=$?
refused "another tile side" "tiles of 8 pixels; this render cuts tiles of 16"
# a torn tail: dropped, the rest used, the image identical
size=$(wc -c <"$LJ")
head -c $((size - 100)) "$T/loc.journal" >"$LJ"
lrender "$SCENE" -o "$L" --size 96x64 --tile 8 --resume || fail "torn journal: exit $?: $(cat "$T/l.log")"
grep -q "tail of [0-9]* bytes dropped" "$T/l.log" || fail "torn journal: no note: $(cat "$T/l.log")"
grep -q "resumed: 95 tiles from the journal, 1 traced, 96 in all" "$T/l.log" || fail "torn journal: $(cat "$T/l.log")"
cmp "$T/loc-ref.ppm" "$L" || fail "torn journal: image differs"
[ -f "$LJ" ] && fail "journal left after a finished render"
# a damaged header: refused
rm -f "$L"
{ printf 'XXXX'; tail -c +5 "$T/loc.journal"; } >"$LJ"
cp "$LJ" "$T/loc.journal"
lrender "$SCENE" -o "$L" --size 96x64 --tile 8 --resume
rc=$?
refused "damaged header" "not a portray journal, or its header is damaged"
# a --region render: another region's journal is refused; its own resumes to
# the bytes of the region rendered in one go (a float format: 12 bytes a pixel)
RG=10,4,90,60
lrender "$SCENE" -o "$T/reg-ref.pfm" --size 96x64 --tile 8 --region $RG || fail "region render"
lrender "$SCENE" -o "$T/reg.pfm" --size 96x64 --tile 8 --region $RG --keep-journal || fail "region render, journal kept"
rm -f "$T/reg.pfm"
cp "$T/reg.pfm.journal" "$T/reg.journal"
lrender "$SCENE" -o "$T/reg.pfm" --size 96x64 --tile 8 --region 10,4,90,61 --resume
rc=$?
[ $rc -eq 65 ] && grep -q "another --region" "$T/l.log" || fail "another region: exit $rc: $(cat "$T/l.log")"
# half the tiles: the journal cut after the header and a few records is still whole up to there
size=$(wc -c <"$T/reg.journal")
head -c $((112 + (size - 112) / 2)) "$T/reg.journal" >"$T/reg.pfm.journal"
lrender "$SCENE" -o "$T/reg.pfm" --size 96x64 --tile 8 --region $RG --resume || fail "region resume: $(cat "$T/l.log")"
grep -q "resumed: [1-9][0-9]* tiles from the journal, [1-9][0-9]* traced" "$T/l.log" || fail "region resume: $(cat "$T/l.log")"
cmp "$T/reg-ref.pfm" "$T/reg.pfm" || fail "region resumed: image differs"
echo "region: resumed to the same bytes"
# --resume and standard output
"$BIN/portray-master" "$SCENE" -o - --size 96x64 --resume >/dev/null 2>"$T/l.log"
rc=$?
[ $rc -eq 64 ] || fail "--resume -o -: exit $rc, want 64"
grep -q "resume needs an output file" "$T/l.log" || fail "--resume -o -: $(cat "$T/l.log")"
echo ok
