#!/bin/sh
# cputime.sh - build/tools/cputime, bench/povray.sh's timer: it passes the
# command's exit status through (128 + the signal when one ended it),
# ends with one "TIME user sys wall" line on stderr whose CPU time covers
# a busy command and is at most its wall-clock time, says 127 for a command
# that cannot be run and 64 for none.
BUILD=${BUILD:-build}
T=$BUILD/tools/cputime
fail=0
# shellcheck disable=SC2016 # the loop is the inner shell's
out=$("$T" sh -c 'i=0; while [ $i -lt 300000 ]; do i=$((i + 1)); done; exit 3' 2>&1)
rc=$?
[ "$rc" -eq 3 ] || { echo "FAIL: exit status $rc, not the command's 3"; fail=1; }
line=$(printf '%s\n' "$out" | tail -n 1)
if ! echo "$line" | awk 'NF == 4 && $1 == "TIME" && $2 + $3 > 0.01 && $2 + $3 <= $4 + 0.01 { ok = 1 } END { exit !ok }'; then
	echo "FAIL: busy command timed as '$line'"
	fail=1
fi
"$T" sh -c 'kill -TERM $$' 2>/dev/null
rc=$?
[ "$rc" -eq 143 ] || { echo "FAIL: a command ended by SIGTERM gave $rc, not 143"; fail=1; }
"$T" /nonexistent/portray-command 2>/dev/null
rc=$?
[ "$rc" -eq 127 ] || { echo "FAIL: a missing command gave $rc, not 127"; fail=1; }
"$T" 2>/dev/null
rc=$?
[ "$rc" -eq 64 ] || { echo "FAIL: no command gave $rc, not 64"; fail=1; }
[ "$fail" -eq 0 ] && echo "cputime: status, TIME line, signals, missing command: ok"
exit "$fail"
