#!/bin/sh
# render_background.sh - a render that watches keys on its terminal and is
# then moved to the background (as the shell's `bg` does) must keep running
# when the user types in the foreground: reading the terminal from the
# background would stop it with SIGTTIN. A session on a fresh pty, made with
# python3, plays the shell (skipped, exit 77, without python3).
. tests/cli/render_lib.inc
command -v python3 >/dev/null 2>&1 || { echo "python3 not installed"; exit 77; }
slow_scene "$TMP/slow.sce" 300
python3 - "$MASTER" "$TMP/slow.sce" "$TMP/bg.ppm" <<'PY' || fail "see above"
import fcntl, os, pty, signal, sys, termios, time
master, scene, out = sys.argv[1:4]
if os.getpid() == os.getpgrp():  # a group leader cannot start a session
    pid = os.fork()
    if pid:
        sys.exit(os.waitstatus_to_exitcode(os.waitpid(pid, 0)[1]))
os.setsid()
m, s = pty.openpty()
fcntl.ioctl(s, termios.TIOCSCTTY, 0)
signal.signal(signal.SIGTTOU, signal.SIG_IGN)
r, w = os.pipe()
pid = os.fork()
if pid == 0:
    os.setpgid(0, 0)
    os.read(r, 1)
    os.dup2(s, 0)
    os.execv(master, [master, scene, "-o", out, "-j", "1", "-q"])
os.setpgid(pid, pid)
os.tcsetpgrp(s, pid)          # the render in the foreground: it watches keys
os.write(w, b"x")
time.sleep(1.0)
os.tcsetpgrp(s, os.getpgrp())  # `bg`: the shell takes the terminal back
os.write(m, b"ls\n")           # the user types at the shell
time.sleep(1.0)
state = open("/proc/%d/stat" % pid).read().rsplit(")", 1)[1].split()[0]
if state == "T":
    os.kill(pid, signal.SIGKILL)
    os.waitpid(pid, 0)
    print("FAIL: the background render stopped (SIGTTIN) when the user typed")
    sys.exit(1)
_, st = os.waitpid(pid, 0)
rc = os.waitstatus_to_exitcode(st)
if rc != 0:
    print("FAIL: render exit %d" % rc)
    sys.exit(1)
PY
ppm_check "$TMP/bg.ppm" 300 300
[ "$(ppm_pixel "$TMP/bg.ppm" 300 299 299)" != "0 0 0" ] || fail "image not complete"
echo "render_background: ok"
