#!/bin/sh
# Refusals, each with a clear message on both sides: wrong secret, missing
# secret, protocol version mismatch, another pixel revision, another pixel
# probe. With --no-local and no usable worker the master fails with exit
# code 69; without --no-local it renders locally.
. "$(dirname "$0")/farm_lib.inc"
printf 'correct horse battery staple\n' >"$T/secret"
printf 'something else\n' >"$T/wrong"
chmod 600 "$T/secret"
chmod 644 "$T/wrong"
start_worker s -j 1 --secret-file "$T/secret"
start_worker v -j 1 --test-fault proto-version
local_render "$SCENE" "$T/local.ppm"

# right secret: works
"$BIN/portray-master" "$SCENE" -o "$T/ok.ppm" --no-local -w "127.0.0.1:$s_PORT" --secret-file "$T/secret" 2>"$T/m0.log" ||
	fail "render with the right secret failed"
cmp "$T/local.ppm" "$T/ok.ppm" || fail "image differs with a secret"

# wrong secret
"$BIN/portray-master" "$SCENE" -o "$T/x.ppm" --no-local -w "127.0.0.1:$s_PORT" --secret-file "$T/wrong" 2>"$T/m1.log"
rc=$?
[ $rc -eq 69 ] || fail "wrong secret: exit $rc, expected 69"
grep -q "authentication failed" "$T/m1.log" || fail "wrong secret: master message unclear"
grep -q "every worker is lost and --no-local" "$T/m1.log" || fail "no final message"
wait_for "$T/s.log" "refused: authentication failed: the master's secret differs" "the worker's wrong-secret message"
grep -q "warning: --secret-file .*readable by other users" "$T/m1.log" || fail "no warning for a world-readable secret file"

# no secret at all against a worker that wants one
"$BIN/portray-master" "$SCENE" -o "$T/x.ppm" --no-local -w "127.0.0.1:$s_PORT" 2>"$T/m2.log"
[ $? -eq 69 ] || fail "missing secret: wrong exit code"
grep -q "requires a shared secret" "$T/m2.log" || fail "missing secret: master message unclear"
wait_for "$T/s.log" "refused: this worker requires a shared secret" "the worker's missing-secret message"

# protocol version mismatch
"$BIN/portray-master" "$SCENE" -o "$T/x.ppm" --no-local -w "127.0.0.1:$v_PORT" 2>"$T/m3.log"
[ $? -eq 69 ] || fail "version mismatch: wrong exit code"
grep -q "protocol version mismatch: the worker speaks version 4, this master speaks 3" "$T/m3.log" ||
	fail "version mismatch: master message unclear"
wait_for "$T/v.log" "refused: protocol version mismatch: the master speaks version 3, this worker speaks 4" \
	"the worker's version mismatch message"

# another core build (pixel revision): its pixels could differ
start_worker bld -j 1 --test-fault build-id
"$BIN/portray-master" "$SCENE" -o "$T/x.ppm" --no-local -w "127.0.0.1:$bld_PORT" 2>"$T/m5.log"
[ $? -eq 69 ] || fail "build mismatch: wrong exit code"
grep -q "core build mismatch: the worker runs 'proto-[0-9]*/scene-[0-9]*/pixels-[0-9]*-other/probe-[0-9a-f]*', this master runs 'proto-" "$T/m5.log" ||
	fail "build mismatch: master message unclear"
wait_for "$T/bld.log" "peer says: core build mismatch" "the worker to be told of the build mismatch"

# another pixel probe (a compiler, flag or CPU that draws other pixels)
start_worker prb -j 1 --test-fault probe
"$BIN/portray-master" "$SCENE" -o "$T/x.ppm" --no-local -w "127.0.0.1:$prb_PORT" 2>"$T/m6.log"
[ $? -eq 69 ] || fail "probe mismatch: wrong exit code"
grep -q "pixel probe mismatch: the worker's probe image hashes to [0-9a-f]*, this master's to [0-9a-f]*" "$T/m6.log" ||
	fail "probe mismatch: master message unclear"
wait_for "$T/prb.log" "peer says: pixel probe mismatch" "the worker to be told of the probe mismatch"

# all workers refused but local threads allowed: the render completes locally
"$BIN/portray-master" "$SCENE" -o "$T/l.ppm" -w "127.0.0.1:$v_PORT,127.0.0.1:$s_PORT" 2>"$T/m4.log" ||
	fail "render with only refused workers failed"
cmp "$T/local.ppm" "$T/l.ppm" || fail "image differs when rendered locally after refusals"
echo ok
