#!/bin/sh
# check_error.sh FILE.sce - runs `portray-master --check` on an error case.
# The file's first line holds the expectation:
#   // expect: LEVEL file:line:col: error: message substring
# Optional second line "// camera: FILE" passes -c FILE (relative to tests/errors).
f=$1
dir=$(dirname "$f")
exp=$(head -n 1 "$f" | sed -n 's|^// expect: ||p')
[ -n "$exp" ] || { echo "no '// expect:' line in $f"; exit 1; }
level=${exp%% *}
msg=${exp#* }
cam=$(sed -n '2s|^// camera: ||p' "$f")
if [ -n "$cam" ]; then
	out=$(cd "$dir" && "$OLDPWD/bin/portray-master" --check -c "$cam" "$(basename "$f")" 2>&1)
else
	out=$(cd "$dir" && "$OLDPWD/bin/portray-master" --check "$(basename "$f")" 2>&1)
fi
rc=$?
echo "exit $rc (want $level)"
echo "$out"
[ "$rc" = "$level" ] || { echo "FAIL: exit code $rc, expected $level"; exit 1; }
printf '%s\n' "$out" | grep -F -- "$msg" >/dev/null || { echo "FAIL: message lacks: $msg"; exit 1; }
exit 0
