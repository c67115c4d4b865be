#!/bin/sh
# render_formats.sh - output formats from the command line: each one by its
# extension and by --format, its header and size; the 8-bit PNG's chunks; -o -
# on standard output; byte-identical files across threads and tiles in every
# format (the render-time text apart, written only with --render-time, the only bytes that change from run to
# run); and the output refused before any tracing (exit 64 or 74 at once, on
# a scene whose first pixel never ends).
. tests/cli/render_lib.inc
BUILD=${BUILD:-build}
CHUNKS=$ROOT/$BUILD/tools/pngchunks
[ -x "$CHUNKS" ] || fail "$CHUNKS missing (make test builds it)"
PIXSTAT=$ROOT/$BUILD/tools/pixstat
[ -x "$PIXSTAT" ] || fail "$PIXSTAT missing (make test builds it)"
SCENE=$ROOT/tests/data/spd/tetra_s4.sce
HOSTILE=$ROOT/tests/data/hostile/nested64.sce
W=64
H=48

# render OUT [options]: tetra_s4 at W x H
render() {
	o=$1
	shift
	"$MASTER" -q "$SCENE" --size ${W}x$H -o "$o" "$@" 2>"$TMP/err" || fail "render $o $*: $(cat "$TMP/err")"
	[ -s "$TMP/err" ] && fail "render $o $*: stderr: $(cat "$TMP/err")"
	return 0
}

# hex FILE OFFSET COUNT: COUNT bytes at OFFSET as hex
hex() { od -An -tx1 -j "$2" -N "$3" "$1" | tr -d ' \n'; }

size() { wc -c <"$1" | tr -d ' '; }

# check_format FILE FORMAT: the file starts and is as long as FORMAT says
check_format() {
	case $2 in
	png | png16)
		png_check "$1"
		depth=8
		[ "$2" = png16 ] && depth=16
		"$CHUNKS" "$1" >"$TMP/chunks" || fail "$1: $(cat "$TMP/chunks")"
		grep -q "^IHDR 13 ${W}x$H depth $depth colour 2$" "$TMP/chunks" || fail "$1: IHDR: $(head -n 1 "$TMP/chunks")"
		;;
	ppm) ppm_check "$1" $W $H ;;
	pfm)
		[ "$(head -c 13 "$1")" = "$(printf 'PF\n%d %d\n-1.0' $W $H)" ] || fail "$1: PFM header"
		[ "$(size "$1")" -eq $((14 + W * H * 12)) ] || fail "$1: $(size "$1") bytes, want $((14 + W * H * 12))"
		;;
	exr | exr-half)
		[ "$(hex "$1" 0 8)" = 762f310102000000 ] || fail "$1: not a single-part scan-line OpenEXR"
		bps=4
		[ "$2" = exr-half ] && bps=2
		# the scan lines end the file: H blocks of y, size and 3 W values
		want=$((H * (8 + 3 * W * bps)))
		[ "$(size "$1")" -gt $want ] || fail "$1: too short for its scan lines"
		last=$(hex "$1" $(($(size "$1") - 8 - 3 * W * bps)) 8)
		[ "$last" = "$(printf '%02x000000%02x%02x0000' $((H - 1)) $((3 * W * bps % 256)) $((3 * W * bps / 256)))" ] ||
			fail "$1: last block header $last"
		;;
	esac
}

# every format by extension (any case) and by --format
render "$TMP/e.png" --render-time
check_format "$TMP/e.png" png
render "$TMP/e.PPM"
check_format "$TMP/e.PPM" ppm
render "$TMP/e.pfm"
check_format "$TMP/e.pfm" pfm
render "$TMP/e.Exr"
check_format "$TMP/e.Exr" exr
for f in png png16 ppm pfm exr exr-half; do
	render "$TMP/f.$f" --format $f
	check_format "$TMP/f.$f" $f
done
render "$TMP/g.png" --format png16
check_format "$TMP/g.png" png16
render "$TMP/g.exr" --format exr-half
check_format "$TMP/g.exr" exr-half
cmp "$TMP/e.PPM" "$TMP/f.ppm" || fail "PPM by extension and by --format differ"
cmp "$TMP/e.pfm" "$TMP/f.pfm" || fail "PFM by extension and by --format differ"

