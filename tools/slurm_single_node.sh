#!/usr/bin/env bash
# Starts a single-node Slurm cluster on this machine (Debian's slurm-wlm + munge) for egogen's
# Slurm backend test: munged, slurmctld and slurmd as root, one partition `egogen` holding this
# host with all its CPUs and memory; no accounting database (jobs are followed with squeue and
# the job-completion log). Idempotent: does nothing when `sinfo` already answers.
#
#   sudo tools/slurm_single_node.sh         # install first: apt-get install slurmctld slurmd slurm-client munge
#
# Exit status: 0 when the cluster answers, 1 when it could not be started (reason on stderr).
set -euo pipefail

if sinfo -h >/dev/null 2>&1; then
    exit 0
fi
for bin in munged slurmctld slurmd sinfo; do
    command -v "$bin" >/dev/null || { echo "slurm_single_node: $bin not found (apt-get install slurmctld slurmd slurm-client munge)" >&2; exit 1; }
done
if [ "$(id -u)" != 0 ]; then
    echo "slurm_single_node: must run as root to start munged/slurmctld/slurmd" >&2
    exit 1
fi

host=$(hostname -s)
# This host as slurmd sees it (sockets, cores, threads), with 90 % of its memory schedulable.
mem_mb=$(awk '/MemTotal/ {print int($2 / 1024 * 0.9)}' /proc/meminfo)
node=$(slurmd -C | head -1 | sed -E "s/RealMemory=[0-9]+/RealMemory=${mem_mb}/")

# munge: a key, then the daemon.
mkdir -p /etc/munge /var/lib/munge /var/log/munge /run/munge
if [ ! -s /etc/munge/munge.key ]; then
    dd if=/dev/urandom bs=1 count=1024 of=/etc/munge/munge.key 2>/dev/null
fi
chown -R munge:munge /etc/munge /var/lib/munge /var/log/munge /run/munge 2>/dev/null || true
chmod 0700 /etc/munge
chmod 0400 /etc/munge/munge.key
if ! munge -n >/dev/null 2>&1; then
    munged --force 2>/dev/null || su -s /bin/sh munge -c "munged --force"
fi

mkdir -p /etc/slurm /var/spool/slurmctld /var/spool/slurmd /var/log/slurm
cat > /etc/slurm/slurm.conf <<CONF
# Written by egogen tools/slurm_single_node.sh: a single-node test cluster.
ClusterName=egogen
SlurmctldHost=${host}
SlurmUser=root
AuthType=auth/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
DefMemPerCPU=1024
SchedulerType=sched/backfill
MpiDefault=none
ReturnToService=2
StateSaveLocation=/var/spool/slurmctld
SlurmdSpoolDir=/var/spool/slurmd
SlurmctldPidFile=/run/slurmctld.pid
SlurmdPidFile=/run/slurmd.pid
SlurmctldLogFile=/var/log/slurm/slurmctld.log
SlurmdLogFile=/var/log/slurm/slurmd.log
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/filetxt
JobCompLoc=/var/log/slurm/jobcomp.log
MinJobAge=600
SlurmdTimeout=60
InactiveLimit=0
KillWait=5
${node} State=UNKNOWN
PartitionName=egogen Nodes=${host} Default=YES MaxTime=INFINITE State=UP
CONF

pgrep -x slurmctld >/dev/null || slurmctld
pgrep -x slurmd >/dev/null || slurmd
for _ in $(seq 1 60); do
    if sinfo -h -o '%T' 2>/dev/null | grep -qE 'idle|mix|alloc'; then
        exit 0
    fi
    sleep 1
done
echo "slurm_single_node: the cluster did not come up in 60 s; see /var/log/slurm/slurmctld.log and slurmd.log" >&2
tail -5 /var/log/slurm/slurmctld.log /var/log/slurm/slurmd.log >&2 || true
exit 1
