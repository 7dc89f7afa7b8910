#!/usr/bin/env bash
# A private single-node Slurm on this machine, for tests and trying the sweep scripts:
# munged, slurmctld and slurmd from Debian's packages (slurm-wlm, munge), with every file
# (key, configuration, state, logs, sockets) under DIR and ports of their own, so it does
# not touch a Slurm or munge the machine may already run.
#
#   scripts/slurm/local_cluster.sh start DIR   # prints `export SLURM_CONF=...` on success
#   scripts/slurm/local_cluster.sh stop DIR
#
# Needs root (slurmd starts jobs as their user). Exits 2, saying why, where Slurm cannot
# start here (not installed, not root, the node never comes up), so a test can skip.
set -euo pipefail

usage() { echo "usage: $0 start|stop DIR" >&2; exit 64; }
[ $# -eq 2 ] || usage
action=$1
dir=$(mkdir -p "$2" && cd "$2" && pwd)
conf=$dir/etc/slurm.conf

cannot() { echo "local_cluster: cannot start Slurm here: $*" >&2; exit 2; }

stop() {
  for pid_file in "$dir"/run/slurmd.pid "$dir"/run/slurmctld.pid "$dir"/run/munged.pid; do
    [ -f "$pid_file" ] || continue
    pid=$(cat "$pid_file")
    kill "$pid" 2>/dev/null || true
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -9 "$pid" 2>/dev/null || true
    rm -f "$pid_file"
  done
}

start() {
  for tool in munged slurmctld slurmd sbatch scontrol sinfo; do
    command -v "$tool" >/dev/null || cannot "$tool is not installed (Debian: apt-get install slurm-wlm munge)"
  done
  [ "$(id -u)" -eq 0 ] || cannot "slurmd needs root"
  stop
  mkdir -p "$dir"/{etc,munge,run,log,state,spool}
  chmod 700 "$dir/munge"
  # A fresh key per cluster: only processes given this folder's socket can authenticate.
  dd if=/dev/urandom of="$dir/munge/munge.key" bs=1024 count=1 status=none
  chmod 400 "$dir/munge/munge.key"
  munged --force --key-file="$dir/munge/munge.key" --socket="$dir/munge/munge.socket" \
    --pid-file="$dir/run/munged.pid" --log-file="$dir/log/munged.log" --seed-file="$dir/munge/munge.seed" \
    || cannot "munged did not start ($dir/log/munged.log)"

  local host node ctl_port
  host=$(hostname -s)
  # What slurmd finds on this machine (CPUs, sockets, memory): a node described as larger
  # than it is would be drained.
  node=$(slurmd -C | head -1 | sed 's/ UpTime=.*//')
  # Ports of its own, from the folder's name, so that two clusters (or a system Slurm) differ.
  ctl_port=$(( 20000 + $(printf '%s' "$dir" | cksum | cut -d' ' -f1) % 20000 ))
  cat > "$conf" <<CONF
ClusterName=segslam-local
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
SlurmctldPort=$ctl_port
SlurmdPort=$((ctl_port + 1))
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$dir/munge/munge.socket
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/run/slurmctld.pid
SlurmdPidFile=$dir/run/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
SwitchType=switch/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
SlurmdTimeout=60
$node NodeAddr=127.0.0.1 State=UNKNOWN
PartitionName=local Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
  export SLURM_CONF=$conf
  slurmctld -f "$conf" || cannot "slurmctld did not start ($dir/log/slurmctld.log)"
  slurmd -f "$conf" || cannot "slurmd did not start ($dir/log/slurmd.log)"
  for _ in $(seq 60); do
    state=$(sinfo -h -N -o '%t' 2>/dev/null | head -1 || true)
    case "$state" in idle|mix|alloc) echo "export SLURM_CONF=$conf"; return 0 ;; esac
    sleep 0.5
  done
  tail -5 "$dir/log/slurmctld.log" "$dir/log/slurmd.log" >&2 || true
  stop
  cannot "the node never became idle (state '${state:-none}'; logs in $dir/log)"
}

case "$action" in
  start) start ;;
  stop) stop ;;
  *) usage ;;
esac