# the 8-bit PNG: colour chunks, then the three texts, then the image
"$CHUNKS" "$TMP/e.png" | cut -d' ' -f1 | uniq | tr '\n' ' ' >"$TMP/order"
[ "$(cat "$TMP/order")" = "IHDR cHRM gAMA sRGB tEXt IDAT IEND " ] || fail "chunk order: $(cat "$TMP/order")"
"$CHUNKS" "$TMP/e.png" | grep '^tEXt' | cut -d' ' -f3- >"$TMP/texts"
sed -n 1p "$TMP/texts" | grep -qx 'Software=portray [0-9.]*' || fail "Software text: $(cat "$TMP/texts")"
sed -n 2p "$TMP/texts" | grep -qx 'Source=tetra_s4.sce' || fail "Source text: $(cat "$TMP/texts")"
sed -n 3p "$TMP/texts" | grep -qx 'Render time=[0-9]*\.[0-9][0-9][0-9] s' || fail "Render time text: $(cat "$TMP/texts")"
[ "$(wc -l <"$TMP/texts")" -eq 3 ] || fail "texts: $(cat "$TMP/texts")"
# the 16-bit PNG holds the renderer's values in 65535 steps: every bit is
# significant, so no sBIT (an 8-bit pipeline's would say 8)
"$CHUNKS" "$TMP/g.png" | grep -q '^sBIT' && fail "16-bit PNG from the float pipeline with an sBIT chunk"
render "$TMP/nt.png" --no-render-time
"$CHUNKS" "$TMP/nt.png" | grep -q 'Render time' && fail "--no-render-time wrote a render time"
render "$TMP/dflt.png"
"$CHUNKS" "$TMP/dflt.png" | grep -q 'Render time' && fail "a render time written without --render-time"
cmp "$TMP/dflt.png" "$TMP/nt.png" || fail "the default is not --no-render-time"
# with a camera file, the Source names both files
cat >"$TMP/view.cam" <<'CAM'
camera look-from (0 0 10) look-at (0 0 0) ;
CAM
"$MASTER" -q -c "$TMP/view.cam" "$SCENE" --size 8x6 -o "$TMP/cam.png" 2>"$TMP/err" || fail "render with a camera file: $(cat "$TMP/err")"
"$CHUNKS" "$TMP/cam.png" | grep -qx 'tEXt [0-9]* Source=tetra_s4.sce (camera file view.cam)' ||
	fail "Source with a camera: $("$CHUNKS" "$TMP/cam.png" | grep Source)"

# -o -: the image on standard output, PNG unless --format says otherwise;
# the summary (without -q) still on stderr, naming standard output
"$MASTER" "$SCENE" --size ${W}x$H -o - --no-render-time >"$TMP/stdout.png" 2>"$TMP/err" || fail "-o -: $(cat "$TMP/err")"
cmp "$TMP/stdout.png" "$TMP/nt.png" || fail "-o - differs from -o FILE.png"
grep -q "standard output: ${W}x$H" "$TMP/err" || fail "-o - summary: $(cat "$TMP/err")"
[ -e "$ROOT/-" ] && fail "-o - wrote a file named -"
"$MASTER" -q "$SCENE" --size ${W}x$H -o - --format exr-half --no-render-time | cat >"$TMP/stdout.exr" ||
	fail "-o - --format exr-half through a pipe"
render "$TMP/nt.exr" --format exr-half --no-render-time
cmp "$TMP/stdout.exr" "$TMP/nt.exr" || fail "-o - --format exr-half differs from the file"

# byte-identical across threads and tiles, in every format
for f in png png16 ppm pfm exr exr-half; do
	render "$TMP/a.$f" --format $f -j 1 --tile 8 --no-render-time
	for args in "-j 2 --tile 32" "-j 2 --tile 8" "-j 1 --tile 32"; do
		# shellcheck disable=SC2086
		render "$TMP/b.$f" --format $f $args --no-render-time
		cmp "$TMP/a.$f" "$TMP/b.$f" || fail "$f: $args differs from -j 1 --tile 8"
	done
done

# the float formats carry the renderer's values before clamping: a light of
# colour 1.5 on a white sphere gives values above 1 in the PFM (linear: up
# to about 2) where the 8-bit files clamp to 255, and a smooth gradient below; byte-identical across
# threads and tiles too, and the same values as OpenEXR's FLOAT channels
SCENE_SAVED=$SCENE
SCENE=$ROOT/tests/data/bright.sce
render "$TMP/br.pfm" -j 1 --tile 8
"$PIXSTAT" "$TMP/br.pfm" >"$TMP/stat" || fail "pixstat: $(cat "$TMP/stat")"
read -r _ _ _ _ max _ above _ below _ levels <"$TMP/stat"
[ "$above" -gt 1000 ] || fail "bright PFM: $above values above 1 ($(cat "$TMP/stat"))"
awk -v m="$max" 'BEGIN { exit !(m > 1.5 && m < 2.5) }' || fail "bright PFM: max $max, want about 2"
[ "$below" -eq 0 ] || fail "bright PFM: $below values below 0"
[ "$levels" -gt 256 ] || fail "bright PFM: only $levels distinct values: still 8-bit?"
for args in "-j 2 --tile 32" "-j 2 --tile 5"; do
	# shellcheck disable=SC2086
	render "$TMP/br2.pfm" $args
	cmp "$TMP/br.pfm" "$TMP/br2.pfm" || fail "bright PFM: $args differs from -j 1 --tile 8"
