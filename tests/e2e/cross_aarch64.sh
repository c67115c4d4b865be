#!/bin/sh
# An aarch64 worker (cross-compiled, run under qemu-aarch64) serves this
# x86-64 master on 127.0.0.1: its probe matches and the images are
# byte-identical to local renders (small scenes: qemu is slow), and xmath
# gives the same bits on both CPUs over 2^20 arguments per function. Skips
# without qemu-aarch64 or until `make test-cross` has built the worker.
. "$(dirname "$0")/farm_lib.inc"
. "$(dirname "$0")/cross_lib.inc"
command -v qemu-aarch64 >/dev/null 2>&1 || { echo "no qemu-aarch64 (qemu-user)"; exit 77; }
need_build aarch64
[ "$(cat "$CROSS/aarch64/status")" = built ] || fail "the aarch64 build did not compile"
export QEMU_LD_PREFIX=${QEMU_LD_PREFIX:-/usr/aarch64-linux-gnu}
file "$CROSS/aarch64/bin/portray-worker" 2>/dev/null | grep -q aarch64 || [ ! -x /usr/bin/file ] ||
	fail "the worker is not an aarch64 binary"
start_xworker a qemu-aarch64 "$CROSS/aarch64/bin/portray-worker"
wait_for "$T/a.log" "listening on .*probe-" "the aarch64 worker to start"
same_images "$a_PORT" farm "$SCENE" --size 64x48
i=0
for s in glass tir_slab light_sphere light_cylinder light_box filter_lens filter_disk shader_turb3d shader_bumpy \
	shader_noise fall_off point_specular; do
	i=$((i + 1))
	same_images "$a_PORT" g$i "tests/golden/scenes/$s.sce" --size 32x24
done
same_images "$a_PORT" spd tests/data/spd/tetra_s4.sce --size 48x36
same_images "$a_PORT" mesh tests/data/meshes/spot.sce --size 48x36
"$BUILD/tools/xmath_hash" >"$T/xm.x86" && qemu-aarch64 "$CROSS/aarch64/tools/xmath_hash" >"$T/xm.arm" ||
	fail "xmath_hash failed"
cmp -s "$T/xm.x86" "$T/xm.arm" || { diff "$T/xm.x86" "$T/xm.arm"; fail "xmath differs on aarch64"; }
echo "ok   xmath: the same bits on x86-64 and aarch64 over $(awk '{ n += $2 } END { print n }' "$T/xm.x86") calls"
echo ok
