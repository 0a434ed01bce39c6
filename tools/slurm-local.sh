#!/usr/bin/env bash
# A one-node Slurm on this machine, for the tests of `myriad slurm` (run as root; Debian).
#
#   tools/slurm-local.sh start   installs slurm-wlm and munge if missing, writes a munge key and
#                                /etc/slurm/slurm.conf for this machine's cores and memory,
#                                starts munged, slurmctld and slurmd, waits for the node
#   tools/slurm-local.sh stop    stops the daemons this script started (by their pid files)
#
# No systemd is needed; accounting (slurmdbd, sacct) is left out: follow jobs with squeue.
set -euo pipefail

PIDS=(/run/slurmd.pid /run/slurmctld.pid /run/munge/munged.pid)

start() {
    if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
        echo "installing slurm-wlm and munge"
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq slurm-wlm munge >/dev/null
    fi
    mkdir -p /etc/munge /var/lib/munge /var/log/munge /run/munge /etc/slurm \
        /var/spool/slurmctld /var/spool/slurmd /var/log/slurm
    [ -f /etc/munge/munge.key ] || dd if=/dev/urandom bs=1 count=1024 of=/etc/munge/munge.key 2>/dev/null
    chown -R munge:munge /etc/munge /var/lib/munge /var/log/munge /run/munge
    chmod 400 /etc/munge/munge.key
    chmod 700 /etc/munge
    [ -f /run/munge/munged.pid ] && kill -0 "$(cat /run/munge/munged.pid)" 2>/dev/null || /usr/sbin/munged --force
    local host cpus mem
    host=$(hostname -s)
    cpus=$(nproc)
    mem=$(( $(awk '/MemTotal/ {print $2}' /proc/meminfo) / 1024 * 3 / 4 ))
    cat > /etc/slurm/slurm.conf <<CONF
ClusterName=local
SlurmctldHost=$host
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
StateSaveLocation=/var/spool/slurmctld
SlurmdSpoolDir=/var/spool/slurmd
SlurmctldPidFile=/run/slurmctld.pid
SlurmdPidFile=/run/slurmd.pid
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
ReturnToService=2
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SlurmctldLogFile=/var/log/slurm/slurmctld.log
SlurmdLogFile=/var/log/slurm/slurmd.log
NodeName=$host CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=debug Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
    running /run/slurmctld.pid || slurmctld
    running /run/slurmd.pid || slurmd
    for _ in $(seq 60); do
        if sinfo -h -o '%T' 2>/dev/null | grep -qE 'idle|mixed|alloc'; then
            echo "slurm: node $host up ($cpus CPUs, $mem MB)"
            return 0
        fi
        sleep 1
    done
    echo "slurm: the node did not come up; see /var/log/slurm/" >&2
    return 1
}

running() {
    [ -f "$1" ] && kill -0 "$(cat "$1")" 2>/dev/null
}

stop() {
    for p in "${PIDS[@]}"; do
        if running "$p"; then
            kill "$(cat "$p")" || true
        fi
    done
    echo "slurm: stopped"
}

case "${1:-}" in
    start) start ;;
    stop) stop ;;
    *) echo "usage: $0 start|stop" >&2; exit 2 ;;
esac
