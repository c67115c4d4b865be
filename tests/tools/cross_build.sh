#!/bin/sh
# tests/tools/cross_build.sh DIR - the other builds `make test-cross` tests
# (tests/e2e/cross_*.sh), each a worker (and the xmath_hash tool) under
# DIR/NAME, with its outcome in DIR/NAME/status ("built", "refused" when the
# compiler stopped it on purpose, "failed", or "skipped: why") and a checksum
# of the sources in DIR/NAME/sources:
#   clang     CC=clang
#   fastmath  CFLAGS adding -ffast-math (must not compile: common/xmath.h)
#   contract  CFLAGS adding -mfma -ffp-contract=fast: compiles, changes values
#             (fused multiply-adds), must be refused by the pixel probe
#   aarch64   CC=aarch64-linux-gnu-gcc, run under qemu-aarch64
# MAKE, the flags and the jobs can be overridden: MAKE=make JOBS=-j2.
set -u
DIR=${1:-build/cross}
MAKE=${MAKE:-make}
JOBS=${JOBS:--j2}
OPT=${OPT:--O3}

have() { command -v "$1" >/dev/null 2>&1; }
# the sources a worker is built from: tests/e2e/cross_lib.inc skips a build older than them
sources() { cat common/*.[ch] proto/*.[ch] worker/*.[ch] tests/tools/xmath_hash.c Makefile | cksum; }

# variant NAME [make variables...]: builds NAME's worker and xmath_hash
variant() {
	n=$1
	shift
	b=$DIR/$n
	mkdir -p "$b/bin"
	if $MAKE $JOBS "$@" BUILD="$b" MASTER_BIN="$b/bin/portray-master" WORKER_BIN="$b/bin/portray-worker" \
		"$b/bin/portray-worker" "$b/tools/xmath_hash" >"$b/build.log" 2>&1; then
		echo built >"$b/status"
	elif grep -q 'error: #error "portray must not be built with' "$b/build.log"; then
		echo refused >"$b/status"
	else
		echo failed >"$b/status"
	fi
	sources >"$b/sources"
	echo "cross build $n: $(cat "$b/status") (log $b/build.log)"
}

skip() { # NAME WHY
	mkdir -p "$DIR/$1"
	echo "skipped: $2" >"$DIR/$1/status"
	echo "cross build $1: skipped: $2"
}

if have clang; then variant clang CC=clang; else skip clang "no clang"; fi
variant fastmath CFLAGS="$OPT -g -ffast-math"
if grep -qw fma /proc/cpuinfo 2>/dev/null; then
	variant contract CFLAGS="$OPT -g -mfma -ffp-contract=fast"
else
	skip contract "this CPU has no FMA instructions"
fi
if have aarch64-linux-gnu-gcc && [ -d /usr/aarch64-linux-gnu/lib ]; then
	variant aarch64 CC=aarch64-linux-gnu-gcc AR=aarch64-linux-gnu-ar
else
	skip aarch64 "no aarch64-linux-gnu-gcc or libc6-dev-arm64-cross"
fi
exit 0
