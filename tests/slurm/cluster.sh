#!/usr/bin/env bash
# A single-node Slurm cluster on this machine, for partlife's Slurm executor tests.
#
#   tests/slurm/cluster.sh start DIR   # munged, slurmctld and slurmd with a generated slurm.conf in DIR
#   tests/slurm/cluster.sh stop DIR    # stops the daemons it started, by their process ids
#
# Needs root and the Debian packages slurm-wlm and munge (apt-get install slurm-wlm munge). The
# configuration lives in DIR/slurm.conf (the node line from `slurmd -C`: this machine's hostname,
# CPUs and memory); clients find it through SLURM_CONF=DIR/slurm.conf, which `start` prints.
# Nothing under /etc is changed; munged uses the package's /etc/munge/munge.key (created if absent).
set -euo pipefail
cmd=${1:?usage: cluster.sh start|stop DIR}
dir=$(realpath -m "${2:?usage: cluster.sh start|stop DIR}")

stop() {
    for d in slurmd slurmctld munged; do
        if [[ -f "$dir/$d.pid" ]]; then
            pid=$(cat "$dir/$d.pid")
            kill "$pid" 2>/dev/null || true
            for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
            kill -9 "$pid" 2>/dev/null || true
            rm -f "$dir/$d.pid"
        fi
    done
}

case "$cmd" in
stop)
    stop
    exit 0
    ;;
start) ;;
*)
    echo "usage: cluster.sh start|stop DIR" >&2
    exit 2
    ;;
esac

for b in munged slurmctld slurmd sbatch squeue scontrol; do
    command -v "$b" >/dev/null || { echo "cluster.sh: $b not found (apt-get install slurm-wlm munge)" >&2; exit 3; }
done
[[ $(id -u) == 0 ]] || { echo "cluster.sh: the daemons are started as root" >&2; exit 3; }

mkdir -p "$dir/state" "$dir/spool" "$dir/munge"
chown munge:munge "$dir/munge"
chmod 711 "$dir/munge"
if [[ ! -f /etc/munge/munge.key ]]; then
    mkdir -p /etc/munge
    dd if=/dev/urandom of=/etc/munge/munge.key bs=1 count=128 status=none
    chown munge:munge /etc/munge/munge.key
    chmod 400 /etc/munge/munge.key
fi
# munged: its own socket in DIR, so a machine's own munged (if any) is untouched.
socket="$dir/munge/munge.socket"
runuser -u munge -- munged --socket="$socket" --pid-file="$dir/munge/munged.pid" --log-file="$dir/munge/munged.log" --seed-file="$dir/munge/seed"
for _ in $(seq 50); do [[ -S "$socket" ]] && break; sleep 0.1; done
cp "$dir/munge/munged.pid" "$dir/munged.pid"

node=$(slurmd -C | head -1)
host=$(hostname)
cat > "$dir/slurm.conf" <<CONF
ClusterName=partlife
SlurmctldHost=$host
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$socket
CredType=cred/munge
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldPort=6817
SlurmdPort=6818
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SwitchType=switch/none
MpiDefault=none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MinJobAge=3600
MaxArraySize=10001
$node State=UNKNOWN
PartitionName=debug Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF="$dir/slurm.conf"
slurmctld -f "$SLURM_CONF"
slurmd -f "$SLURM_CONF"
for _ in $(seq 100); do
    if sinfo -h -o %T 2>/dev/null | grep -qx idle; then
        echo "SLURM_CONF=$SLURM_CONF"
        exit 0
    fi
    sleep 0.2
done
echo "cluster.sh: the node did not come up idle; slurmctld.log and slurmd.log are in $dir" >&2
tail -5 "$dir/slurmctld.log" "$dir/slurmd.log" >&2 || true
stop
exit 1
