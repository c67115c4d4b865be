#!/bin/sh
# farm_deadlines.sh - a worker that stalls at any stage of the handshake or
# the scene transfer while it keeps heartbeating (tests/tools/fakepeer.c)
# must not hold a --no-local master for ever: each stage needs a deadline of
# its own, since heartbeats alone prove only that the peer's loop runs.
# With --heartbeat-timeout 1 and the fake as the only worker, the master
# must end with exit 69 ("every worker is lost") and say that it dropped
# the worker, within 30 s (several attempts with back-off included).
#
# The deadlines (master/wconn.c): each handshake step and a stalled
# transfer 1 heartbeat timeout, a build 10 of them plus 20 x the master's own
# build; stalls at the handshake, offer, transfer and build drop the worker
# for good (a peer that accepted the connection and then does not follow the
# protocol is broken, not busy), and a HEARTBEAT before the handshake is a
# protocol error.
. "$(dirname "$0")/farm_lib.inc"
printf 'correct horse battery staple\n' >"$T/secret"
chmod 600 "$T/secret"
now() { date +%s.%N; }
# a scene whose encoding (about 30 MB) is larger than the socket buffers
# and the master's output high-water mark together: with stall-data the
# master is still sending it (W_SENDING) when the fake stops reading
awk 'BEGIN { for (i = 0; i < 300000; i++)
	printf "object sphere centre (%d %d -%d) radius 0.01 ; ;\n", i % 100, int(i / 100) % 100, 20 + int(i / 10000) }' \
	>"$T/spheres.inc"
cat "$SCENE" "$T/spheres.inc" >"$T/big.sce"

# MODE  SCENE  [fakepeer options]  (the master gets --secret-file when the fake has a secret)
while read -r mode scene opts; do
	[ -n "$mode" ] || continue
	fk=$(echo "$mode" | tr -d -)
	# shellcheck disable=SC2086
	start_fake "$fk" "$mode" $opts
	msec=""
	case "$opts" in *secret*) msec="--secret-file $T/secret" ;; esac
	eval "port=\$${fk}_PORT"
	t0=$(now)
	# shellcheck disable=SC2086
	timeout 40 "$BIN/portray-master" "$scene" -o "$T/x.ppm" --no-local --heartbeat-timeout 1 $msec \
		-w "127.0.0.1:$port" 2>"$T/m_$fk.log"
	rc=$?
	t1=$(now)
	el=$(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.1f", b - a }')
	[ $rc -eq 69 ] || fail "$mode: exit $rc after $el s, expected 69 (124: still waiting after 40 s)"
	grep -q "worker 127.0.0.1:$port dropped" "$T/m_$fk.log" || fail "$mode: the master did not say it dropped the worker"
	grep -q "every worker is lost" "$T/m_$fk.log" || fail "$mode: no word on why the render stopped"
	awk -v e="$el" 'BEGIN { exit !(e < 30) }' || fail "$mode: took $el s (bound 30 s)"
	echo "ok   $mode: exit 69 after $el s: $(grep -m 1 "dropped" "$T/m_$fk.log" | sed 's/^portray-master: //')"
done <<MODES
heartbeat-only  $SCENE
stall-hello     $SCENE
stall-auth      $SCENE        --secret
stall-offer     $SCENE        --secret-file $T/secret
stall-data      $T/big.sce
stall-build     $SCENE
MODES
echo ok
