#!/bin/sh
# systemd_syscalls.sh - the worker lives inside its unit's sandbox: every
# system call it makes through jobs, a refused master and SIGTERM is one that
# deploy/systemd/portray-worker.service's SystemCallFilter= allows (and the
# template portray-worker@.service's, the same), and every
# socket it opens is of a family RestrictAddressFamilies= allows. (Under
# systemd a call outside the filter fails with EPERM: the worker would break
# in ways no other test sees.) The calls are recorded with strace; a
# dialling worker (--connect) is traced too when the binaries have
# --connect and --accept. Skipped (exit 77) without strace or
# systemd-analyze, or where ptrace is not permitted.
for c in strace systemd-analyze; do
	if ! command -v $c >/dev/null 2>&1; then
		echo "$c not installed"
		exit 77
	fi
done
if ! strace -f -qq -o /dev/null true 2>/dev/null; then
	echo "strace cannot trace here (ptrace not permitted)"
	exit 77
fi
. tests/cli/install_lib.inc
UNIT=deploy/systemd/portray-worker.service
M=bin/portray-master
W=bin/portray-worker

# expand GROUP|NAME: the system calls of a systemd group, one a line
expand() {
	case "$1" in
	@*)
		systemd-analyze syscall-filter "$1" | sed -e 1d -e 's/^[[:space:]]*//' -e '/^#/d' -e '/^$/d' |
			while read -r s; do expand "$s"; done
		;;
	*) echo "$1" ;;
	esac
}
# the unit's filter: the allow lists' calls, less the deny lists' (~) calls
: >"$TMP/allow"
: >"$TMP/deny"
sed -n 's/^SystemCallFilter=//p' "$UNIT" >"$TMP/filter"
[ -s "$TMP/filter" ] || fail "$UNIT has no SystemCallFilter="
while read -r line; do
	case "$line" in
	"~"*) list=deny line=${line#\~} ;;
	*) list=allow ;;
	esac
	for g in $line; do expand "$g"; done >>"$TMP/$list"
done <"$TMP/filter"
sort -u "$TMP/allow" >"$TMP/a"
sort -u "$TMP/deny" >"$TMP/d"
comm -23 "$TMP/a" "$TMP/d" >"$TMP/allowed"
[ -s "$TMP/allowed" ] || fail "could not expand the filter of $UNIT"
families=$(sed -n 's/^RestrictAddressFamilies=//p' "$UNIT")
[ -n "$families" ] || fail "$UNIT has no RestrictAddressFamilies="
echo "filter: $(wc -l <"$TMP/allowed") calls allowed; families: $families"
# the template (portray-worker@.service) has the same sandbox
for k in SystemCallFilter RestrictAddressFamilies; do
	[ "$(grep "^$k=" "$UNIT")" = "$(grep "^$k=" deploy/systemd/portray-worker@.service)" ] ||
		fail "portray-worker@.service's $k= differs from $UNIT's"
done

# wait_file FILE PID WHAT: until FILE is not empty (30 s)
wait_file() {
	i=0
	while [ ! -s "$1" ]; do
		i=$((i + 1))
		[ $i -gt 600 ] && fail "$3 did not start within 30 s"
		kill -0 "$2" 2>/dev/null || fail "$3 exited at start"
		sleep 0.05
	done
}
# traced_worker NAME ARGS...: starts the worker under strace, trace in
# $TMP/NAME.trace; sets SPID (strace) and WPID (the worker)
traced_worker() {
	n=$1
	shift
	strace -f -qq -o "$TMP/$n.trace" "$W" "$@" 2>"$TMP/$n.log" &
	SPID=$!
	i=0
	until WPID=$(sed -n '1s/^\([0-9][0-9]*\) .*/\1/p' "$TMP/$n.trace" 2>/dev/null) && [ -n "$WPID" ]; do
		i=$((i + 1))
		[ $i -gt 600 ] && fail "strace did not start the worker"
		sleep 0.05
	done
}
# stop_worker: SIGTERM to the worker; it must end with 0
stop_worker() {
	kill -TERM "$WPID"
	wait "$SPID"
	i=0
	while kill -0 "$WPID" 2>/dev/null; do
		i=$((i + 1))
		[ $i -gt 200 ] && fail "worker $WPID did not end on SIGTERM"
		sleep 0.05
	done
}

