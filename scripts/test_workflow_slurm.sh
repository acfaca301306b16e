#!/usr/bin/env bash
# The workflow through its SLURM profile (workflow/profiles/slurm) on a real SLURM: a single-node
# cluster on localhost (munged, MariaDB + slurmdbd for accounting, slurmctld, slurmd; one
# partition "main" of 2 CPUs), configured in a temporary folder, started here and stopped on exit
# whatever happened.
#   1. simulates two units (6 recordings each; one unit's name holds a space, ';' and $(...));
#      runs the workflow locally (-j 2) on them, for reference;
#   2. adds two units built to fail: one with a truncated recording, one whose fit_bias never
#      ends (a tool folder whose fit_bias sleeps for that unit; fit_bias runtime set to 1 min);
#   3. runs the workflow on all four through the profile: every panel_extract, fit_bias and
#      diagnose_gap a SLURM job; checks that the two good units' outputs are byte-identical to
#      the local run's, that the corrupt unit failed alone at its recording, that the hung job
#      was killed by the time limit, submitted again (the profile's retries) and reported, that
#      the summary names both failed units and their logs, that sacct lists every job with the
#      state expected, and that each job's log is in .snakemake/slurm_logs/ (workflow/README.md).
#   bash scripts/test_workflow_slurm.sh [BUILD_DIR]     (ctest: workflow_slurm, label slurm)
# Installs nothing: `WITH_SLURM=1 scripts/setup.sh` does (scripts/test.sh runs it, as root, before
# ctest), since tests run side by side on one .venv. Exits 77 (skipped) with one line when SLURM is
# missing or cannot be started here (not root, a daemon that does not start);
# any other failing check says which on one line and exits 1. KEEP=1 keeps the cluster's folder.
set -uo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
SKIPPED=77
skip() {
  echo "test_workflow_slurm: skipped: $*"
  exit $SKIPPED
}
NAME=test_workflow_slurm
# shellcheck source=scripts/workflow_test_lib.sh
. "$ROOT/scripts/workflow_test_lib.sh"
use_build "${1:-}" simulate panel_extract fit_bias diagnose_gap
use_snakemake
[ "$(id -u)" -eq 0 ] || skip "not root (munged, slurmd and slurmstepd need root here)"

# --- What the cluster needs: SLURM, munge, MariaDB, the executor plugin -----------------------
have_all() {
  for cmd in munged mungekey slurmctld slurmd slurmdbd sbatch sacct mariadbd \
      mariadb-install-db; do
    command -v "$cmd" >/dev/null 2>&1 || return 1
  done
  "$PYTHON" -c "import snakemake_executor_plugin_slurm" 2>/dev/null
}
have_all || skip "SLURM, munge, MariaDB or the SLURM executor missing;" \
  "install them with WITH_SLURM=1 bash scripts/setup.sh (scripts/test.sh does, as root)"

# --- The cluster, in a temporary folder -------------------------------------------------------
C=$(mktemp -d /tmp/depthbias-slurm.XXXXXX) || skip "cannot make a temporary folder"
chmod 700 "$C"
mkdir -p "$C/munge" "$C/state" "$C/spool" "$C/log" "$C/db"
export SLURM_CONF=$C/slurm.conf
# Only what was started here is stopped: the workflow's snakemake, the jobs, then the daemons by
# the pids they wrote. The daemons leave this script's process tree, so a kill this script cannot
# trap (ctest's timeout, KILL) would leave them running: a watchdog outside the tree (setsid)
# stops them once this script is gone without having stopped them itself.
cat >"$C/stop_daemons.sh" <<'EOF_STOP'
C=$1
if [ -f "$C/slurmctld.pid" ]; then
  scancel --quiet --user="$(id -un)" >/dev/null 2>&1 || true
  sleep 1
fi
munged --stop --socket="$C/munge/munge.socket" >/dev/null 2>&1 &
for pidfile in slurmd.pid slurmctld.pid slurmdbd.pid db/mariadbd.pid munge/munged.pid; do
  pid=$(cat "$C/$pidfile" 2>/dev/null) || continue
  [ -n "$pid" ] && kill "$pid" 2>/dev/null || continue
  for _ in $(seq 50); do
    kill -0 "$pid" 2>/dev/null || break
    sleep 0.1
  done
  kill -9 "$pid" 2>/dev/null || true
