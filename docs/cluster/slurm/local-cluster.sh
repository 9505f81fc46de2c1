#!/usr/bin/env bash
# A single-node Slurm cluster on this machine, to run docs/cluster/slurm/submit.sh for real
# (.ci/cluster.sh, docs/cluster/README.md).
#
#   docs/cluster/slurm/local-cluster.sh start   # install, configure and start; wait until idle
#   docs/cluster/slurm/local-cluster.sh stop    # stop the daemons this script started
#   docs/cluster/slurm/local-cluster.sh status
#
# For a throw-away Debian machine or container (CI's): run as root. `start` installs what is
# missing with apt-get (Debian's slurmctld, slurmd, slurm-client and munge), writes
# /etc/slurm/slurm.conf for one node named `hostname -s` with the CPUs and memory `slurmd -C`
# reports (memory is not a consumable resource: jobs never wait for it), without cgroups or
# accounting, and starts munged, slurmctld and slurmd directly (no systemd: containers have
# no init). Starting again is harmless: running daemons are kept, a changed configuration
# restarts them. State and spool where Debian's packages put them (/var/lib/slurm/slurmctld,
# /var/lib/slurm/slurmd), logs under /var/log/slurm.
set -euo pipefail

conf_dir=/etc/slurm
conf=$conf_dir/slurm.conf
state_dir=/var/lib/slurm
logs=/var/log/slurm
ctld_pid=/run/slurmctld.pid
slurmd_pid=/run/slurmd.pid
munge_pid=/run/munge/munged.pid

say() { echo "local-cluster: $*"; }
die() {
    echo "local-cluster: error: $*" >&2
    exit 1
}

usage() {
    echo "usage: $0 start|stop|status" >&2
    exit 2
}

# The pid in FILE when that process is alive.
alive() {
    local pid
    [[ -f $1 ]] || return 1
    pid=$(cat "$1" 2>/dev/null) || return 1
    [[ $pid =~ ^[0-9]+$ ]] && kill -0 "$pid" 2>/dev/null
}