done
render "$TMP/br.ppm"
[ "$(od -An -v -tu1 -j 15 "$TMP/br.ppm" | tr -s ' ' '\n' | grep -c '^255$')" -gt 1000 ] ||
	fail "bright PPM: values above 1 not clamped to 255"
render "$TMP/br.exr" --no-render-time
if command -v python3 >/dev/null 2>&1; then
	# a second reader: the EXR's FLOAT channels hold the PFM's values (rows
	# the other way up), and the 16-bit PNG of a smooth gradient has far more
	# than 256 levels, each the PFM's value clamped and rounded to 65535 steps
	render "$TMP/br.png" --format png16
	python3 - "$TMP/br.pfm" "$TMP/br.exr" "$TMP/br.png" <<'PY' || fail "float formats disagree (python3 check)"
import struct, sys, zlib
pfm, exr, png = (open(f, 'rb').read() for f in sys.argv[1:])
W, H = 64, 48
head = b'PF\n64 48\n-1.0\n'
assert pfm[:len(head)] == head
pf = struct.unpack('<%df' % (W * H * 3), pfm[len(head):])
rows = [pf[(H - 1 - y) * W * 3:(H - y) * W * 3] for y in range(H)]  # top row first
line = 8 + 3 * W * 4
for y in range(H):
    blk = exr[len(exr) - (H - y) * line:][:line]
    yy, n = struct.unpack('<ii', blk[:8])
    assert yy == y and n == 3 * W * 4, (y, yy, n)
    v = struct.unpack('<%df' % (3 * W), blk[8:])
    for x in range(W):
        for c in range(3):  # EXR: B, G, R planes
            assert v[(2 - c) * W + x] == rows[y][3 * x + c], (x, y, c)
i, idat = 8, b''
while i < len(png):
    n, = struct.unpack('>I', png[i:i + 4])
    t = png[i + 4:i + 8]
    if t == b'IHDR':
        assert png[i + 16] == 16, 'not 16-bit'
    if t == b'IDAT':
        idat += png[i + 8:i + 8 + n]
    i += 12 + n
