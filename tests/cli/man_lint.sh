#!/bin/sh
# man_lint.sh - the man pages (docs/man/*) format without a single warning:
# `groff -ww -man` (every warning on) and `mandoc -T lint`, each where it is
# installed; skipped (exit 77) when neither is.
PAGES="docs/man/portray-master.1 docs/man/portray-worker.1 docs/man/portray.5"
TMP=$(mktemp -d "${TMPDIR:-/tmp}/portray-man.XXXXXX") || exit 1
trap 'rm -rf "$TMP"' EXIT
fail() {
	echo "FAIL: $*"
	exit 1
}
ran=""
if command -v groff >/dev/null 2>&1; then
	for p in $PAGES; do
		groff -ww -man -Tutf8 "$p" >"$TMP/out" 2>"$TMP/err" || fail "groff $p: exit $?: $(cat "$TMP/err")"
		[ -s "$TMP/err" ] && fail "groff -ww $p warns:
$(cat "$TMP/err")"
		[ -s "$TMP/out" ] || fail "groff $p: no output"
	done
	echo "ok   groff -ww -man: no warnings ($(groff --version | head -n 1))"
	ran="$ran groff"
fi
if command -v mandoc >/dev/null 2>&1; then
	for p in $PAGES; do
		# -W warning: warnings and worse; style hints are not failures
		mandoc -T lint -W warning "$p" >"$TMP/err" 2>&1 || fail "mandoc -T lint $p:
$(cat "$TMP/err")"
		[ -s "$TMP/err" ] && fail "mandoc -T lint $p:
$(cat "$TMP/err")"
	done
	echo "ok   mandoc -T lint: no warnings"
	ran="$ran mandoc"
fi
if [ -z "$ran" ]; then
	echo "neither groff nor mandoc is installed"
	exit 77
fi
echo ok