install_packages() {
    local missing=()
    command -v munged >/dev/null || missing+=(munge)
    command -v slurmctld >/dev/null || missing+=(slurmctld)
    command -v slurmd >/dev/null || missing+=(slurmd)
    command -v sbatch >/dev/null || missing+=(slurm-client)
    if [[ ${#missing[@]} -eq 0 ]]; then
        say "installed: $(slurmctld -V) and munge"
        return
    fi
    command -v apt-get >/dev/null ||
        die "${missing[*]} missing and no apt-get to install them (this script is for Debian)"
    say "installing ${missing[*]} with apt-get"
    local t0=$SECONDS log=/tmp/local-cluster-apt.log
    local install=(apt-get install -y -q --no-install-recommends "${missing[@]}")
    export DEBIAN_FRONTEND=noninteractive
    # The package lists of a fresh image may be empty or old: update once if needed.
    if ! "${install[@]}" >"$log" 2>&1; then
        if ! apt-get update -q >>"$log" 2>&1; then
            tail -20 "$log" >&2
            die "apt-get update failed (log: $log)"
        fi
        if ! "${install[@]}" >>"$log" 2>&1; then
            tail -20 "$log" >&2
            die "apt-get install ${missing[*]} failed (log: $log)"
        fi
    fi
    for c in munged slurmctld slurmd sbatch; do
        command -v $c >/dev/null || die "$c still missing after apt-get install ${missing[*]}"
    done
    say "installed $(slurmctld -V) and munge in $((SECONDS - t0)) s"
}

# The slurm.conf of a single node: this machine, as `slurmd -C` sees it.
write_conf() {
    local host hw cpus mem line
    host=$(hostname -s)
    [[ -n $host ]] || die "hostname -s is empty"
    hw=$(slurmd -C 2>/dev/null | head -1) || true
    [[ $hw == NodeName=* ]] ||
        die "slurmd -C printed no node line: '$(slurmd -C 2>&1 | head -3)'"
    # slurmd -C names the node by its own hostname; ours is `hostname -s`, reachable on
    # 127.0.0.1 whatever /etc/hosts says.
    line="NodeName=$host NodeAddr=127.0.0.1 ${hw#NodeName=* } State=UNKNOWN"
    cpus=$(grep -o 'CPUs=[0-9]*' <<<"$hw" | cut -d= -f2)
    mem=$(grep -o 'RealMemory=[0-9]*' <<<"$hw" | cut -d= -f2)
    mkdir -p "$conf_dir" "$state_dir/slurmctld" "$state_dir/slurmd" "$logs"
    local new
    new=$(mktemp)
    cat >"$new" <<EOF
# Written by docs/cluster/slurm/local-cluster.sh: a single-node cluster on $host
# ($cpus CPUs, $mem MB), without cgroups or accounting, for testing job scripts.
ClusterName=sss-local
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
AuthType=auth/munge
CredType=cred/munge
MpiDefault=none
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
# CPUs only: memory is not allocated, so no job waits for it.
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/backfill
ReturnToService=2
StateSaveLocation=$state_dir/slurmctld
SlurmdSpoolDir=$state_dir/slurmd
SlurmctldPidFile=$ctld_pid
SlurmdPidFile=$slurmd_pid
SlurmctldLogFile=$logs/slurmctld.log
SlurmdLogFile=$logs/slurmd.log
SlurmctldTimeout=30
SlurmdTimeout=30
# Finished jobs stay known to scontrol for 10 minutes (no accounting to ask afterwards).
MinJobAge=600
$line
PartitionName=local Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
    if [[ -f $conf ]] && cmp -s "$new" "$conf"; then
        rm -f "$new"
        say "$conf is current (node $host: $cpus CPUs, $mem MB)"
        return 1
    fi
    [[ -f $conf && ! -f $conf.orig ]] && cp "$conf" "$conf.orig"
    mv "$new" "$conf"
    chmod 644 "$conf"
    say "wrote $conf (node $host: $cpus CPUs, $mem MB)"
    return 0
}

start_munge() {
    if alive "$munge_pid"; then
        say "munged running (pid $(cat "$munge_pid"))"
        return
    fi
    id munge >/dev/null 2>&1 || die "no user munge (the munge package creates it)"
    if [[ ! -s /etc/munge/munge.key ]]; then
        mkdir -p /etc/munge
        if command -v mungekey >/dev/null; then
            mungekey --create --keyfile=/etc/munge/munge.key >/dev/null
        else
            dd if=/dev/urandom of=/etc/munge/munge.key bs=1024 count=1 status=none
        fi
        say "created /etc/munge/munge.key"
    fi
    chown munge:munge /etc/munge /etc/munge/munge.key
    chmod 700 /etc/munge
    chmod 400 /etc/munge/munge.key
    install -d -o munge -g munge -m 755 /run/munge
    install -d -o munge -g munge -m 700 /var/lib/munge /var/log/munge
    runuser -u munge -- munged ||
        die "munged did not start: $(tail -5 /var/log/munge/munged.log 2>/dev/null)"
    local i
    for i in $(seq 50); do
        munge -n 2>/dev/null | unmunge >/dev/null 2>&1 && break
        sleep 0.2
    done
    munge -n | unmunge >/dev/null 2>&1 ||
        die "munge does not work: $(tail -5 /var/log/munge/munged.log 2>/dev/null)"
    say "started munged (pid $(cat "$munge_pid"))"
}

# start_daemon NAME PIDFILE
start_daemon() {
    local name=$1 pidfile=$2 i
    if alive "$pidfile"; then
        say "$name running (pid $(cat "$pidfile"))"
        return
    fi
    "$name" || die "$name did not start: $(tail -5 "$logs/$name.log" 2>/dev/null)"
    for i in $(seq 50); do
        alive "$pidfile" && break
        sleep 0.2
    done
    alive "$pidfile" || die "$name exited: $(tail -10 "$logs/$name.log" 2>/dev/null)"
    say "started $name (pid $(cat "$pidfile"), log $logs/$name.log)"
}

# stop_daemon NAME PIDFILE
stop_daemon() {
    local name=$1 pidfile=$2 pid i
    if ! alive "$pidfile"; then
        say "$name not running"
        return
    fi
    pid=$(cat "$pidfile")
    kill "$pid"
    for i in $(seq 100); do
        kill -0 "$pid" 2>/dev/null || break
        sleep 0.1
    done
    if kill -0 "$pid" 2>/dev/null; then
        kill -9 "$pid" 2>/dev/null || true
        say "killed $name (pid $pid)"
    else
        say "stopped $name (pid $pid)"
    fi
}

wait_idle() {
    local host state i
    host=$(hostname -s)
    for i in $(seq 120); do
        state=$(sinfo -h -N -n "$host" -o %T 2>/dev/null | head -1) || true
        case $state in
            idle | mixed | allocated | completing)
                say "node $host is $state: $(sinfo -h -o '%P %a %D nodes, %c CPUs, %m MB')"
                return
                ;;
            down* | drain* | fail*)
                # A restart may leave the node down: bring it back once it responds.
                scontrol update NodeName="$host" State=RESUME 2>/dev/null || true
                ;;
        esac
        sleep 0.5
    done
    scontrol show node "$host" >&2 || true
    tail -20 "$logs/slurmctld.log" "$logs/slurmd.log" >&2 || true
    die "node $host not idle after 60 s (state '${state:-none}')"
}

start() {
    [[ $(id -u) -eq 0 ]] ||
        die "run as root: it installs packages, writes /etc/slurm and starts daemons"
    local t0=$SECONDS
    install_packages
    local t1=$SECONDS
    if write_conf; then
        # A new configuration: daemons started with the old one start again.
        if alive "$slurmd_pid" || alive "$ctld_pid"; then
            stop_daemon slurmd "$slurmd_pid"
            stop_daemon slurmctld "$ctld_pid"
        fi
    fi
    start_munge
    start_daemon slurmctld "$ctld_pid"
    start_daemon slurmd "$slurmd_pid"
    wait_idle
    say "ready: packages $((t1 - t0)) s, configuration and daemons $((SECONDS - t1)) s"
}

stop() {
    [[ $(id -u) -eq 0 ]] || die "run as root"
    stop_daemon slurmd "$slurmd_pid"
    stop_daemon slurmctld "$ctld_pid"
    stop_daemon munged "$munge_pid"
}

status() {
    local n
    for n in "munged $munge_pid" "slurmctld $ctld_pid" "slurmd $slurmd_pid"; do
        set -- $n
        if alive "$2"; then say "$1 running (pid $(cat "$2"))"; else say "$1 not running"; fi
    done
    if alive "$ctld_pid"; then sinfo; fi
}

case ${1:-} in
    start) start ;;
    stop) stop ;;
    status) status ;;
    *) usage ;;
esac
