#!/usr/bin/env bash
# Stands up a one-node Slurm cluster on this machine (munged + slurmctld + slurmd from Debian's
# slurm-wlm and munge, configured for localhost and this machine's cores and memory, everything
# under a temporary folder, ports of its own), runs a command against it (SLURM_CONF exported),
# and stops the daemons (by their PIDs) however the command ends.
#
# usage: local_slurm.sh [--install] [--keep DIR] -- COMMAND [ARGS...]
#   --install   apt-get install slurm-wlm munge when missing (needs root and the Debian mirror)
#   --keep DIR  use DIR for the cluster's files and keep it (logs) instead of a temporary folder
# Environment: SIMREEL_SLURM_PORT (slurmctld port; slurmd uses the next one). Default: two free
# ports found at start, so clusters of concurrent runs do not meet.
# Runs as root (SlurmUser=SlurmdUser=root): meant for containers and CI machines.
set -euo pipefail

install=0 keep=""
while [[ $# -gt 0 ]]; do
  case $1 in
    --install) install=1; shift ;;
    --keep) keep=$2; shift 2 ;;
    --) shift; break ;;
    *) echo "local_slurm.sh: unknown option $1" >&2; exit 2 ;;
  esac
done
[[ $# -ge 1 ]] || { echo "usage: local_slurm.sh [--install] [--keep DIR] -- COMMAND [ARGS...]" >&2; exit 2; }

if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
  if [[ $install -eq 1 ]]; then
    DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends slurm-wlm munge >/dev/null
  else
    echo "local_slurm.sh: slurmctld/munged not found (apt-get install slurm-wlm munge, or pass --install)" >&2
    exit 77
  fi
fi
[[ $(id -u) -eq 0 ]] || { echo "local_slurm.sh: must run as root (SlurmdUser=root)" >&2; exit 77; }

if [[ -n $keep ]]; then mkdir -p "$keep"; dir=$(realpath "$keep"); else dir=$(mktemp -d /tmp/simreel-slurm-XXXXXX); fi
mkdir -p "$dir/state" "$dir/spool"
# Two adjacent free ports from a random start (concurrent clusters do not pick the same).
free_port_pair() {
  python3 - <<'PY'
import random, socket
for _ in range(200):
    base = random.randrange(20000, 60000, 2)
    socks = []
    try:
        for p in (base, base + 1):
            s = socket.socket()
            socks.append(s)
            s.bind(("127.0.0.1", p))
        print(base)
        break
    except OSError:
        pass
    finally:
        for s in socks:
            s.close()
PY
}
port=${SIMREEL_SLURM_PORT:-$(free_port_pair)}
[[ -n $port ]] || { echo "local_slurm.sh: no free port pair" >&2; exit 1; }
pids=()
cleanup() {
  local rc=$?
  # Stop what this script started, by PID, newest first.
  for ((i = ${#pids[@]} - 1; i >= 0; i--)); do kill "${pids[i]}" 2>/dev/null || true; done
  for p in "${pids[@]}"; do
    for _ in $(seq 50); do kill -0 "$p" 2>/dev/null || break; sleep 0.1; done
    kill -9 "$p" 2>/dev/null || true
  done
  [[ -z $keep ]] && rm -rf "$dir"
  exit $rc
}
trap cleanup EXIT INT TERM

# munge: a fresh key and a socket of our own.
dd if=/dev/urandom of="$dir/munge.key" bs=1024 count=1 status=none
chmod 400 "$dir/munge.key"
munged --foreground --force --key-file="$dir/munge.key" --socket="$dir/munge.socket" \
  --pid-file="$dir/munged.pid" --log-file="$dir/munged.log" --seed-file="$dir/munged.seed" 2>"$dir/munged.out" &
pids+=($!)
for _ in $(seq 50); do [[ -S $dir/munge.socket ]] && break; sleep 0.1; done
[[ -S $dir/munge.socket ]] || { echo "local_slurm.sh: munged did not start ($dir/munged.log)" >&2; exit 1; }

cpus=$(nproc)
mem=$(( $(awk '/MemTotal/ {print int($2 / 1024)}' /proc/meminfo) * 9 / 10 ))
cat > "$dir/slurm.conf" <<CONF
ClusterName=simreel
SlurmctldHost=localhost
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$dir/munge.socket
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
ReturnToService=2
MpiDefault=none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SwitchType=switch/none
SlurmctldTimeout=30
SlurmdTimeout=60
InactiveLimit=0
MinJobAge=300
KillWait=5
NodeName=localhost NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=simreel Nodes=localhost Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF=$dir/slurm.conf

slurmctld -D -i -f "$SLURM_CONF" >"$dir/slurmctld.out" 2>&1 &
pids+=($!)
slurmd -D -N localhost -f "$SLURM_CONF" >"$dir/slurmd.out" 2>&1 &
pids+=($!)
ok=0
for _ in $(seq 100); do
  if sinfo -h -N -o '%T' 2>/dev/null | grep -qE '^(idle|mixed|allocated)'; then ok=1; break; fi
  sleep 0.2
done
if [[ $ok -ne 1 ]]; then
  echo "local_slurm.sh: the node did not come up; logs:" >&2
  tail -n 20 "$dir/slurmctld.log" "$dir/slurmd.log" "$dir/slurmctld.out" "$dir/slurmd.out" >&2 2>/dev/null || true
  exit 1
fi
echo "local_slurm.sh: one-node cluster up ($cpus CPUs, ${mem} MB; SLURM_CONF=$SLURM_CONF)"
"$@"
