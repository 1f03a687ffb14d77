#!/usr/bin/env bash
# deploy/slurm/crackvis.sbatch under a real single-node Slurm (issue 34
# point 5): slurmctld and slurmd started here on loopback (Debian's
# slurm-wlm, auth/none, state in a temporary folder), jobs submitted with
# sbatch. For the roles `both`, then `data` with `render` reading from it
# in a second job: the job prints its address, the real crackvis-client
# connects through it and draws the file, scancel ends the job, and every
# process the job started is gone. A job with a missing option fails with
# its one line in the job's output. With `pvserver`, the role pvserver
# instead: a pvpython client connects through the printed address and the
# server renders the file's crack through the plugin.
#
#   tests/deploy/slurm-job.sh SOURCE_DIR CRACKVIS CRACKVIS_DATA CRACKVIS_RENDER CRACKVIS_CLIENT [pvserver]
set -euo pipefail
shopt -s inherit_errexit
source_dir=$(realpath "$1")
cli=$(realpath "$2")
data=$(realpath "$3")
render=$(realpath "$4")
client=$(realpath "$5")
scenario=${6:-crackvis}

fail() {
  echo "FAIL: $*" >&2
  exit 1
}
for tool in slurmctld slurmd sbatch squeue scancel sinfo; do
  command -v "$tool" >/dev/null || fail "$tool is missing (deploy/install-deps.sh installs slurm-wlm)"
done

work=$(mktemp -d)
daemons=()
cleanup() {
  local pid
  scancel --full --quiet --user "$(id -un)" 2>/dev/null || true
  for pid in "${daemons[@]}"; do
    kill "$pid" 2>/dev/null || true
    wait "$pid" 2>/dev/null || true
  done
  rm -rf "$work"
}
trap cleanup EXIT

# A port nothing listens on (the daemons' ports are fixed in slurm.conf).
free_port() {
  local candidate
  for _ in $(seq 200); do
    candidate=$((20000 + RANDOM % 40000))
    if ! (exec 3<>"/dev/tcp/127.0.0.1/$candidate") 2>/dev/null; then
      echo "$candidate"
      return
    fi
  done
  fail "no free port"
}

# until SECONDS COMMAND...: retries COMMAND every 0.2 s.
until_true() {
  local tries=$(($1 * 5))
  shift
  for _ in $(seq "$tries"); do
    if "$@"; then
      return 0
    fi
    sleep 0.2
  done
  return 1
}

# --- A single-node cluster on loopback -------------------------------------
host=$(hostname -s)
mkdir -p "$work/state" "$work/spool" "$work/bin" "$work/data"
export SLURM_CONF=$work/slurm.conf
cat >"$SLURM_CONF" <<EOF
ClusterName=crackvistest
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$(free_port)
SlurmdPort=$(free_port)
AuthType=auth/none
CredType=cred/none
SlurmUser=$(id -un)
SlurmdUser=$(id -un)
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
MpiDefault=none
ReturnToService=2
KillWait=5
NodeName=cvnode NodeHostname=$host NodeAddr=127.0.0.1 CPUs=$(nproc) State=UNKNOWN
PartitionName=test Nodes=cvnode Default=YES MaxTime=INFINITE State=UP
EOF
slurmctld -D -f "$SLURM_CONF" >"$work/slurmctld.out" 2>&1 &
daemons+=($!)
slurmd -D -f "$SLURM_CONF" -N cvnode >"$work/slurmd.out" 2>&1 &
daemons+=($!)
node_idle() { sinfo -h -N -o '%t' 2>/dev/null | grep -qx idle; }
until_true 60 node_idle || fail "the node did not come up: $(tail -5 "$work"/slurm*.out)"
echo "Slurm: node cvnode idle ($(sinfo --version))"

# --- What the jobs serve, and with which certificates ----------------------
bash "$source_dir/certs/make-dev-certs.sh" "$work/certs" --client crackvis-render >/dev/null
ln -s "$data" "$work/bin/crackvis-data"
ln -s "$(dirname "$data")/crackvis-hdf5-worker" "$work/bin/crackvis-hdf5-worker"
ln -s "$render" "$work/bin/crackvis-render"
"$cli" generate --sites 10 10 10 --planted-crack 3 -o "$work/data/run.h5" -q
tls=(--ca "$work/certs/ca.pem" --cert "$work/certs/client.pem" --key "$work/certs/client.key")

