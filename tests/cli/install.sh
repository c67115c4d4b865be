#!/bin/sh
# install.sh - `make install DESTDIR=D PREFIX=/usr` puts every file in place
# (binaries 755, the rest 644, nothing else), the units name the installed
# binary, the installed binaries run, `man -l` renders each page without a
# warning (that part skipped when man is absent), and `make uninstall`
# leaves no file behind.
. tests/cli/install_lib.inc
D=$TMP/root
make_install DESTDIR="$D" PREFIX=/usr >"$TMP/install.log" 2>&1 || fail "make install: $(cat "$TMP/install.log")"

expected_files | sort >"$TMP/want"
(cd "$D" && find . ! -type d | sed 's|^\./||' | sort) >"$TMP/got"
cmp -s "$TMP/want" "$TMP/got" || fail "installed files differ from the list (< missing, > extra):
$(diff "$TMP/want" "$TMP/got" | grep '^[<>]')"
while read -r f; do
	mode=$(ls -l "$D/$f" | cut -c1-10)
	case "$f" in
	usr/bin/*) want=-rwxr-xr-x ;;
	*) want=-rw-r--r-- ;;
	esac
	[ "$mode" = "$want" ] || fail "$f: mode $mode, want $want"
done <"$TMP/want"
echo "ok   $(wc -l <"$TMP/want") files in place"

# the units name /usr/bin/portray-worker; no @BINDIR@ is left anywhere
U=$D/usr/lib/systemd/system
grep -q '^ExecStart=/usr/bin/portray-worker --listen ' "$U/portray-worker.service" || fail "portray-worker.service: ExecStart"
grep -q '^ExecStart=/usr/bin/portray-worker --connect %i ' "$U/portray-worker@.service" || fail "portray-worker@.service: ExecStart"
grep -rl '@BINDIR@' "$D" && fail "@BINDIR@ left in the files above"
"$D/usr/bin/portray-master" --version >/dev/null || fail "installed portray-master --version"
"$D/usr/bin/portray-worker" --version >/dev/null || fail "installed portray-worker --version"

# PREFIX and the directory variables
make_install DESTDIR="$TMP/r2" PREFIX=/opt/portray SYSTEMDDIR=/etc/systemd/system >/dev/null 2>&1 || fail "install PREFIX=/opt/portray"
[ -x "$TMP/r2/opt/portray/bin/portray-worker" ] || fail "PREFIX=/opt/portray: no bin/portray-worker"
grep -q '^ExecStart=/opt/portray/bin/portray-worker ' "$TMP/r2/etc/systemd/system/portray-worker.service" ||
	fail "SYSTEMDDIR=/etc/systemd/system: the unit is not there, or names another binary"
[ -f "$TMP/r2/opt/portray/share/man/man5/portray.5" ] || fail "PREFIX=/opt/portray: no man5/portray.5"

# man -l renders each installed page, nothing on stderr
if command -v man >/dev/null 2>&1; then
	for p in man1/portray-master.1 man1/portray-worker.1 man5/portray.5; do
		MANWIDTH=80 man -l "$D/usr/share/man/$p" >"$TMP/page" 2>"$TMP/err" || fail "man -l $p: exit $?"
		[ -s "$TMP/err" ] && fail "man -l $p warns: $(cat "$TMP/err")"
		grep -q '^NAME' "$TMP/page" || fail "man -l $p: no NAME section in the output"
		echo "ok   man -l $p: $(wc -l <"$TMP/page") lines, no warnings"
	done
else
	echo "note: man not installed: the pages were not rendered (man_lint.sh lints them with groff)"
fi

# uninstall: no file or link left, and the doc directory gone
pmake uninstall DESTDIR="$D" PREFIX=/usr >"$TMP/uninstall.log" 2>&1 || fail "make uninstall: $(cat "$TMP/uninstall.log")"
left=$(cd "$D" && find . ! -type d)
[ -z "$left" ] || fail "make uninstall left: $left"
[ -d "$D/usr/share/doc/portray" ] && fail "make uninstall left the directory usr/share/doc/portray"
echo "ok   make uninstall left no file"
echo ok