done
EOF_STOP
cat >"$C/watchdog.sh" <<'EOF_WATCH'
C=$1 PARENT=$2
while kill -0 "$PARENT" 2>/dev/null && [ ! -e "$C/stopped" ]; do sleep 2; done
[ -d "$C" ] && [ ! -e "$C/stopped" ] || exit 0
touch "$C/stopped"
bash "$C/stop_daemons.sh" "$C"
[ "${KEEP:-0}" = "1" ] || rm -rf "$C"
EOF_WATCH
SNAKE_PID=
stop_cluster() {
  if [ -n "$SNAKE_PID" ] && kill -0 "$SNAKE_PID" 2>/dev/null; then
    kill -INT "$SNAKE_PID" 2>/dev/null
    sleep 5
    kill -KILL "$SNAKE_PID" 2>/dev/null || true
  fi
  touch "$C/stopped"  # the watchdog leaves it to this
  bash "$C/stop_daemons.sh" "$C"
  if [ "${KEEP:-0}" = "1" ]; then
    echo "test_workflow_slurm: cluster folder kept: $C"
  else
    rm -rf "$C"
  fi
}
trap stop_cluster EXIT
trap 'exit 130' INT
trap 'exit 143' TERM
setsid -f bash "$C/watchdog.sh" "$C" $$ </dev/null >/dev/null 2>&1 ||
  skip "cannot start the watchdog that stops the cluster (setsid)"
started() {  # started WHAT LOG: the daemon's last log line, as a skip
  skip "$1 did not start: $(grep -v '^\s*$' "$2" 2>/dev/null | tail -1 || echo "no log")"
}
wait_for() {  # wait_for SECONDS COMMAND...: true once COMMAND succeeds
  local deadline=$((SECONDS + $1))
  shift
  until "$@" >/dev/null 2>&1; do
    [ $SECONDS -lt $deadline ] || return 1
    sleep 0.3
  done
}
read -r DB_PORT DBD_PORT CTLD_PORT SLURMD_PORT < <("$PYTHON" - <<'EOF'
import socket
socks = [socket.socket() for _ in range(4)]
for s in socks:
    s.bind(("127.0.0.1", 0))
print(*[s.getsockname()[1] for s in socks])
EOF
)
[ -n "${SLURMD_PORT:-}" ] || skip "no free local port"
MEM_MB=$(awk '/^MemTotal:/ { m = int($2 / 1024 * 0.8); print (m < 8000 ? m : 8000) }' \
  /proc/meminfo)

# munge: the credentials every SLURM message carries; its own key and socket.
mungekey --create --keyfile="$C/munge/munge.key" >"$C/log/mungekey.log" 2>&1 ||
  started "mungekey" "$C/log/mungekey.log"
chmod 600 "$C/munge/munge.key"
munged --force --socket="$C/munge/munge.socket" --key-file="$C/munge/munge.key" \
    --pid-file="$C/munge/munged.pid" --seed-file="$C/munge/munged.seed" \
    --log-file="$C/log/munged.log" >>"$C/log/munged.log" 2>&1 || started munged "$C/log/munged.log"

# MariaDB on 127.0.0.1 for slurmdbd (sacct reads the jobs from it).
mariadb-install-db --no-defaults --datadir="$C/db" --user=root --skip-test-db \
    --auth-root-authentication-method=normal >"$C/log/mariadb-install.log" 2>&1 ||
  started "mariadb-install-db" "$C/log/mariadb-install.log"
mariadbd --no-defaults --datadir="$C/db" --user=root --bind-address=127.0.0.1 \
    --port="$DB_PORT" --socket="$C/db/mysqld.sock" --pid-file="$C/db/mariadbd.pid" \
    --log-error="$C/log/mariadb.log" --skip-name-resolve >/dev/null 2>&1 &
wait_for 30 mariadb --no-defaults -S "$C/db/mysqld.sock" -u root -e 'SELECT 1' ||
  started mariadbd "$C/log/mariadb.log"