# submit ARGS...: the job's id. The job runs in $work, a user's folder
# outside the checkout, which CRACKVIS_ROOT names (for pvserver's script).
submit() {
  CRACKVIS_ROOT=$source_dir sbatch --parsable --chdir "$work" -o "$work/job-%j.out" "$source_dir/deploy/slurm/crackvis.sbatch" \
    --bin "$work/bin" --certs "$work/certs" --advertise localhost "$@"
}

has_address() { grep -q '^Inside the cluster:' "$work/job-$1.out" 2>/dev/null; }

# address JOB: the address the job tells clients inside the cluster to use.
address() {
  until_true 60 has_address "$1" ||
    fail "job $1 printed no address: $(cat "$work/job-$1.out" 2>/dev/null) $(tail -3 "$work"/crackvis-"$1"-*.log 2>/dev/null)"
  grep -A1 '^Inside the cluster:' "$work/job-$1.out" | tail -1 | grep -oE '[^ /=]+:[0-9]+$'
}

# job_pids JOB: the pids the job says it started.
job_pids() {
  sed -n 's/.*(pids \([0-9 ]*\)).*/\1/p' "$work/job-$1.out"
}

# draw ADDRESS: crackvis-client connects, opens run.h5 and grabs its window.
draw() {
  rm -f "$work/shot.png"
  (cd "$work" && QT_QPA_PLATFORM=offscreen timeout 120 "$client" --connect "$1" "${tls[@]}" \
    --file run.h5 --window-screenshot "$work/shot.png" >"$work/client.out" 2>&1) ||
    fail "crackvis-client through $1: $(cat "$work/client.out")"
  # It grabs only after a full-resolution frame has arrived (client/app).
  [[ -s $work/shot.png ]] || fail "crackvis-client through $1 wrote no picture"
}

