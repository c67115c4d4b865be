#!/bin/sh
# systemd_verify.sh - the systemd units as `make install` writes them pass
# `systemd-analyze verify` without a word: portray-worker.service, and the
# template portray-worker@.service as the instance
# portray-worker@render-master:7412.service, whose worker must dial
# exactly render-master:7412 (%i is the instance name unescaped). Their
# hardening is held to an exposure of at most 2.0 by `systemd-analyze
# security --offline=yes` (systemd 250 and later). Skipped (exit 77) when
# systemd-analyze is absent.
if ! command -v systemd-analyze >/dev/null 2>&1; then
	echo "systemd-analyze not installed"
	exit 77
fi
. tests/cli/install_lib.inc
case "$TMP" in *:*) echo "TMPDIR contains ':' (systemd-analyze reads it as FILE:ALIAS)"; exit 77 ;; esac
# installed under a real prefix (no DESTDIR), so that ExecStart names a binary
# that exists and the man pages of Documentation= are found through MANPATH
P=$TMP/usr
make_install PREFIX="$P" >"$TMP/install.log" 2>&1 || fail "make install: $(cat "$TMP/install.log")"
U=$P/lib/systemd/system
export MANPATH="$P/share/man"
sysv=$(systemd-analyze --version | sed -n '1s/^systemd \([0-9]*\).*/\1/p')
echo "systemd $sysv"

# verify UNIT-ARG: exit 0 and nothing printed
verify() {
	systemd-analyze verify "$1" >"$TMP/v.out" 2>&1
	rc=$?
	cat "$TMP/v.out"
	[ $rc -eq 0 ] || fail "systemd-analyze verify $1: exit $rc"
	[ -s "$TMP/v.out" ] && fail "systemd-analyze verify $1 printed the lines above"
	echo "ok   systemd-analyze verify ${1##*/}: nothing to say"
}

verify "$U/portray-worker.service"
verify "$U/portray-worker@.service"
if [ "${sysv:-0}" -ge 250 ]; then
	# FILE:NAME verifies FILE loaded as NAME (systemd 250): an instance
	inst=portray-worker@render-master:7412.service
	verify "$U/portray-worker@.service:$inst"
	SYSTEMD_LOG_LEVEL=debug systemd-analyze verify "$U/portray-worker@.service:$inst" >"$TMP/dbg" 2>&1
	if grep -q 'Command Line:' "$TMP/dbg"; then
		grep -q "Command Line: $P/bin/portray-worker --connect render-master:7412 " "$TMP/dbg" ||
			fail "$inst does not dial render-master:7412: $(grep 'Command Line:' "$TMP/dbg")"
		echo "ok   $inst runs: $(grep -m 1 'Command Line:' "$TMP/dbg" | sed 's/^[[:space:]]*//')"
	else
		echo "note: this systemd-analyze does not print the command line: the instance's --connect not checked"
	fi
	for u in portray-worker.service "portray-worker@.service:$inst"; do
		systemd-analyze security --offline=yes --no-pager --threshold=20 "$U/$u" >"$TMP/sec" 2>&1 ||
			fail "systemd-analyze security $u: exposure above 2.0: $(grep -v '✓' "$TMP/sec")"
		echo "ok   $(tail -n 1 "$TMP/sec" | sed 's/^[^O]*Overall/Overall/' | tr -cd '\40-\176')"
	done
else
	echo "note: systemd $sysv (< 250): no FILE:NAME verify and no offline security: instance and exposure not checked"
fi
echo ok
