#!/bin/sh
# render_keys.sh - on a terminal (a pty from script(1)), q and Esc end a render
# early and write the finished part (exit 0), the terminal gets its canonical
# mode and echo back; with image `nonstop` keys are ignored. Skipped (exit 77)
# without script(1), which provides the terminal.
. tests/cli/render_lib.inc
if ! command -v script >/dev/null 2>&1; then
	echo "script(1) not installed"
	exit 77
fi
# on_tty KEYS DELAY LOG COMMAND: runs COMMAND on a pty, typing KEYS after DELAY s
on_tty() {
	(sleep "$2"; printf "$1"; sleep 1) | script -qec "$4" /dev/null >"$3" 2>&1
}

slow_scene "$TMP/slow.sce" 600
for key in q '\033'; do
	rm -f "$TMP/k.ppm"
	on_tty "$key" 1 "$TMP/log" "'$MASTER' '$TMP/slow.sce' -o '$TMP/k.ppm' -j 1 --tile 20; echo rc=\$?; stty -a"
	tr -d '\r' <"$TMP/log" >"$TMP/log2"
	grep -Eq 'stopped: [0-9]+ of 900 tiles \([0-9]+%\) written to' "$TMP/log2" ||
		fail "key '$key': no 'stopped' message: $(tail -c 300 "$TMP/log2")"
	grep -q '^rc=0$' "$TMP/log2" || fail "key '$key': exit status not 0"
	grep -Eq '[0-9]+% \[#*\.*\] [0-9]+/900 tiles .* elapsed  ETA ' "$TMP/log2" ||
		fail "key '$key': no progress bar on the terminal"
	ppm_check "$TMP/k.ppm" 600 600
	[ "$(ppm_pixel "$TMP/k.ppm" 600 599 599)" = "0 0 0" ] || fail "key '$key': unfinished pixel not black"
	# terminal restored: canonical mode and echo
	grep -q -- '-icanon' "$TMP/log2" && fail "key '$key': terminal left non-canonical"
	grep -Eq '(^| )icanon' "$TMP/log2" || fail "key '$key': no stty output"
	grep -Eq '(^| )-echo( |$)' "$TMP/log2" && fail "key '$key': echo left off"
done

# nonstop: q is ignored, the render completes; -q: no bar even on a terminal
slow_scene "$TMP/ns.sce" 200 nonstop
on_tty q 0.3 "$TMP/log" "'$MASTER' -q '$TMP/ns.sce' -o '$TMP/ns.ppm' -j 1 --tile 20; echo rc=\$?"
tr -d '\r' <"$TMP/log" >"$TMP/log2"
grep -q 'stopped' "$TMP/log2" && fail "nonstop: a key stopped the render"
grep -q 'ETA' "$TMP/log2" && fail "-q: progress bar drawn"
grep -q 'rc=0$' "$TMP/log2" || fail "nonstop: exit status not 0: $(tail -c 300 "$TMP/log2")"
ppm_check "$TMP/ns.ppm" 200 200
[ "$(ppm_pixel "$TMP/ns.ppm" 200 199 199)" != "0 0 0" ] || fail "nonstop: image not complete"
# a crash (SIGSEGV, SIGABRT) while the terminal is in key mode: restored before dying
for sig in SEGV ABRT; do
	on_tty "" 0 "$TMP/log" "'$MASTER' '$TMP/slow.sce' -o '$TMP/c.ppm' -j 1 --tile 20 </dev/tty 2>/dev/null &
p=\$!; sleep 1; kill -$sig \$p; wait \$p; echo rc=\$?; stty -a"
	tr -d '\r' <"$TMP/log" >"$TMP/log2"
	grep -Eq '^rc=(13[4-9]|1[4-9][0-9])$' "$TMP/log2" || fail "SIG$sig: not killed by it: $(tail -c 300 "$TMP/log2")"
	grep -q -- '-icanon' "$TMP/log2" && fail "SIG$sig: terminal left non-canonical"
	grep -Eq '(^| )icanon' "$TMP/log2" || fail "SIG$sig: no stty output"
done
echo "render_keys: ok"
