#!/bin/sh
# A worker name that resolves to several addresses is several workers (as a
# Kubernetes headless Service gives): "farmpool" resolves to 127.0.0.1 and
# 127.0.0.2, a worker listens on each (same port), and `-w farmpool:PORT`
# renders on both. The name comes from a hosts file bind-mounted over
# /etc/hosts in a private mount namespace (unshare -m): no system file is
# edited. Skipped where that is not allowed (not root, no unshare).
. "$(dirname "$0")/farm_lib.inc"
command -v unshare >/dev/null || { echo "unshare(1) is missing"; exit 77; }
printf '127.0.0.1 farmpool\n127.0.0.2 farmpool\n' >"$T/hosts"
unshare -m sh -c "mount --bind '$T/hosts' /etc/hosts" 2>/dev/null ||
	{ echo "cannot bind-mount a hosts file in a private mount namespace (needs root)"; exit 77; }
start_worker one -j 1 --test-delay-ms 5
"$BIN/portray-worker" --listen "127.0.0.2:$one_PORT" -j 1 --test-delay-ms 5 2>"$T/two.log" &
PIDS="$PIDS $!"
wait_for "$T/two.log" "listening on 127.0.0.2" "the second worker to listen on 127.0.0.2"
local_render "$SLOW" "$T/local.ppm" --size 192x144
unshare -m sh -c "mount --bind '$T/hosts' /etc/hosts && exec '$BIN/portray-master' '$SLOW' --size 192x144 \
	--tile 16 -o '$T/farm.ppm' --no-local -w farmpool:$one_PORT" 2>"$T/m.log" ||
	fail "render on farmpool failed (exit $?)"
cmp "$T/local.ppm" "$T/farm.ppm" || fail "image differs"
grep -q "farmpool:$one_PORT/127.0.0.1 " "$T/m.log" || fail "no worker for 127.0.0.1 in the summary"
grep -q "farmpool:$one_PORT/127.0.0.2 " "$T/m.log" || fail "no worker for 127.0.0.2 in the summary"
wait_for "$T/one.log" "tiles in" "the worker on 127.0.0.1 to log its job"
wait_for "$T/two.log" "tiles in" "the worker on 127.0.0.2 to log its job"
echo ok