mariadb --no-defaults -S "$C/db/mysqld.sock" -u root -e "
  CREATE USER 'slurm'@'127.0.0.1' IDENTIFIED BY 'slurm';
  GRANT ALL ON slurm_acct_db.* TO 'slurm'@'127.0.0.1';" >"$C/log/mariadb-user.log" 2>&1 ||
  started "MariaDB's slurm user" "$C/log/mariadb-user.log"

cat >"$C/slurmdbd.conf" <<EOF
AuthType=auth/munge
AuthInfo=socket=$C/munge/munge.socket
DbdHost=localhost
DbdAddr=127.0.0.1
DbdPort=$DBD_PORT
SlurmUser=root
LogFile=$C/log/slurmdbd.log
PidFile=$C/slurmdbd.pid
StorageType=accounting_storage/mysql
StorageHost=127.0.0.1
StoragePort=$DB_PORT
StorageUser=slurm
StoragePass=slurm
StorageLoc=slurm_acct_db
EOF
chmod 600 "$C/slurmdbd.conf"
cat >"$C/slurm.conf" <<EOF
ClusterName=depthbias
SlurmctldHost=localhost(127.0.0.1)
SlurmctldPort=$CTLD_PORT
SlurmdPort=$SLURMD_PORT
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$C/munge/munge.socket
CredType=cred/munge
StateSaveLocation=$C/state
SlurmdSpoolDir=$C/spool
SlurmctldPidFile=$C/slurmctld.pid
SlurmdPidFile=$C/slurmd.pid
SlurmctldLogFile=$C/log/slurmctld.log
SlurmdLogFile=$C/log/slurmd.log
MailProg=/bin/true
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/linux
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU_Memory
SchedulerType=sched/backfill
MpiDefault=none
ReturnToService=2
AccountingStorageType=accounting_storage/slurmdbd
AccountingStorageHost=localhost
AccountingStoragePort=$DBD_PORT
AccountingStoragePass=$C/munge/munge.socket
AccountingStoreFlags=job_comment
JobCompType=jobcomp/none
MinJobAge=600
KillWait=5
InactiveLimit=0
NodeName=localhost NodeAddr=127.0.0.1 CPUs=2 RealMemory=$MEM_MB State=UNKNOWN
PartitionName=main Nodes=localhost Default=YES MaxTime=INFINITE State=UP
EOF
slurmdbd >>"$C/log/slurmdbd.log" 2>&1 || started slurmdbd "$C/log/slurmdbd.log"
wait_for 30 sacctmgr -n list cluster || started slurmdbd "$C/log/slurmdbd.log"
slurmctld >>"$C/log/slurmctld.log" 2>&1 || started slurmctld "$C/log/slurmctld.log"
wait_for 30 scontrol ping || started slurmctld "$C/log/slurmctld.log"
slurmd -N localhost >>"$C/log/slurmd.log" 2>&1 || started slurmd "$C/log/slurmd.log"
node_idle() { sinfo -h -N -o '%t' | grep -qx idle; }
wait_for 60 node_idle || started "slurmd (node not idle: $(sinfo -h -N -o '%t %E'))" \
  "$C/log/slurmd.log"
t_cluster=$SECONDS
# The jobs' own snakemake (snakemake-executor-plugin-slurm-jobstep 0.6.1) runs each job's step
# with srun in an environment stripped of SLURM_* variables, SLURM_CONF included: on a cluster
# whose slurm.conf is in /etc/slurm or served by slurmctld (configless) that is harmless; here,
# with the configuration in a temporary folder, an srun first on PATH sets it back.
mkdir -p "$C/bin"
printf '#!/bin/sh\nSLURM_CONF=%s exec /usr/bin/srun "$@"\n' "$C/slurm.conf" >"$C/bin/srun"
chmod +x "$C/bin/srun"

