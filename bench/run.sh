#!/bin/sh
# bench/run.sh - `make bench`: runs every benchmark binary and script and prints
# their figures. Benchmarks read the large data from ../shared/data when it is
# there and say so when it is not. Nothing here is a pass/fail test.
BUILD=${BUILD:-build}
SHARED=${PORTRAY_SHARED:-../shared/data}
if [ -d "$SHARED" ]; then
	echo "# data: $SHARED"
else
	echo "# data: $SHARED not found: benchmarks that need the large meshes are skipped"
fi
export PORTRAY_SHARED="$SHARED"
for b in "$BUILD"/bench/bench_*; do
	[ -x "$b" ] || continue
	echo "== $(basename "$b")"
	"$b" || echo "(failed: exit $?)"
done
for s in bench/*.sh; do
	[ "$s" = bench/run.sh ] && continue
	[ -f "$s" ] || continue
	echo "== $(basename "$s")"
	BUILD="$BUILD" sh "$s" || echo "(failed: exit $?)"
done
