#!/usr/bin/env bash
# A one-node Slurm cluster for tests: munged, slurmctld and slurmd, each started here in the
# foreground as a background job of this script, with its own config, state and spool
# directories, sockets, ports, logs and PID files under one directory. No systemd, no
# database, nothing installed (scripts/setup.sh installs slurmctld slurmd slurm-client
# munge). Stopping kills exactly the PIDs that `start` recorded.
#
#   bash scripts/slurm-local.sh start DIR   # prints `export SLURM_CONF=DIR/slurm.conf`
#   export SLURM_CONF=DIR/slurm.conf        # sbatch, squeue, scancel now talk to it
#   bash scripts/slurm-local.sh stop DIR
#
# Environment: SLURM_LOCAL_CPUS (CPUs the node offers; default: the cores).
set -euo pipefail

cmd=${1:-}
dir=${2:-}
if [[ -z "$cmd" || -z "$dir" ]]; then
  echo "usage: $0 start|stop DIR" >&2
  exit 2
fi

# Kills the process in PIDFILE (after checking it is still the program NAME), TERM then KILL.
stop_pid() {
  local pidfile=$1 name=$2 pid i
  [[ -f "$pidfile" ]] || return 0
  pid=$(cat "$pidfile")
  if [[ -n "$pid" && -d /proc/$pid ]] && grep -q "$name" "/proc/$pid/comm" 2>/dev/null; then
    kill -TERM "$pid" 2>/dev/null || true
    for i in $(seq 50); do
      [[ -d /proc/$pid ]] || break
      sleep 0.1
    done
    if [[ -d /proc/$pid ]]; then
      kill -KILL "$pid" 2>/dev/null || true
    fi
  fi
  rm -f "$pidfile"
}

case "$cmd" in
stop)
  dir=$(cd "$dir" 2>/dev/null && pwd) || exit 0
  if [[ -f "$dir/slurm.conf" && -f "$dir/slurmctld.pid" ]]; then
    # Cancel what is left in this cluster, so no job step outlives its slurmd.
    SLURM_CONF="$dir/slurm.conf" timeout 10 scancel --quiet --full --user "$(id -un)" 2>/dev/null || true
  fi
  stop_pid "$dir/slurmd.pid" slurmd
  stop_pid "$dir/slurmctld.pid" slurmctld
  stop_pid "$dir/munged.pid" munged
  exit 0
  ;;
start) ;;
*)
  echo "usage: $0 start|stop DIR" >&2
  exit 2
  ;;
esac

for prog in munged mungekey slurmctld slurmd sbatch sinfo scontrol; do
  command -v "$prog" >/dev/null || PATH="$PATH:/usr/sbin"
  if ! command -v "$prog" >/dev/null; then
    echo "slurm-local: $prog not found; run scripts/setup.sh (it installs slurmctld slurmd slurm-client munge)" >&2
    exit 1
  fi
done

mkdir -p "$dir"
dir=$(cd "$dir" && pwd)
if [[ -f "$dir/slurmctld.pid" ]] && [[ -d /proc/$(cat "$dir/slurmctld.pid") ]]; then
  echo "slurm-local: a cluster is already running in $dir (stop it first)" >&2
  exit 1
fi
mkdir -p "$dir/munge" "$dir/state" "$dir/spool" "$dir/log"
chmod 700 "$dir/munge"
user=$(id -un)
host=$(hostname -s)
cpus=${SLURM_LOCAL_CPUS:-$(nproc)}

# Two free TCP ports next to each other.
port_free() { ! (exec 3<>"/dev/tcp/127.0.0.1/$1") 2>/dev/null; }
for _ in $(seq 50); do
  base=$((20000 + RANDOM % 30000))
  if port_free "$base" && port_free $((base + 1)); then
    break
  fi
done

# munge: its own key, socket, seed, log and PID.
rm -f "$dir/munge/munge.key"
mungekey --create --keyfile="$dir/munge/munge.key" --force
chmod 400 "$dir/munge/munge.key"
nohup munged --foreground --force \
  --socket="$dir/munge/munge.socket" \
  --key-file="$dir/munge/munge.key" \
  --seed-file="$dir/munge/munge.seed" \
  --log-file="$dir/log/munged.log" \
  --pid-file="$dir/munge/munged.pidfile" \
  >"$dir/log/munged.out" 2>&1 &
echo $! >"$dir/munged.pid"
for _ in $(seq 50); do
  [[ -S "$dir/munge/munge.socket" ]] && break
  sleep 0.1
done
if [[ ! -S "$dir/munge/munge.socket" ]]; then
  echo "slurm-local: munged did not start:" >&2
  cat "$dir/log/munged.out" "$dir/log/munged.log" >&2 2>/dev/null || true
  exit 1
fi

cat >"$dir/slurm.conf" <<CONF
# Written by scripts/slurm-local.sh: a one-node test cluster under $dir.
ClusterName=fathomtest
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$base
SlurmdPort=$((base + 1))
SlurmUser=$user
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$dir/munge/munge.socket
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/state/slurmctld.pidfile
SlurmdPidFile=$dir/spool/slurmd.pidfile
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SchedulerType=sched/builtin
SchedulerParameters=batch_sched_delay=0,sched_min_interval=100000
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
MpiDefault=none
MailProg=/bin/true
LaunchParameters=enable_nss_slurm
ReturnToService=2
SlurmdParameters=config_overrides
MaxArraySize=100001
MinJobAge=600
KillWait=2
InactiveLimit=0
SlurmctldTimeout=30
SlurmdTimeout=30
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=test Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF

export SLURM_CONF="$dir/slurm.conf"
nohup slurmctld -D -f "$SLURM_CONF" -i >"$dir/log/slurmctld.out" 2>&1 &
echo $! >"$dir/slurmctld.pid"
nohup slurmd -D -f "$SLURM_CONF" -N "$host" >"$dir/log/slurmd.out" 2>&1 &
echo $! >"$dir/slurmd.pid"

# Ready when the node is idle.
state=""
for _ in $(seq 150); do
  state=$(sinfo -h -N -o %T 2>/dev/null | head -1 || true)
  [[ "$state" == idle* ]] && break
  sleep 0.2
done
if [[ "$state" != idle* ]]; then
  echo "slurm-local: the node did not become idle (state: '${state:-none}'); logs:" >&2
  tail -n 20 "$dir"/log/*.log "$dir"/log/*.out >&2 2>/dev/null || true
  bash "$0" stop "$dir"
  exit 1
fi
echo "export SLURM_CONF=$dir/slurm.conf"