# --- 1. Two units and the local run ------------------------------------------------------------
WORK=$BUILD/workflow-slurm-test
rm -rf "$WORK"
mkdir -p "$WORK/units" "$WORK/tools" "$WORK/tools_hung" "$WORK/run"
write_protocol "$WORK/protocol.yaml" "4, 8, 12" "0, 20" HD 3
UNIT_A=unit_a
UNIT_B='unit b;$(touch PWNED)'
seed=1
for unit in "$UNIT_A" "$UNIT_B"; do
  "$APPS/simulate" --protocol "$WORK/protocol.yaml" --out-dir "$WORK/units/$unit" \
      --seed $seed --threads 2 >"$WORK/simulate.log" 2>&1 ||
    fail "simulate failed, see $WORK/simulate.log"
  seed=$((seed + 1))
done
for tool in "$APPS"/*; do
  [ -x "$tool" ] && [ -f "$tool" ] && ln -s "$tool" "$WORK/tools/" && ln -s "$tool" \
    "$WORK/tools_hung/"
done
(cd "$WORK/run" && "$SNAKEMAKE" -s "$ROOT/workflow/Snakefile" -j 2 --config \
    units_dir="$WORK/units" out_dir="$WORK/results" tools="$WORK/tools" diagnose_gap=true) \
    >"$WORK/local.log" 2>&1 || fail "the local run failed, see $WORK/local.log"
mv "$WORK/results" "$WORK/results_local"
rm -rf "$WORK/run/.snakemake"

# --- 2. Two units built to fail ---------------------------------------------------------------
mkdir "$WORK/units/unit_corrupt" "$WORK/units/unit_hung"
for unit in unit_corrupt unit_hung; do  # three distances: enough for diagnose_gap
  cp "$WORK/units/$UNIT_A"/*_0deg_*.bag "$WORK/units/$UNIT_A/manifest.csv" "$WORK/units/$unit/"
done
bad=$(cd "$WORK/units/unit_corrupt" && ls ./*_8m_0deg_*.bag) || fail "no 8 m recording simulated"
bad=${bad#./}
size=$(stat -c %s "$WORK/units/unit_corrupt/$bad")
truncate -s $((size / 3)) "$WORK/units/unit_corrupt/$bad"
rm "$WORK/tools_hung/fit_bias"
cat >"$WORK/tools_hung/fit_bias" <<EOF
#!/bin/sh
# fit_bias, except that it never ends on unit_hung (a job for the scheduler's time limit).
case "\$*" in */unit_hung/*) exec sleep 600 ;; esac
exec "$APPS/fit_bias" "\$@"
EOF
chmod +x "$WORK/tools_hung/fit_bias"

# --- 3. The four units through the SLURM profile ------------------------------------------------
t_start=$SECONDS
since=$(date +%Y-%m-%dT%H:%M:%S)
(cd "$WORK/run" && PATH="$C/bin:$PATH" exec "$SNAKEMAKE" -s "$ROOT/workflow/Snakefile" \
    --profile "$ROOT/workflow/profiles/slurm" --slurm-init-seconds-before-status-checks 3 \
    --latency-wait 5 --set-resources fit_bias:runtime=1 --config units_dir="$WORK/units" \
    out_dir="$WORK/results" tools="$WORK/tools_hung" diagnose_gap=true) \
    >"$WORK/slurm.log" 2>&1 &
SNAKE_PID=$!
wait $SNAKE_PID
status=$?
SNAKE_PID=
t_run=$((SECONDS - t_start))
LOG=$WORK/slurm.log
[ $status -ne 0 ] || fail "the run with two failing units exited 0, see $LOG"
{ find "$WORK" /tmp -maxdepth 4 -name 'PWNED*' 2>/dev/null || true; } | grep . >/dev/null &&
  fail "a unit's name was run by a shell"
grep -q "SLURM run ID" "$LOG" || fail "the jobs did not go through the SLURM executor, see $LOG"

# The good units: byte-identical to the local run (every output, the tools' logs aside).
for unit in "$UNIT_A" "$UNIT_B"; do
  diff -r -x logs -x '*.log' "$WORK/results_local/$unit" "$WORK/results/$unit" \
      >"$WORK/diff.txt" 2>&1 ||
    fail "$unit: outputs differ from the local run's (see $WORK/diff.txt)"
  [ -s "$WORK/results/$unit/weights.yaml" ] && [ -s "$WORK/results/$unit/gap/gap.json" ] ||
    fail "$unit: no weights.yaml or gap report"
done

# The failed units: nothing partial, and the summary names each with its logs.
[ ! -e "$WORK/results/unit_corrupt/shards/${bad%.bag}.csv" ] ||
  fail "unit_corrupt: a shard left for its corrupt recording"
[ ! -e "$WORK/results/unit_corrupt/metrics.csv" ] ||
  fail "unit_corrupt: a metrics table despite its corrupt recording"
[ ! -e "$WORK/results/unit_hung/weights.yaml" ] ||
  fail "unit_hung: weights.yaml although its fit_bias was killed"
grep -q '^workflow: 4 unit(s): 2 done, 2 not done' "$LOG" ||
  fail "no summary '4 unit(s): 2 done, 2 not done' at the end of $LOG"
corrupt=$(grep "^workflow: unit unit_corrupt not done: panel_extract on $bad:" "$LOG")
[ -n "$corrupt" ] || fail "the summary does not name unit_corrupt's recording, see $LOG"
log_of() { sed -n "s/.*$1 \([^,)]*\).*/\1/p" <<<"$2"; }
[ -s "$(log_of log "$corrupt")" ] || fail "unit_corrupt: its tool log is not where the summary says"
[ -s "$(log_of 'job log' "$corrupt")" ] || fail "unit_corrupt: no job log where the summary says"
hung=$(grep '^workflow: unit unit_hung not done: fit_bias: .*DUE TO TIME LIMIT' "$LOG")
[ -n "$hung" ] || fail "the summary does not report unit_hung's time limit, see $LOG"
[ -s "$(log_of 'job log' "$hung")" ] || fail "unit_hung: no job log where the summary says"

