#!/bin/sh
# man_options.sh - the man pages keep up with the programs: every option that
# `portray-master --help` or `portray-worker --help` lists is described in
# its page (docs/man/*.1), and the example scene in portray(5) parses
# (`portray-master --check`). Needs only sh, sed and grep.
M=bin/portray-master
W=bin/portray-worker
TMP=$(mktemp -d "${TMPDIR:-/tmp}/portray-man.XXXXXX") || exit 1
trap 'rm -rf "$TMP"' EXIT
fail() {
	echo "FAIL: $*"
	exit 1
}

# page_text PAGE: the page's source with roff's \- and font escapes undone
page_text() {
	sed -e 's/\\-/-/g' -e 's/\\f[BIRP]//g' -e 's/\\&//g' "$1"
}

# options PROGRAM: the long options its --help lists (those that begin an
# item: "  -x, --opt" or "      --opt", not ones named inside a description), one a line
options() {
	"$1" --help | sed -n 's/^ *\(-[a-zA-Z], \)\{0,1\}\(--[a-z][a-z-]*\).*/\2/p' | sort -u
}

for prog in portray-master portray-worker; do
	page=docs/man/$prog.1
	# the items' heads: the line after each .TP
	page_text "$page" | awk '/^\.TP/ { if ((getline l) > 0) print l }' >"$TMP/heads"
	options "bin/$prog" >"$TMP/opts" || fail "$prog --help"
	[ -s "$TMP/opts" ] || fail "$prog --help lists no options"
	n=0
	while read -r o; do
		grep -q -- "$o\([^a-z-]\|\$\)" "$TMP/heads" || fail "$page has no item for $o ($prog --help lists it)"
		n=$((n + 1))
	done <"$TMP/opts"
	echo "ok   $page has an item for each of the $n options of $prog --help"
done

# the example in portray(5) is a scene that parses
sed -n '/^\.SH EXAMPLE/,/^\.fi/p' docs/man/portray.5 | sed -e '1,2d' -e '$d' | sed 's/\\-/-/g' >"$TMP/example.sce"
[ -s "$TMP/example.sce" ] || fail "no example in portray.5"
"$M" --check "$TMP/example.sce" >"$TMP/check" 2>&1 || fail "the example in portray.5 does not parse: $(cat "$TMP/check")"
echo "ok   the example in portray.5 parses: $(grep '^objects:' "$TMP/check")"
# the worker's page and --help agree on the default address
"$W" --help | grep -q '127.0.0.1:7411' || fail "portray-worker --help: default address changed?"
grep -q '127.0.0.1:7411' docs/man/portray-worker.1 || fail "portray-worker.1: no default address"
echo ok
