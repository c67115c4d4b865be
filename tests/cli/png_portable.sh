#!/bin/sh
# png_portable.sh - the PNG encoder built without its SSE2 and word-at-a-time
# paths (-DIMG_PORTABLE, as on a CPU or compiler that has neither) makes
# the same bytes: test_img_bytes, compiled here against that encoder, checks
# the recorded lengths and CRC-32s and the row filters. Skipped (77) when no
# C compiler ($CC, default cc) is found.
CC=${CC:-cc}
if ! command -v "$CC" >/dev/null 2>&1; then
	echo "no C compiler ($CC)"
	exit 77
fi
dir=$(mktemp -d "${TMPDIR:-/tmp}/png_portable.XXXXXX") || exit 1
trap 'rm -rf "$dir"' EXIT
$CC -std=c11 -D_POSIX_C_SOURCE=200809L -D_DEFAULT_SOURCE -DIMG_PORTABLE -O2 -I. -o "$dir/test_img_bytes" \
	tests/unit/test_img_bytes.c common/img_png.c common/img.c common/img_float.c common/crc32.c common/xmath.c \
	-lm -pthread || exit 1
"$dir/test_img_bytes"
