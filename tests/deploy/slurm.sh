#!/bin/sh
# tests/deploy/slurm.sh - deploy/slurm/portray.sbatch on a real Slurm.
#
# Brings up a single-node Slurm cluster as root in a scratch directory
# (munged on a private socket and key, slurmctld, slurmd: Debian's slurm-wlm
# and munge packages; nothing under /etc is read or written), submits the
# sbatch script on a small scene, polls `scontrol show job` until it ends, and
# checks the job's exit status and that its image is byte-identical to a local
# render. A second job on a scene with an error checks that the job exits with
# the master's status. The daemons are always torn down (EXIT trap).
# Skipped (exit 77) when not root or when slurmctld, slurmd or munged is missing.
#   KEEP=1  keep the scratch directory (logs, slurm.conf)
BIN=${BIN:-bin}
ROOT=$(pwd)
SBATCH_SCRIPT=$ROOT/deploy/slurm/portray.sbatch
E2E=$ROOT/tests/e2e

skip() {
	echo "$*"
	exit 77
}
[ "$(id -u)" -eq 0 ] || skip "needs root to run slurmd and slurmctld"
for c in munged munge slurmctld slurmd sbatch srun scontrol scancel sinfo squeue; do
	command -v "$c" >/dev/null 2>&1 ||
		PATH=$PATH:/usr/sbin:/sbin command -v "$c" >/dev/null 2>&1 ||
		skip "$c not installed (apt-get install slurm-wlm munge)"
done
PATH=$PATH:/usr/sbin:/sbin
[ -x "$BIN/portray-master" ] && [ -x "$BIN/portray-worker" ] || {
	echo "FAIL: no $BIN/portray-master or $BIN/portray-worker (run make)"
	exit 1
}
BIN=$(cd "$BIN" && pwd)

# nothing from an enclosing Slurm job (make test run inside one) leaks in
for v in $(env | sed -n 's/^\(SLURM_[A-Za-z0-9_]*\)=.*/\1/p'); do
	unset "$v"
done

T=$(mktemp -d "${TMPDIR:-/tmp}/portray-slurm.XXXXXX")
chmod 755 "$T"
export SLURM_CONF="$T/slurm.conf"
JOBS=""

# pid_of FILE: the pid in a pid file, if the process is alive
pid_of() {
	[ -s "$1" ] || return 1
	p=$(cat "$1")
	kill -0 "$p" 2>/dev/null && echo "$p"
}
# stop PIDFILE...: SIGTERM to each live pid, then SIGKILL to those left after 5 s
stop() {
	ps_=""
	for f in "$@"; do
		p=$(pid_of "$f") && ps_="$ps_ $p"
	done
	[ -n "$ps_" ] || return 0
	kill -TERM $ps_ 2>/dev/null
	i=0
	while :; do
		alive=""
		for p in $ps_; do
			kill -0 "$p" 2>/dev/null && alive="$alive $p"
		done
		[ -n "$alive" ] || return 0
		i=$((i + 1))
		[ $i -eq 100 ] && kill -KILL $alive 2>/dev/null
		[ $i -gt 150 ] && return 0
		sleep 0.05
	done
}
cleanup() {
	# jobs still there (a failure): cancel them while slurmctld and slurmd are up
	if [ -n "$JOBS" ] && pid_of "$T/slurmctld.pid" >/dev/null; then
		for j in $JOBS; do
			scancel "$j" 2>/dev/null
		done
		i=0
		while [ $i -lt 100 ] && [ -n "$(squeue -h -o %i 2>/dev/null)" ]; do
			i=$((i + 1))
			sleep 0.1
		done
	fi
	stop "$T/slurmd.pid" "$T/slurmctld.pid"
	stop "$T/munge/munged.pid"
	[ -n "${KEEP:-}" ] && echo "kept $T" || rm -rf "$T"
}
trap cleanup EXIT
trap 'exit 1' INT TERM HUP