# descendants PID...: the processes and all their children, now.
descendants() {
  local pid children
  for pid in "$@"; do
    echo "$pid"
    mapfile -t children < <(pgrep -P "$pid" || true)
    ((${#children[@]} == 0)) || descendants "${children[@]}"
  done
}

# alive PID: running, or stopped, but not yet dead (a zombie is dead).
alive() {
  local stat
  stat=$(cat "/proc/$1/stat" 2>/dev/null) || return 1
  stat=${stat##*) }
  [[ ${stat:0:1} != Z ]]
}

# cancel JOB PIDS...: scancel; then the job and every process it started
# (the services and crackvis-data's HDF5 workers) must be gone.
cancel() {
  local job=$1 all
  shift
  mapfile -t all < <(descendants "$@")
  scancel "$job"
  job_gone() { ! squeue -h -j "$job" 2>/dev/null | grep -q .; }
  until_true 30 job_gone || fail "job $job still queued 30 s after scancel"
  none_alive() {
    local pid
    for pid in "${all[@]}"; do
      ! alive "$pid" || return 1
    done
  }
  until_true 10 none_alive || fail "processes of job $job outlived it: $(ps -o pid,args -p "${all[*]}")"
  grep -q "CANCELLED" "$work/job-$job.out" ||
    fail "job $job's output does not say it was cancelled: $(tail -5 "$work/job-$job.out")"
  echo "job $job: scancel ended it and its ${#all[@]} processes"
}

# --- Role pvserver: ParaView's server with the plugin ----------------------
if [[ $scenario == pvserver ]]; then
  eval "$("$source_dir/deploy/paraview-prefix.sh" --env)"
  plugin=$("$source_dir/paraview-plugin/build.sh")
  job=$(submit --role pvserver)
  pv_address=$(address "$job")
  read -r -a pids <<<"$(job_pids "$job")"
  grep -q -- "ssh -N -L 11111:$pv_address " "$work/job-$job.out" || fail "no tunnel line"
  # The client draws nothing itself but still needs a display for its window.
  xvfb-run -a -s "-screen 0 1280x1024x24 -noreset" "$CRACKVIS_PARAVIEW_PREFIX/usr/bin/pvpython" \
    "$source_dir/paraview-plugin/tests/pvserver_renders.py" "$plugin" "$work/data/run.h5" \
    "$pv_address" "$work/pv.png" >"$work/pvpython.out" 2>&1 ||
    fail "pvpython through $pv_address: $(grep -v '^HDF5-DIAG\|^  ' "$work/pvpython.out" | tail -5)"
  echo "role pvserver: job $job served pvserver at $pv_address; pvpython got the crack rendered: $(tail -1 "$work/pvpython.out")"
  # pvserver itself ends when its client leaves; the job must not.
  sleep 2
  [[ $(squeue -h -j "$job" -o %T 2>/dev/null) == RUNNING ]] ||
    fail "job $job ended when its client left: $(tail -5 "$work/job-$job.out")"
  # The pvserver started for the next client asks for huge pages where THP is
  # madvise (deploy/huge-pages.sh, sourced by pvserver-beside-data.sh), unless
  # the environment the job inherits says otherwise.
  if grep -q '\[madvise\]' /sys/kernel/mm/transparent_hugepage/enabled 2>/dev/null &&
    [[ ${CRACKVIS_HUGE_PAGES:-1} != 0 && ${GLIBC_TUNABLES:-} != *hugetlb* ]]; then
    servers=$(for pid in $(descendants "${pids[@]}"); do
      if [[ $(cat "/proc/$pid/comm" 2>/dev/null) == pvserver ]]; then echo "$pid"; fi
    done)
    [[ -n $servers ]] || fail "job $job runs no pvserver for the next client"
    for pid in $servers; do
      grep -qz '^GLIBC_TUNABLES=.*glibc\.malloc\.hugetlb=1' "/proc/$pid/environ" ||
        fail "pvserver $pid of job $job runs without the huge-pages tunable"
    done
    echo "role pvserver: the job's pvserver ($servers) asks for huge pages"
  fi
  cancel "$job" "${pids[@]}"
  echo "PASS"
  exit 0
fi

# --- Role both: crackvis-data and crackvis-render on the allocated node ----
job=$(submit --data-root "$work/data")
render_address=$(address "$job")
read -r -a pids <<<"$(job_pids "$job")"
((${#pids[@]} == 2)) || fail "job $job named ${#pids[@]} pids, not 2: $(cat "$work/job-$job.out")"
grep -q -- "ssh -N -L 50052:$render_address " "$work/job-$job.out" || fail "no tunnel line"
"$cli" health "${tls[@]}" "$render_address" | grep -q "SERVING (crackvis-render)" ||
  fail "crackvis-render of job $job is not serving at $render_address"
draw "$render_address"
echo "role both: job $job served crackvis-render at $render_address; the client drew run.h5"
cancel "$job" "${pids[@]}"

# --- Roles data and render in two jobs --------------------------------------
data_job=$(submit --role data --data-root "$work/data")
data_address=$(address "$data_job")
"$cli" health "${tls[@]}" "$data_address" | grep -q "SERVING (crackvis-data)" ||
  fail "crackvis-data of job $data_job is not serving at $data_address"
render_job=$(submit --role render --data-server "$data_address")
render_address=$(address "$render_job")
draw "$render_address"
echo "roles data and render: jobs $data_job and $render_job; the client drew run.h5 through both"
read -r -a data_pids <<<"$(job_pids "$data_job")"
read -r -a render_pids <<<"$(job_pids "$render_job")"
cancel "$render_job" "${render_pids[@]}"
cancel "$data_job" "${data_pids[@]}"
if pgrep -a -f "$work/(bin|data)"; then
  fail "processes of the jobs are left"
fi

# --- A job with a missing option fails with one line -----------------------
bad=$(submit --role render)
bad_done() { ! squeue -h -j "$bad" 2>/dev/null | grep -q .; }
until_true 30 bad_done || fail "job $bad without --data-server still runs"
grep -qx "crackvis.sbatch: --role render needs --data-server HOST:PORT" "$work/job-$bad.out" ||
  fail "job $bad's output: $(cat "$work/job-$bad.out")"
echo "a job without --data-server failed with its one line"
echo "PASS"
