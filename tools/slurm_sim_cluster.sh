#!/usr/bin/env bash
# Starts a second Slurm cluster on this machine for `cargo bench --bench campaign_farm --
# --slurm`: NODES node entries (default 8) of CPUS CPUs each (default 8), all served by
# slurmd processes on this host (`slurmd -N <node>`, each on its own port), so Slurm's own
# scheduler places array tasks over many nodes while the tasks (the bench's timed stand-in
# for Blender, which mostly sleeps) run here. Its own ports (16817/16818 and 17001…), state
# and logs under DIR (default /tmp/egogen_slurm_sim): the single-node test cluster
# (tools/slurm_single_node.sh) is left alone. Needs root and munge running (that script
# starts it). Prints the SLURM_CONF line to export; `stop` as the first argument stops it.
#
#   tools/slurm_sim_cluster.sh [stop]
set -euo pipefail
dir=${DIR:-/tmp/egogen_slurm_sim}
nodes=${NODES:-8}
cpus=${CPUS:-8}
conf=$dir/slurm.conf
if [ "${1:-}" = stop ]; then
    for pid in "$dir"/*.pid; do [ -f "$pid" ] && kill "$(cat "$pid")" 2>/dev/null || true; done
    exit 0
fi
if [ "$(id -u)" != 0 ]; then
    echo "slurm_sim_cluster: must run as root to start slurmctld/slurmd" >&2
    exit 1
fi
munge -n >/dev/null 2>&1 || { echo "slurm_sim_cluster: munge is not running (tools/slurm_single_node.sh starts it)" >&2; exit 1; }
host=$(hostname -s)
last=$(printf '%02d' "$nodes")
mkdir -p "$dir/ctld" "$dir/log"
cat > "$conf" <<CONF
# Written by egogen tools/slurm_sim_cluster.sh: ${nodes} node entries on this host.
ClusterName=egogensim
SlurmctldHost=${host}
SlurmctldPort=16817
SlurmdPort=16818
SlurmUser=root
AuthType=auth/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
SchedulerType=sched/backfill
MpiDefault=none
ReturnToService=2
StateSaveLocation=${dir}/ctld
SlurmdSpoolDir=${dir}/d/%n
SlurmctldPidFile=${dir}/ctld.pid
SlurmdPidFile=${dir}/d_%n.pid
SlurmctldLogFile=${dir}/log/ctld.log
SlurmdLogFile=${dir}/log/d_%n.log
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
MinJobAge=300
MaxJobCount=50000
MaxArraySize=10001
SlurmdTimeout=60
SlurmdParameters=config_overrides
InactiveLimit=0
KillWait=5
NodeName=sim[01-${last}] NodeHostname=${host} Port=17001-$((17000 + nodes)) CPUs=${cpus} Boards=1 SocketsPerBoard=1 CoresPerSocket=${cpus} ThreadsPerCore=1 RealMemory=$((cpus * 256)) State=UNKNOWN
PartitionName=sim Nodes=sim[01-${last}] Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF=$conf
[ -f "$dir/ctld.pid" ] && kill -0 "$(cat "$dir/ctld.pid")" 2>/dev/null || slurmctld -f "$conf"
for n in $(seq -f '%02g' 1 "$nodes"); do
    mkdir -p "$dir/d/sim$n"
    pid=$dir/d_sim$n.pid
    [ -f "$pid" ] && kill -0 "$(cat "$pid")" 2>/dev/null || slurmd -f "$conf" -N "sim$n"
done
for _ in $(seq 1 60); do
    if sinfo -h -o '%T' 2>/dev/null | grep -qE 'idle|mix|alloc'; then
        echo "export SLURM_CONF=$conf"
        exit 0
    fi
    sleep 1
done
echo "slurm_sim_cluster: the cluster did not come up; see $dir/log" >&2
exit 1