raw, bpp, rb = zlib.decompress(idat), 6, 6 * W
prev, img = bytearray(rb), []
for y in range(H):
    f, cur = raw[y * (rb + 1)], bytearray(raw[y * (rb + 1) + 1:(y + 1) * (rb + 1)])
    for k in range(rb):
        a = cur[k - bpp] if k >= bpp else 0
        b, c = prev[k], prev[k - bpp] if k >= bpp else 0
        if f == 1: cur[k] = (cur[k] + a) & 255
        elif f == 2: cur[k] = (cur[k] + b) & 255
        elif f == 3: cur[k] = (cur[k] + (a + b) // 2) & 255
        elif f == 4:
            p = a + b - c
            pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
            cur[k] = (cur[k] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
    img.append(struct.unpack('>%dH' % (3 * W), bytes(cur)))
    prev = cur
levels = set(v for r in img for v in r)
assert len(levels) > 256, '%d levels in the 16-bit PNG' % len(levels)
def enc(l):  # sRGB encoding, the inverse of the writers' decoding
    return l * 12.92 if l <= 0.0031308 else 1.055 * l ** (1 / 2.4) - 0.055
for y in range(H):
    for k in range(3 * W):
        want = round(min(max(enc(rows[y][k]), 0.0), 1.0) * 65535)
        assert abs(img[y][k] - want) <= 1, (y, k, img[y][k], want)
print('float formats agree: %d levels in the 16-bit PNG' % len(levels))
PY
else
	echo "note: python3 not installed: the EXR and 16-bit PNG values are not read back"
fi
SCENE=$SCENE_SAVED

# with the render time, a PNG differs from another render in that text only
render "$TMP/t1.png" -j 1 --tile 8 --render-time
render "$TMP/t2.png" -j 2 --tile 32 --render-time
"$CHUNKS" -d "Render time" "$TMP/t1.png" "$TMP/t1s.png" || fail "pngchunks -d"
"$CHUNKS" -d "Render time" "$TMP/t2.png" "$TMP/t2s.png" || fail "pngchunks -d"
cmp "$TMP/t1s.png" "$TMP/t2s.png" || fail "PNGs differ beyond their render time"
cmp "$TMP/t1s.png" "$TMP/a.png" || fail "a PNG without its render time differs from --no-render-time's"
# and the 8-bit PNG holds the plain encoder's IHDR and IDAT, untouched
"$CHUNKS" -s "$TMP/a.png" "$TMP/plain.png" || fail "pngchunks -s"
[ "$(size "$TMP/a.png")" -gt "$(size "$TMP/plain.png")" ] || fail "no chunks were added"

# refused before any tracing: the hostile scene's first pixel never ends,
# so only an answer before rendering comes back (5 s is the backstop; the
# answer must come in under a second)
# refused CODE MESSAGE-PATTERN ARGS...: exit CODE at once, the message on stderr
refused() {
	code=$1
	pattern=$2
	shift 2
	t0=$(date +%s%N)
	timeout -k 1 5 "$MASTER" -q "$HOSTILE" "$@" >"$TMP/out" 2>"$TMP/err"
	rc=$?
	ms=$((($(date +%s%N) - t0) / 1000000))
	[ "$rc" -eq "$code" ] || fail "$*: exit $rc, want $code ($(cat "$TMP/err"))"
	[ "$ms" -lt 1000 ] || fail "$*: took $ms ms: the output was not checked before rendering"
	grep -q -- "$pattern" "$TMP/err" || fail "$*: message '$(cat "$TMP/err")', want /$pattern/"
	[ -s "$TMP/out" ] && fail "$*: wrote to stdout"
	return 0
}
refused 74 'cannot write /nonexistent/x.png: no directory /nonexistent' -o /nonexistent/x.png
refused 74 "cannot write $TMP: it is a directory" -o "$TMP" --format png
refused 74 "is not a directory" -o "$TMP/e.png/x.png"
refused 64 'known extensions are' -o "$TMP/x.tif"
refused 64 '\.png \.ppm \.pfm \.exr' -o "$TMP/x.tif"
refused 64 'known extensions are' -o "$TMP/noextension"
refused 64 'does not go with the name' -o "$TMP/x.png" --format exr
refused 64 'does not go with the name' -o "$TMP/x.exr" --format pfm
refused 64 "--format wants png, png16, ppm, pfm, exr or exr-half, not 'tiff'" -o "$TMP/x.png" --format tiff
refused 74 'no directory' --format exr -o "$TMP/none/x.data"
# standard output closed, or a terminal (script(1) gives one, where present)
timeout -k 1 5 "$MASTER" -q "$HOSTILE" -o - >&- 2>"$TMP/err"
rc=$?
[ "$rc" -eq 74 ] || fail "-o - with stdout closed: exit $rc, want 74"
grep -q 'cannot write standard output: Bad file descriptor' "$TMP/err" || fail "closed stdout: $(cat "$TMP/err")"
if command -v script >/dev/null 2>&1; then
	timeout -k 1 5 script -qec "'$MASTER' -q '$HOSTILE' -o -; echo exit=\$?" /dev/null </dev/null >"$TMP/tty" 2>&1
	grep -q 'exit=64' "$TMP/tty" || fail "-o - on a terminal: $(cat "$TMP/tty")"
	grep -q 'would write a binary image to the terminal' "$TMP/tty" || fail "-o - on a terminal: $(cat "$TMP/tty")"
fi
# a directory that refuses files; root passes any mode bits, so as root the
# master runs as nobody (setpriv) if it can, and the check is skipped if not
mkdir "$TMP/ro" && chmod 555 "$TMP/ro"
if [ "$(id -u)" -ne 0 ]; then
	refused 74 "cannot write $TMP/ro/x.png: $TMP/ro: Permission denied" -o "$TMP/ro/x.png"
elif command -v setpriv >/dev/null 2>&1 && chmod 711 "$TMP" &&
	setpriv --reuid=nobody --regid=nogroup --clear-groups true 2>/dev/null; then
	t0=$(date +%s%N)
	timeout -k 1 5 setpriv --reuid=nobody --regid=nogroup --clear-groups \
		"$MASTER" -q "$HOSTILE" -o "$TMP/ro/x.png" 2>"$TMP/err"
	rc=$?
	ms=$((($(date +%s%N) - t0) / 1000000))
	[ "$rc" -eq 74 ] || fail "read-only directory (as nobody): exit $rc, want 74 ($(cat "$TMP/err"))"
	[ "$ms" -lt 1000 ] || fail "read-only directory: took $ms ms"
	grep -q "cannot write $TMP/ro/x.png: $TMP/ro: Permission denied" "$TMP/err" ||
		fail "read-only directory message: $(cat "$TMP/err")"
else
	echo "note: running as root without setpriv: the read-only directory case is not checked"
fi
[ -z "$(ls -A "$TMP/ro")" ] || fail "files left in the read-only directory"
ls "$TMP" | grep -q '\.tmp\.' && fail "temporary files left behind: $(ls "$TMP")"
echo "render_formats: ok"