fail() {
	echo "FAIL: $*"
	for f in "$T"/log/*.log "$T"/*.out "$T"/portray-*/worker-*.log "$T"/*.log; do
		[ -f "$f" ] && { echo "--- $f"; tail -n 20 "$f"; }
	done
	exit 1
}

now() { date +%s.%N; }
elapsed() { awk -v a="$1" -v b="$(now)" 'BEGIN { printf "%.2f", b - a }'; }

# two free TCP ports on loopback for slurmctld and slurmd
free_port() {
	while :; do
		p=$(awk -v s="$(od -An -N2 -tu2 /dev/urandom)" 'BEGIN { printf "%d", 20000 + s % 30000 }')
		[ "$p" = "${1:-}" ] && continue
		if command -v ss >/dev/null 2>&1; then
			[ -z "$(ss -Htan "sport = :$p" 2>/dev/null)" ] || continue
		fi
		echo "$p"
		return
	done
}
CTLD_PORT=$(free_port)
SLURMD_PORT=$(free_port "$CTLD_PORT")

t_up=$(now)
# munge: a private key and socket; the directory must be 755 (munged warns
# that a socket in a 700 one is inaccessible)
mkdir -p "$T/munge" "$T/state" "$T/spool" "$T/log" "$T/work"
chmod 755 "$T/munge"
(umask 077 && dd if=/dev/urandom of="$T/munge/munge.key" bs=128 count=1 2>/dev/null) ||
	fail "cannot write a munge key"
chmod 400 "$T/munge/munge.key"
# --force: munged would refuse the scratch directory's parent (/tmp: writable by all)
munged --force --socket="$T/munge/socket" --key-file="$T/munge/munge.key" \
	--pid-file="$T/munge/munged.pid" --log-file="$T/log/munged.log" --seed-file="$T/munge/seed" ||
	fail "munged did not start"
munge -n -S "$T/munge/socket" | unmunge -S "$T/munge/socket" >/dev/null 2>&1 ||
	fail "munge does not answer on its private socket"

NODE=$(hostname -s)
cat >"$SLURM_CONF" <<EOF
# written by tests/deploy/slurm.sh: a single-node cluster on loopback
ClusterName=portraytest
SlurmctldHost=$NODE(127.0.0.1)
SlurmUser=root
SlurmdUser=root
SlurmctldPort=$CTLD_PORT
SlurmdPort=$SLURMD_PORT
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$T/munge/socket
StateSaveLocation=$T/state
SlurmdSpoolDir=$T/spool
SlurmctldPidFile=$T/slurmctld.pid
SlurmdPidFile=$T/slurmd.pid
SlurmctldLogFile=$T/log/slurmctld.log
SlurmdLogFile=$T/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
SelectType=select/cons_tres
# the backfill pass every second starts a job about 1 s after sbatch (the
# defaults leave a batch job pending about 3 s)
SchedulerType=sched/backfill
SchedulerParameters=bf_interval=1
MpiDefault=none
MailProg=/bin/true
ReturnToService=2
NodeName=$NODE NodeAddr=127.0.0.1 CPUs=$(nproc) State=UNKNOWN
PartitionName=test Nodes=$NODE Default=YES MaxTime=10 State=UP
EOF

slurmctld -f "$SLURM_CONF" || fail "slurmctld did not start"
slurmd -f "$SLURM_CONF" || fail "slurmd did not start"
i=0
until sinfo -h -o %T 2>/dev/null | grep -q '^idle'; do
	i=$((i + 1))
	[ $i -gt 300 ] && fail "the node did not turn idle within 30 s: $(sinfo 2>&1)"
	sleep 0.1
done
echo "slurm up in $(elapsed "$t_up") s: node $NODE idle, slurmctld on 127.0.0.1:$CTLD_PORT, slurmd on :$SLURMD_PORT"

# the scene and its reference image (a size other than the scene's: the
# extra master options reach the master)
cp "$E2E/farm_scene.sce" "$E2E/farm_tri.raw" "$T/work/"
SIZE=160x120
"$BIN/portray-master" "$T/work/farm_scene.sce" -o "$T/local.ppm" -q --size $SIZE || fail "local render failed"

# job STATE EXITCODE of a job (scontrol show job -o: one line)
job_field() { scontrol show job -o "$1" 2>/dev/null | tr ' ' '\n' | sed -n "s/^$2=//p"; }

# submit NAME [sbatch options...] -- SCRIPT ARGS: runs a job to its end (polling
# scontrol, at most 120 s); sets JOB, STATE and EXIT
submit() {
	name=$1
	shift
	t0=$(now)
	JOB=$(cd "$T/work" && sbatch --parsable --nodes=1 --time=5 --output="$T/$name.out" \
		--export=ALL,PORTRAY_BIN="$BIN" "$@") || fail "sbatch refused the $name job"
	JOB=${JOB%%;*}
	JOBS="$JOBS $JOB"
	i=0
	while :; do
		STATE=$(job_field "$JOB" JobState)
		case $STATE in
		PENDING | CONFIGURING | RUNNING | COMPLETING | SUSPENDED | "") ;;
		*) break ;;
		esac
		i=$((i + 1))
		[ $i -gt 1200 ] && fail "job $JOB ($name) still $STATE after 120 s"
		sleep 0.1
	done
	EXIT=$(job_field "$JOB" ExitCode)
	JOBS=$(echo "$JOBS" | sed "s/ $JOB\$//; s/ $JOB / /")
	echo "job $JOB ($name): $STATE, exit $EXIT, $(elapsed "$t0") s from sbatch to its end"
}

# 1. the farm job: one worker dials the master, the image matches the local render
submit farm "$SBATCH_SCRIPT" farm_scene.sce farm.ppm --size $SIZE --tile 16
echo "--- job output ($T/farm.out)"
cat "$T/farm.out"
JD=$T/work/portray-$JOB
for w in "$JD"/worker-*.log; do
	[ -f "$w" ] || continue
	echo "--- $(basename "$w")"
	cat "$w"
done
[ "$STATE" = COMPLETED ] && [ "$EXIT" = 0:0 ] || fail "the farm job ended $STATE, exit $EXIT"
[ -f "$T/work/farm.ppm" ] || fail "the farm job wrote no image"
cmp "$T/local.ppm" "$T/work/farm.ppm" || fail "the farm job's image differs from the local render"
echo "image: byte-identical to the local render ($SIZE)"
# the tiles came from the worker (the master has --no-local) and it said so
grep -q '127\.0\.0\.1.* tiles' "$T/farm.out" || fail "no worker summary line in the master's output"
[ -f "$JD/worker-$NODE.log" ] || fail "no worker log $JD/worker-$NODE.log"
grep -q ' job .* tiles in ' "$JD/worker-$NODE.log" || fail "the worker did not log its job"
# the generated secret and the port file are gone; no worker is left over
[ -e "$JD/secret" ] && fail "the generated secret was left in $JD"
port=$(sed -n 's/.*dialling 127\.0\.0\.1:\([0-9]*\).*/\1/p' "$T/farm.out" | head -n 1)
[ -n "$port" ] || fail "the job output does not name the port the workers dial"
ps -eo args | grep -q "^[^ ]*portray-worker --connect 127.0.0.1:$port " &&
	fail "a worker of job $JOB is still running"

# 2. a scene with an error: the job fails with the master's status (2)
printf 'object sphere centre (0 0 0) radius 1 ; material called nowhere ; ;\n' >"$T/work/bad.sce"
"$BIN/portray-master" --check "$T/work/bad.sce" >/dev/null 2>&1
want=$?
[ $want -ne 0 ] || fail "bad.sce should not parse"
submit bad "$SBATCH_SCRIPT" bad.sce bad.ppm
[ "$STATE" = FAILED ] && [ "$EXIT" = "$want:0" ] ||
	fail "the job on a bad scene ended $STATE, exit $EXIT (want FAILED, $want:0)"

# 3. no worker can run (a bad worker option: the worker step ends at once):
# the master is stopped, the job exits with 69 ("no worker left")
submit noworker --export=ALL,PORTRAY_BIN="$BIN",PORTRAY_WORKER_ARGS=--bogus-option \
	"$SBATCH_SCRIPT" farm_scene.sce noworker.ppm
grep 'portray.sbatch: the worker step ended' "$T/noworker.out"
[ "$STATE" = FAILED ] && [ "$EXIT" = 69:0 ] ||
	fail "the job whose workers cannot start ended $STATE, exit $EXIT (want FAILED, 69:0)"

# 4. the time limit's signal (SIGUSR1 to the batch shell, as --signal=B:USR1@60
# sends it): the master stops early, writes the finished tiles, exit 130
sed 's/filter standard ;/filter standard ;\n    filter super-sample x-samples 8 y-samples 8 ;/' \
	"$T/work/farm_scene.sce" >"$T/work/slow.sce"
t0=$(now)
JOB=$(cd "$T/work" && sbatch --parsable --nodes=1 --time=5 --output="$T/slow.out" \
	--export=ALL,PORTRAY_BIN="$BIN" "$SBATCH_SCRIPT" slow.sce slow.ppm --size 1600x1200) ||
	fail "sbatch refused the slow job"
JOB=${JOB%%;*}
JOBS="$JOBS $JOB"
wait_started() {
	i=0
	until grep -q ' started' "$T/work/portray-$JOB"/worker-*.log 2>/dev/null; do
		i=$((i + 1))
		[ $i -gt 600 ] && fail "the slow job's worker did not start its job within 60 s"
		sleep 0.1
	done
}
wait_started
scancel --batch --signal=USR1 "$JOB" || fail "scancel --batch --signal=USR1 $JOB"
i=0
while :; do
	STATE=$(job_field "$JOB" JobState)
	case $STATE in PENDING | CONFIGURING | RUNNING | COMPLETING | "") ;; *) break ;; esac
	i=$((i + 1))
	[ $i -gt 600 ] && fail "the slow job did not end within 60 s of SIGUSR1"
	sleep 0.1
done
EXIT=$(job_field "$JOB" ExitCode)
JOBS=$(echo "$JOBS" | sed "s/ $JOB\$//; s/ $JOB / /")
echo "job $JOB (slow, SIGUSR1 once its worker started): $STATE, exit $EXIT, $(elapsed "$t0") s from sbatch to its end"
grep 'portray.sbatch: time limit\|portray.sbatch: master exit' "$T/slow.out"
[ "$EXIT" = 130:0 ] || fail "the interrupted job ended $STATE, exit $EXIT (want 130:0)"
[ "$(head -n 3 "$T/work/slow.ppm" 2>/dev/null | tr '\n' ' ')" = "P6 1600 1200 255 " ] ||
	fail "the interrupted job wrote no 1600x1200 image"
echo "ok"
