#!/bin/sh
# A clang-built worker serves this (gcc-built) master: its probe matches, so
# the handshake passes, and every image is byte-identical to the local
# render: the farm scene, every golden scene, the examples and the SPD and
# mesh scenes (smaller). Skips until `make test-cross` has built the worker.
. "$(dirname "$0")/farm_lib.inc"
. "$(dirname "$0")/cross_lib.inc"
need_build clang
[ "$(cat "$CROSS/clang/status")" = built ] || fail "the clang build did not compile"
start_xworker c "$CROSS/clang/bin/portray-worker"
same_images "$c_PORT" farm "$SCENE"
i=0
for s in tests/golden/scenes/*.sce; do
	i=$((i + 1))
	same_images "$c_PORT" g$i "$s"
done
for s in examples/exam_*.sce examples/bgammon.sce examples/dice.sce tests/data/spd/*.sce tests/data/meshes/*.sce; do
	i=$((i + 1))
	same_images "$c_PORT" x$i "$s" --size 160x120
done
# xmath itself, 2^20 arguments per function
"$BUILD/tools/xmath_hash" >"$T/xm.gcc" && "$CROSS/clang/tools/xmath_hash" >"$T/xm.clang" || fail "xmath_hash failed"
cmp -s "$T/xm.gcc" "$T/xm.clang" || { diff "$T/xm.gcc" "$T/xm.clang"; fail "xmath differs under clang"; }
echo "ok   xmath: the same bits from gcc and clang over $(awk '{ n += $2 } END { print n }' "$T/xm.gcc") calls"
echo ok
