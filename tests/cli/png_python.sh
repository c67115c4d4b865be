#!/bin/sh
# png_python.sh - our PNGs decoded by a second, unrelated decoder: Python's
# zlib (plus a few lines of unfiltering). Skipped (exit 77) when python3 is
# absent. $BUILD/tests/test_img DIR writes the sample PNGs and raw pixels.
BUILD=${BUILD:-build}
if ! command -v python3 >/dev/null 2>&1; then
	echo "python3 not installed"
	exit 77
fi
dir=$(mktemp -d "${TMPDIR:-/tmp}/png_python.XXXXXX") || exit 1
trap 'rm -rf "$dir"' EXIT
"$BUILD/tests/test_img" "$dir" || { echo "test_img could not write samples"; exit 1; }
python3 - "$dir" <<'PY'
import os, struct, sys, zlib
d = sys.argv[1]
bad = 0
names = sorted(f[:-4] for f in os.listdir(d) if f.endswith('.png'))
for name in names:
    data = open(os.path.join(d, name + '.png'), 'rb').read()
    assert data[:8] == b'\x89PNG\r\n\x1a\n', name
    i, idat, w = 8, b'', None
    while i < len(data):
        n, = struct.unpack('>I', data[i:i + 4])
        t, c = data[i + 4:i + 8], data[i + 8:i + 8 + n]
        crc, = struct.unpack('>I', data[i + 8 + n:i + 12 + n])
        assert zlib.crc32(t + c) & 0xffffffff == crc, name + ': chunk CRC'
        if t == b'IHDR':
            w, h, depth, ctype, _, _, _ = struct.unpack('>IIBBBBB', c)
            assert depth == 8 and ctype == 2, name
        elif t == b'IDAT':
            idat += c
        i += 12 + n
    raw = zlib.decompress(idat)
    rb = 3 * w
    assert len(raw) == h * (rb + 1), name + ': size'
    out, prev = bytearray(), bytearray(rb)
    for y in range(h):
        f = raw[y * (rb + 1)]
        r = bytearray(raw[y * (rb + 1) + 1:(y + 1) * (rb + 1)])
        for x in range(rb):
            a = r[x - 3] if x >= 3 else 0
            b = prev[x]
            c = prev[x - 3] if x >= 3 else 0
            if f == 1: p = a
            elif f == 2: p = b
            elif f == 3: p = (a + b) // 2
            elif f == 4:
                q = a + b - c; pa, pb, pc = abs(q - a), abs(q - b), abs(q - c)
                p = a if pa <= pb and pa <= pc else b if pb <= pc else c
            else: p = 0
            r[x] = (r[x] + p) & 255
        out += r
        prev = r
    ref = open(os.path.join(d, name + '.rgb'), 'rb').read()
    ok = bytes(out) == ref
    bad += not ok
    print('%-8s %4dx%-4d %7d bytes  zlib-6 would give %7d: %s' % (
        name, w, h, len(idat), len(zlib.compress(raw, 6)), 'ok' if ok else 'PIXELS DIFFER'))
sys.exit(1 if bad or not names else 0)
PY
