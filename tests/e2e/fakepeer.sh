#!/bin/sh
# The fake peers (tests/tools/fakepeer.c) against today's master and worker:
#  - every `fakepeer worker` mode starts, gets as far as the stage it stalls
#    at (its log says what it received: the master's HELLO, AUTH, the offer
#    (sent only after the master checked the fake's HELLO and proof), the
#    whole scene with the right hash, tiles), and a master with local threads
#    finishes the render anyway, identical to the local one; `wrong-type`
#    (results in the other pixel type) is dropped for it, both ways;
#  - with --no-local, the stalls the master already has a deadline for:
#    `silent` (no frame: heartbeat timeout) and `stall-tile` (the hung-tile
#    deadline) end with exit 69. The other modes make today's master wait
#    for ever with --no-local: farm_deadlines.sh holds those expectations;
#  - `fakepeer hold` keeps idle connections open on a real worker, which
#    drops them at its handshake deadline; they are opened again, and a real
#    master still renders through that worker meanwhile;
#  - both kinds exit 0 on SIGTERM.
. "$(dirname "$0")/farm_lib.inc"
printf 'correct horse battery staple\n' >"$T/secret"
chmod 600 "$T/secret"
local_render "$SLOW" "$T/local.ppm" --size 192x144

# MODE  PATTERN (one word: '.' for spaces) [fakepeer options]; the master
# gets --secret-file when the fake has a secret
while read -r mode pattern opts; do
	[ -n "$mode" ] || continue
	fk=$(echo "$mode" | tr -d -)
	# shellcheck disable=SC2086
	start_fake "$fk" "$mode" $opts
	msec=""
	case "$opts" in *secret*) msec="--secret-file $T/secret" ;; esac
	eval "port=\$${fk}_PORT"
	# shellcheck disable=SC2086
	timeout 60 "$BIN/portray-master" "$SLOW" --size 192x144 --tile 16 -j 1 --heartbeat-timeout 1 $msec \
		-o "$T/$fk.ppm" -w "127.0.0.1:$port" 2>"$T/m_$fk.log" || fail "$mode: the render failed (exit $?)"
	cmp "$T/local.ppm" "$T/$fk.ppm" || fail "$mode: the image differs from the local render"
	wait_for "$T/$fk.log" "$pattern" "$mode to log '$pattern'" 10
	grep -q "authentication failed" "$T/m_$fk.log" "$T/$fk.log" && fail "$mode: the fake's AUTH is wrong"
	echo "ok   $mode: $(grep -m 1 "$pattern" "$T/$fk.log" | sed 's/^fakepeer worker [0-9.]* //')"
done <<MODES
silent          received.HELLO
heartbeat-only  received.HELLO
stall-hello     received.SCENE_OFFER
stall-auth      received.AUTH                 --secret
stall-offer     received.SCENE_OFFER          --secret-file $T/secret
stall-data      sent.SCENE_NEED;.not.reading
stall-build     scene.complete:.*hash.ok
stall-tile      received.TILE
wrong-type      answered.TILE.[0-9]*.with.RGBF32.pixels
MODES

# a result in the other pixel type than its TILE asked for is a protocol
# error (whatever its checksum): 8-bit asked, floats answered, and back
grep -q "worker 127.0.0.1:$wrongtype_PORT dropped: tile [0-9]* came back with pixel type 1, sent with 0" \
	"$T/m_wrongtype.log" || fail "wrong-type: floats for an 8-bit tile not refused: $(cat "$T/m_wrongtype.log")"
local_render "$SLOW" "$T/local.pfm" --size 192x144
timeout 60 "$BIN/portray-master" "$SLOW" --size 192x144 --tile 16 -j 1 -o "$T/wrongtype.pfm" \
	-w "127.0.0.1:$wrongtype_PORT" 2>"$T/m_wrongtype2.log" || fail "wrong-type, PFM: the render failed (exit $?)"
cmp "$T/local.pfm" "$T/wrongtype.pfm" || fail "wrong-type, PFM: the image differs from the local render"
grep -q "worker 127.0.0.1:$wrongtype_PORT dropped: tile [0-9]* came back with pixel type 0, sent with 1" \
	"$T/m_wrongtype2.log" || fail "wrong-type: 8-bit pixels for a float tile not refused"
echo "ok   wrong-type: refused both ways"

# --no-local: the deadlines today's master has
timeout 60 "$BIN/portray-master" "$SCENE" -o "$T/x.ppm" --no-local --heartbeat-timeout 0.5 \
	-w "127.0.0.1:$silent_PORT" 2>"$T/m_silent2.log"
rc=$?
[ $rc -eq 69 ] || fail "silent, --no-local: exit $rc, expected 69"
grep -q "worker 127.0.0.1:$silent_PORT dropped" "$T/m_silent2.log" || fail "silent: not reported dropped"
timeout 60 "$BIN/portray-master" "$SCENE" -o "$T/x.ppm" --no-local --heartbeat-timeout 0.5 \
	-w "127.0.0.1:$stalltile_PORT" 2>"$T/m_tile2.log"
rc=$?
[ $rc -eq 69 ] || fail "stall-tile, --no-local: exit $rc, expected 69"
grep -q "worker 127.0.0.1:$stalltile_PORT dropped" "$T/m_tile2.log" || fail "stall-tile: not reported dropped"
echo "ok   --no-local: silent and stall-tile end with exit 69"

# a fake worker ends cleanly on SIGTERM
kill -TERM "$stalltile_PID"
wait "$stalltile_PID" || fail "fakepeer worker: exit $? on SIGTERM"

# hold: 8 idle connections on a worker with a 300 ms handshake deadline
start_worker w -j 1 --test-handshake-ms 300
"$TOOLS/fakepeer" hold --to "127.0.0.1:$w_PORT" --count 8 --port-file-ready "$T/hold.ready" 2>"$T/hold.log" &
HOLD=$!
PIDS="$PIDS $HOLD"
wait_for "$T/hold.ready" "^8$" "hold to open its 8 connections" 10
wait_count "$T/w.log" "refused: .*(timeout error)" 8 "the worker to drop the 8 idle connections"
wait_count "$T/hold.log" "worker says: .*(timeout); again in" 8 "hold to open them again"
"$BIN/portray-master" "$SLOW" --size 192x144 --tile 16 --no-local -o "$T/held.ppm" -w "127.0.0.1:$w_PORT" \
	2>"$T/m_held.log" || fail "render through a worker with idle connections failed (exit $?)"
cmp "$T/local.ppm" "$T/held.ppm" || fail "image differs through a worker with idle connections"
kill -TERM $HOLD
wait $HOLD || fail "fakepeer hold: exit $? on SIGTERM"
echo "ok   hold: $(grep -c 'again in' "$T/hold.log") reconnections; a master rendered meanwhile"

# a flood of idle connections against a worker that makes room for real
# masters: tests/e2e/farm_flood.sh
