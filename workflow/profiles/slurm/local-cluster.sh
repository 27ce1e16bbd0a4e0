#!/usr/bin/env bash
# A single-node SLURM cluster on this machine, to try the slurm profile before a real
# cluster (docs/cluster.md) and for the integration test (tests/test_slurm.py).
#
#   workflow/profiles/slurm/local-cluster.sh start    # write slurm.conf, start munged, slurmctld, slurmd; wait until idle
#   workflow/profiles/slurm/local-cluster.sh status   # sinfo
#   workflow/profiles/slurm/local-cluster.sh stop     # stop the daemons started by `start`, remove its slurm.conf
#
# Needs root and Debian's slurm-wlm and munge (apt-get install slurm-wlm munge). One node:
# this host with its CPUs and memory (less RAILRADIO_SLURM_RESERVE_MB for the system), one
# partition `local`, no accounting database: job states come from squeue, so finished jobs
# are kept there for MinJobAge (10 min) — run Snakemake with --slurm-status-command squeue.
# The configuration goes to SLURM's default path, /etc/slurm/slurm.conf (the executor plugin
# clears SLURM_* variables, SLURM_CONF among them, before the job steps' srun reads it); a
# configuration there that this script did not write is never replaced. `stop` removes the
# configuration it wrote: left behind, it names a controller that no longer answers, and every
# later `scontrol show config` waits ~9 s for it (the executor plugin runs that command each
# time Snakemake starts, installed plugins being loaded whatever the profile). State, logs and
# pid files live under RAILRADIO_SLURM_DIR (default $TMPDIR/railradio-slurm).
set -euo pipefail

dir=${RAILRADIO_SLURM_DIR:-${TMPDIR:-/tmp}/railradio-slurm}
reserve_mb=${RAILRADIO_SLURM_RESERVE_MB:-2048}
conf=/etc/slurm/slurm.conf
marker="# written by railradio's local-cluster.sh"

need() { command -v "$1" >/dev/null 2>&1 || { echo "local-cluster: $1 not found (apt-get install slurm-wlm munge)" >&2; exit 2; }; }

write_conf() {
  local host cpus mem
  host=$(hostname -s)
  cpus=$(nproc)
  mem=$(( $(awk '/MemTotal/ {print int($2 / 1024)}' /proc/meminfo) - reserve_mb ))
  if [ -e "$conf" ] && ! head -n1 "$conf" | grep -qF "$marker"; then
    echo "local-cluster: $conf exists and is not ours; not replacing it" >&2
    exit 2
  fi
  mkdir -p /etc/slurm "$dir/state" "$dir/spool" "$dir/log" "$dir/run"
  cat > "$conf" <<EOF
$marker
ClusterName=railradio-local
SlurmctldHost=$host
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/run/slurmctld.pid
SlurmdPidFile=$dir/run/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
SlurmctldPort=${RAILRADIO_SLURMCTLD_PORT:-6817}
SlurmdPort=${RAILRADIO_SLURMD_PORT:-6818}
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
SchedulerType=sched/backfill
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
MpiDefault=none
ReturnToService=2
MinJobAge=600
KillWait=5
OverTimeLimit=0
InactiveLimit=0
SlurmdTimeout=60
NodeName=$host CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=local Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
}

wait_idle() {
  local i state
  for i in $(seq 1 60); do
    state=$(sinfo -h -o '%t' 2>/dev/null | head -n1 || true)
    if [ "$state" = "idle" ] || [ "$state" = "mix" ]; then
      echo "local-cluster: node $(hostname -s) $state ($(nproc) CPUs), configuration $conf"
      return 0
    fi
    sleep 1
  done
  echo "local-cluster: the node did not become idle; logs in $dir/log" >&2
  tail -n 20 "$dir/log/slurmctld.log" "$dir/log/slurmd.log" >&2 || true
  return 1
}

start() {
  need munged; need slurmctld; need slurmd; need sinfo
  write_conf
  stop_daemons  # a cluster this script started before: its daemons are replaced (its jobs are lost)
  if ! pgrep -x munged >/dev/null; then
    if [ ! -s /etc/munge/munge.key ]; then
      mkdir -p /etc/munge
      dd if=/dev/urandom of=/etc/munge/munge.key bs=1 count=1024 status=none
    fi
    chown -R munge:munge /etc/munge 2>/dev/null || true
    chmod 400 /etc/munge/munge.key
    mkdir -p /run/munge /var/lib/munge /var/log/munge
    chown munge:munge /run/munge /var/lib/munge /var/log/munge 2>/dev/null || true
    if id munge >/dev/null 2>&1; then
      runuser -u munge -- munged
    else
      munged --force
    fi
  fi
  slurmctld -c
  slurmd -c
  wait_idle
}

stop_daemons() {
  local f
  for f in "$dir/run/slurmd.pid" "$dir/run/slurmctld.pid"; do
    if [ -s "$f" ]; then kill "$(cat "$f")" 2>/dev/null || true; fi
  done
  sleep 1
}

stop() {
  stop_daemons
  if [ -e "$conf" ] && head -n1 "$conf" | grep -qF "$marker"; then rm -f "$conf"; fi
}

case "${1:-}" in
  start) start ;;
  stop) stop ;;
  status) sinfo ;;
  conf) echo "$conf" ;;
  *) echo "usage: $0 start|status|stop|conf" >&2; exit 2 ;;
esac