head -c 32 /dev/urandom >"$TMP/secret"
head -c 32 /dev/urandom >"$TMP/wrong"
chmod 600 "$TMP/secret" "$TMP/wrong"
cp tests/e2e/farm_scene.sce tests/e2e/farm_tri.raw "$TMP/"
S=$TMP/farm_scene.sce

# a listening worker: two jobs (scene cache miss, then hit), a wrong secret
traced_worker listen --listen 127.0.0.1:0 --port-file "$TMP/w.port" --secret-file "$TMP/secret" -j 2
wait_file "$TMP/w.port" "$WPID" "the traced worker"
P=$(cat "$TMP/w.port")
for i in 1 2; do
	"$M" "$S" -o "$TMP/out.ppm" -q --no-local -w "127.0.0.1:$P" --secret-file "$TMP/secret" ||
		fail "job $i through the traced worker failed"
done
"$M" "$S" -o "$TMP/out.ppm" -q --no-local -w "127.0.0.1:$P" --secret-file "$TMP/wrong" 2>/dev/null
[ $? -eq 69 ] || fail "a wrong secret was not refused"
i=0
until grep -q "refused: authentication failed" "$TMP/listen.log"; do
	i=$((i + 1))
	[ $i -gt 600 ] && fail "the worker did not log the refusal"
	sleep 0.05
done
stop_worker
traces=$TMP/listen.trace

# a dialling worker, when the binaries have it
if "$W" --help | grep -q -- '--connect' && "$M" --help | grep -q -- '--accept'; then
	timeout 60 "$M" "$S" -o "$TMP/dial.ppm" -q --no-local --accept 127.0.0.1:0 --port-file "$TMP/m.port" \
		--secret-file "$TMP/secret" 2>"$TMP/m.log" &
	MPID=$!
	wait_file "$TMP/m.port" "$MPID" "the accepting master"
	traced_worker dial --connect "localhost:$(cat "$TMP/m.port")" --secret-file "$TMP/secret" -j 2
	wait "$MPID" || fail "the accepting master failed: $(cat "$TMP/m.log")"
	sleep 0.5 # the worker dials again: those calls count too
	stop_worker
	traces="$traces $TMP/dial.trace"
	echo "ok   a dialling worker traced too"
else
	echo "note: no --connect/--accept in these binaries: only a listening worker traced"
fi

# every call made, against the filter ($traces: one or two files)
# shellcheck disable=SC2086
sed -n -e 's/^[0-9][0-9]* *\([a-z_0-9][a-z_0-9]*\)(.*/\1/p' \
	-e 's/^[0-9][0-9]* *<\.\.\. \([a-z_0-9][a-z_0-9]*\) resumed>.*/\1/p' $traces | sort -u >"$TMP/used"
[ -s "$TMP/used" ] || fail "no system calls in the trace"
bad=$(comm -23 "$TMP/used" "$TMP/allowed" | tr '\n' ' ')
[ -z "$bad" ] || fail "$UNIT's SystemCallFilter= refuses calls the worker makes: $bad"
echo "ok   all $(wc -l <"$TMP/used") system calls the worker made are allowed: $(tr '\n' ' ' <"$TMP/used")"
# shellcheck disable=SC2086
fams=$(sed -n 's/^[0-9][0-9]* *socket(\(AF_[A-Z0-9]*\),.*/\1/p' $traces | sort -u | tr '\n' ' ')
for f in $fams; do
	case " $families " in
	*" $f "*) ;;
	*)
		# glibc's getaddrinfo (AI_ADDRCONFIG) asks the kernel for the host's
		# addresses over netlink; refused, it assumes both families: harmless
		[ "$f" = AF_NETLINK ] || fail "the worker opens $f sockets; $UNIT allows $families"
		;;
	esac
done
echo "ok   socket families used: $fams"
echo ok