# sacct: every job of the run, in the state expected; each job's log where the README says.
wait_for 30 sh -c "sacct -a -X -n -S $since -o State | grep -q TIMEOUT" || true
sacct -a -X -S "$since" --parsable2 \
    -o JobID,Comment%60,State,ExitCode,Elapsed,Timelimit,ReqMem,AllocCPUS >"$WORK/sacct.txt" ||
  fail "sacct failed"
count() { awk -F'|' -v rule="$1" -v state="$2" \
  'NR > 1 && index($2, "rule_" rule) == 1 && $3 ~ "^" state { n++ } END { print n + 0 }' \
  "$WORK/sacct.txt"; }
# 12 recordings of the good units + 3 + 3 of the others (one fails, and is tried again), fit_bias
# and diagnose_gap for the good units, diagnose_gap for unit_hung, fit_bias of unit_hung twice.
expect() {  # expect RULE STATE N
  local n
  n=$(count "$1" "$2")
  [ "$n" -eq "$3" ] || fail "sacct: $n $1 jobs $2, expected $3 (see $WORK/sacct.txt)"
}
expect panel_extract COMPLETED 17
expect panel_extract FAILED 2
expect fit_bias COMPLETED 2
expect fit_bias TIMEOUT 2
expect diagnose_gap COMPLETED 3
jobs=$(awk 'NR > 1' "$WORK/sacct.txt" | wc -l)
[ "$jobs" -eq 26 ] || fail "sacct lists $jobs jobs, expected 26 (see $WORK/sacct.txt)"
while IFS='|' read -r id _; do
  found=$(find "$WORK/run/.snakemake/slurm_logs" -name "$id.log" | head -1)
  [ -s "$found" ] || fail "job $id: no log .snakemake/slurm_logs/rule_*/*/$id.log"
done < <(awk 'NR > 1' "$WORK/sacct.txt")
grep -q 'DUE TO TIME LIMIT' "$(log_of 'job log' "$hung")" ||
  fail "unit_hung's job log does not say it was cancelled by the time limit"

echo "test_workflow_slurm: 4 units, $jobs SLURM jobs (sacct: $(awk -F'|' 'NR > 1 { print $3 }' \
  "$WORK/sacct.txt" | sort | uniq -c | awk '{ printf "%s%d %s", sep, $1, $2; sep = ", " }'));" \
  "2 units byte-identical to the local run, a corrupt recording and a time limit reported;" \
  "cluster up in ${t_cluster} s, run ${t_run} s"
