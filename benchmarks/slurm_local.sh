#!/usr/bin/env bash
# Bring up a single-node Slurm on this machine from Debian's packages, for running the workflow's
# SLURM profile for real (tests/workflow/test_slurm_real.py runs it).
#
#   sudo benchmarks/slurm_local.sh up      # install (apt) if needed, configure, start the daemons
#   benchmarks/slurm_local.sh status       # sinfo + a test job
#   sudo benchmarks/slurm_local.sh down    # stop the daemons
#
# What it takes (tried on Debian 12, slurm-wlm 22.05): munge alone is not enough -- the executor
# plugin asks `sacct` whether a job finished, so without accounting it never sees one and the run
# stalls after the first job. Hence slurmdbd + MariaDB (accounting_storage/slurmdbd) and
# `sacctmgr add cluster`. Containers have no systemd and no cgroup delegation: the daemons run in
# the foreground-less classic way as root, with proctrack/linuxproc and task/none.
set -euo pipefail

CLUSTER=granudep
HOST=$(hostname -s)
CPUS=$(nproc)
MEM_MB=$(awk '/MemTotal/ {print int($2 / 1024 * 0.8)}' /proc/meminfo)
ETC=/etc/slurm
STATE=/var/lib/slurm
LOGDIR=/var/log/slurm

wait_for() {  # wait_for SECONDS CMD...: retry CMD until it succeeds
    local n=$1; shift
    for _ in $(seq "$n"); do "$@" >/dev/null 2>&1 && return 0; sleep 1; done
    echo "slurm_local: timed out waiting for: $*" >&2; return 1
}

up() {
    if ! command -v slurmctld >/dev/null || ! command -v slurmdbd >/dev/null || ! command -v mysqld >/dev/null; then
        DEBIAN_FRONTEND=noninteractive apt-get install -y -q slurm-wlm slurmdbd munge mariadb-server >/dev/null
    fi
    mkdir -p "$ETC" "$STATE/slurmctld" "$STATE/slurmd" "$LOGDIR" /run/munge /run/mysqld /run/slurm
    # munge: a key and the daemon
    if [ ! -s /etc/munge/munge.key ]; then
        (command -v mungekey >/dev/null && mungekey --create --keyfile=/etc/munge/munge.key) \
            || dd if=/dev/urandom of=/etc/munge/munge.key bs=1024 count=1 status=none
    fi
    chown -R munge: /etc/munge /run/munge /var/lib/munge /var/log/munge 2>/dev/null || true
    chmod 400 /etc/munge/munge.key
    pgrep -x munged >/dev/null || runuser -u munge -- /usr/sbin/munged
    wait_for 20 munge -n
    # MariaDB with the accounting database
    chown mysql: /run/mysqld
    pgrep -x mariadbd >/dev/null || pgrep -x mysqld >/dev/null || (mysqld_safe --user=mysql >/dev/null 2>&1 &)
    wait_for 60 mysqladmin ping
    mysql -e "CREATE USER IF NOT EXISTS 'slurm'@'localhost' IDENTIFIED BY 'slurm';
              GRANT ALL ON slurm_acct_db.* TO 'slurm'@'localhost'; FLUSH PRIVILEGES;"
    cat > "$ETC/slurmdbd.conf" <<EOF
AuthType=auth/munge
DbdHost=localhost
SlurmUser=root
LogFile=$LOGDIR/slurmdbd.log
PidFile=/run/slurm/slurmdbd.pid
StorageType=accounting_storage/mysql
StorageHost=localhost
StorageUser=slurm
StoragePass=slurm
StorageLoc=slurm_acct_db
EOF
    chmod 600 "$ETC/slurmdbd.conf"
    cat > "$ETC/slurm.conf" <<EOF
ClusterName=$CLUSTER
SlurmctldHost=$HOST
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
StateSaveLocation=$STATE/slurmctld
SlurmdSpoolDir=$STATE/slurmd
SlurmctldPidFile=/run/slurm/slurmctld.pid
SlurmdPidFile=/run/slurm/slurmd.pid
SlurmctldLogFile=$LOGDIR/slurmctld.log
SlurmdLogFile=$LOGDIR/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/slurmdbd
AccountingStorageHost=localhost
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
ReturnToService=2
MpiDefault=none
SchedulerType=sched/backfill
NodeName=$HOST CPUs=$CPUS RealMemory=$MEM_MB State=UNKNOWN
PartitionName=main Nodes=$HOST Default=YES MaxTime=INFINITE State=UP
EOF
    pgrep -x slurmdbd >/dev/null || slurmdbd
    wait_for 60 sacctmgr -n show cluster
    sacctmgr -i add cluster "$CLUSTER" >/dev/null 2>&1 || true
    sacctmgr -i add account default Cluster="$CLUSTER" >/dev/null 2>&1 || true
    sacctmgr -i add user "$(id -un)" Account=default >/dev/null 2>&1 || true
    pgrep -x slurmctld >/dev/null || slurmctld
    wait_for 60 scontrol ping
    pgrep -x slurmd >/dev/null || slurmd
    wait_for 60 sh -c "sinfo -h -o %T | grep -Eq 'idle|mixed|allocated'"
    scontrol update NodeName="$HOST" State=RESUME >/dev/null 2>&1 || true
    status
}

status() {
    sinfo
    srun -N1 -n1 -t 1 hostname
    echo "slurm $(sinfo -V | awk '{print $2}'), node $HOST: $CPUS CPUs, $MEM_MB MB"
}

down() {  # each daemon by the pid it wrote
    for f in /run/slurm/slurmd.pid /run/slurm/slurmctld.pid /run/slurm/slurmdbd.pid /run/munge/munged.pid; do
        [ -s "$f" ] && kill "$(cat "$f")" 2>/dev/null || true
    done
    mysqladmin shutdown 2>/dev/null || true
}

"${1:-up}"
