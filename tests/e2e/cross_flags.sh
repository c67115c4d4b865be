#!/bin/sh
# Value-changing flags: a build with -ffast-math must not compile
# (common/xmath.h), and one that compiles but computes other values
# (-mfma -ffp-contract=fast: fused multiply-adds) must be refused at the
# handshake by the pixel probe, with a message that says so; if the
# -ffast-math build ever compiled, it must be refused the same way. Skips
# until `make test-cross` has tried the builds.
. "$(dirname "$0")/farm_lib.inc"
. "$(dirname "$0")/cross_lib.inc"
need_build fastmath

# refused_by_probe NAME: the worker of build NAME is refused by the probe
refused_by_probe() {
	start_xworker "$1" "$CROSS/$1/bin/portray-worker"
	"$BIN/portray-master" "$SCENE" -o "$T/$1.ppm" --no-local -w "127.0.0.1:$(eval echo "\$${1}_PORT")" \
		2>"$T/$1.master.log"
	rc=$?
	[ $rc -eq 69 ] || fail "$1: the master exited $rc, expected 69 (no worker)"
	grep -q "pixel probe mismatch: the worker's probe image hashes to" "$T/$1.master.log" ||
		fail "$1: no probe mismatch in the master's message"
	# the worker refuses the master's HELLO too, or hears the master's ERROR first
	wait_for "$T/$1.log" "\(refused\|peer says\): pixel probe mismatch" "the $1 worker's probe mismatch message"
	echo "ok   $1: refused: $(grep -o 'pixel probe mismatch[^(]*' "$T/$1.master.log" | head -n 1)"
}

case $(cat "$CROSS/fastmath/status") in
refused) echo "ok   fastmath: does not compile: $(grep -m 1 'error: #error' "$CROSS/fastmath/build.log" | sed 's/.*#error //')" ;;
built) refused_by_probe fastmath ;;
esac
st=$(cat "$CROSS/contract/status" 2>/dev/null)
case $st in
built) refused_by_probe contract ;;
refused) fail "-ffp-contract=fast was refused at compile time: pick another flag for this test" ;;
*) echo "contract: ${st:-not built}" ;;
esac
echo ok
