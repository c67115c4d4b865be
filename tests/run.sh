#!/bin/sh
# tests/run.sh - runs every test, each in its own process with a time limit,
# and ends with the line "N passed, N failed".
#   unit tests      $BUILD/tests/test_*             (tests/unit/test_*.c)
#   fuzz replays    $BUILD/tests/fuzz_*-replay over tests/fuzz/corpus/fuzz_*/
#   error cases     tests/errors/*.sce: first line "// expect: LEVEL MESSAGE-SUBSTRING"
#   scripts         tests/e2e/*.sh and tests/cli/*.sh (exit 0 = pass)
# TEST_FILTER=substring runs only matching tests.
BUILD=${BUILD:-build}
T=${TEST_TIMEOUT:-300}
ROOT=$(pwd)
OUT=$ROOT/tests/out
mkdir -p "$OUT"
pass=0
fail=0
failed_names=""

run() { # name, command...
	name=$1
	shift
	case "$name" in *"${TEST_FILTER:-}"*) ;; *) return ;; esac
	log="$OUT/$(echo "$name" | tr '/ ' '__').log"
	start=$(date +%s)
	if timeout -k 5 "$T" "$@" >"$log" 2>&1; then
		pass=$((pass + 1))
		printf 'PASS %-50s %3ss\n' "$name" $(($(date +%s) - start))
	else
		rc=$?
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

for s in tests/cli/*.sh tests/e2e/*.sh; do
	[ -f "$s" ] || continue
	run "$(basename "$(dirname "$s")")/$(basename "$s")" env BUILD="$BUILD" sh "$s"
done

[ -n "$failed_names" ] && echo "failed:$failed_names"
echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
