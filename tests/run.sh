#!/bin/sh
# tests/run.sh - runs every test, each in its own process with a time limit,
# and ends with the line "N passed, N failed, N skipped".
#   unit tests      $BUILD/tests/test_*             (tests/unit/test_*.c)
#   fuzz replays    $BUILD/tests/fuzz_*-replay over tests/fuzz/corpus/fuzz_*/
#   error cases     tests/errors/*.sce: first line "// expect: LEVEL MESSAGE-SUBSTRING"
#   scripts         tests/cli/*.sh, tests/e2e/*.sh and tests/deploy/*.sh (deploy:
#                   a real Slurm; skipped when it is not installed)
# Exit status of a test: 0 passed; 77 skipped (it could not check anything
# here, e.g. a tool it needs is missing: the last line of its output says
# why); anything else failed. Skips do not fail the run.
# TEST_FILTER=substring runs only matching tests.
# PORTRAY_TEST_FULL=1 runs the long variants: test_bvh traces 100,000 rays per
# scene (about 10 s on 2 cores) instead of 10,000 (about 1 s).
BUILD=${BUILD:-build}
T=${TEST_TIMEOUT:-300}
ROOT=$(pwd)
OUT=$ROOT/tests/out
mkdir -p "$OUT"
pass=0
fail=0
skip=0
failed_names=""

run() { # name, command...
	name=$1
	shift
	case "$name" in *"${TEST_FILTER:-}"*) ;; *) return ;; esac
	log="$OUT/$(echo "$name" | tr '/ ' '__').log"
	start=$(date +%s)
	timeout -k 5 "$T" "$@" >"$log" 2>&1
	rc=$?
	if [ $rc -eq 0 ]; then
		pass=$((pass + 1))
		printf 'PASS %-50s %3ss\n' "$name" $(($(date +%s) - start))
	elif [ $rc -eq 77 ]; then
		skip=$((skip + 1))
		printf 'SKIP %-50s (reason: %s)\n' "$name" "$(tail -n 1 "$log")"
	else
		fail=$((fail + 1))
		failed_names="$failed_names $name"
		printf 'FAIL %-50s (exit %s, log %s)\n' "$name" "$rc" "$log"
		tail -n 15 "$log" | sed 's/^/     | /'
	fi
}

for t in "$BUILD"/tests/test_*; do
	[ -x "$t" ] || continue
	run "unit/$(basename "$t")" "$t"
done

for r in "$BUILD"/tests/fuzz_*-replay; do
	[ -x "$r" ] || continue
	n=$(basename "$r" -replay)
	[ -d "tests/fuzz/corpus/$n" ] || continue
	run "fuzz-replay/$n" "$r" "tests/fuzz/corpus/$n"
done

for e in tests/errors/*.sce; do
	[ -f "$e" ] || continue
	run "errors/$(basename "$e")" sh tests/check_error.sh "$e"
done

for s in tests/cli/*.sh tests/e2e/*.sh tests/deploy/*.sh; do
	[ -f "$s" ] || continue
	run "$(basename "$(dirname "$s")")/$(basename "$s")" env BUILD="$BUILD" sh "$s"
done

[ -n "$failed_names" ] && echo "failed:$failed_names"
echo "$pass passed, $fail failed, $skip skipped"
[ "$fail" -eq 0 ]
