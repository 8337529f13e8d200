#!/usr/bin/env bash
# test-cluster.sh - a throw-away one-node Slurm cluster for voxlight's tests.
#
#   tools/cluster/test-cluster.sh start DIR   start munged, slurmctld and slurmd; all
#                                           state, logs, pid files and the munge
#                                           socket live under DIR; prints on stdout
#                                           the environment a client needs:
#                                             export SLURM_CONF=DIR/slurm.conf
#                                           so:  eval "$(test-cluster.sh start DIR)"
#   tools/cluster/test-cluster.sh stop DIR    cancel all jobs, stop the daemons (by
#                                           their pid files) and any job step left;
#                                           nothing of this cluster keeps running.
#   tools/cluster/test-cluster.sh status DIR  exit 0 if all three daemons run.
#
# Needs: Debian's slurmctld, slurmd, slurm-client and munge (apt-get install slurm-wlm
# munge), to be run as root (slurmd must run jobs as the submitting user), no systemd
# needed. The packages' own services are not used: the munge socket is DIR/munge/
# munged.sock, and slurm.conf points every daemon and client at it (AuthInfo=socket=).
#
# start refuses a DIR that is not empty unless it holds a cluster made by this script;
# starting a cluster that already runs only prints its environment again; starting a
# stopped one starts it again with a clean job state (slurmctld -c).
#
# Environment (all optional):
#   VOXLIGHT_SLURM_START_TIMEOUT  seconds to wait for the node to be idle (default 60)
#   VOXLIGHT_SLURM_PORT           first port to try for slurmctld (default 6817); slurmd
#                                 gets the next free one. Busy ports are skipped.
#   VOXLIGHT_SLURM_CPUS           CPUs of the node (default: nproc; more than nproc
#                                 is allowed: SlurmdParameters=config_overrides)
#   VOXLIGHT_SLURM_JOBCOMP        "none" (default) or "filetxt": job completion records
#                                 appended to DIR/jobcomp.txt (final state of every job,
#                                 also after MinJobAge forgot it; read it with
#                                 `sacct -c`; plain sacct needs slurmdbd).
#   VOXLIGHT_SLURM_SCHED_PARAMS   SchedulerParameters (default: the fast settings below;
#                                 "slurm-default" leaves Slurm's defaults).
set -euo pipefail

MARKER=.voxlight-test-cluster
PROG=${0##*/}

die()  { echo "$PROG: error: $*" >&2; exit 1; }
info() { echo "$PROG: $*" >&2; }

usage() {
    sed -n '2,/^set -euo/{/^set -euo/d;s/^# \{0,1\}//;p}' "$0" >&2
    exit 2
}

need() {
    local c
    for c in "$@"; do
        command -v "$c" >/dev/null 2>&1 ||
            die "'$c' not found: apt-get install -y slurm-wlm munge (Debian 12)"
    done
}

# ---- paths ------------------------------------------------------------------------
set_paths() {
    D=$1
    CONF=$D/slurm.conf
    MDIR=$D/munge
    MKEY=$MDIR/munge.key
    MSOCK=$MDIR/munged.sock
    MPID=$MDIR/munged.pid
    MLOG=$MDIR/munged.log
    MSEED=$MDIR/munged.seed
    LOGD=$D/log
    RUND=$D/run
    STATED=$D/state
    SPOOLD=$D/spool
    CPID=$RUND/slurmctld.pid
    DPID=$RUND/slurmd.pid
    CLOG=$LOGD/slurmctld.log
    DLOG=$LOGD/slurmd.log
}

# ---- processes --------------------------------------------------------------------
# pid from a pid file, only if that process is alive and is ours: its command line
# names this cluster's folder (so a reused pid is never killed).
our_pid() {
    local f=$1 pid
    [[ -s $f ]] || return 1
    pid=$(tr -dc '0-9' <"$f")
    [[ -n $pid && -r /proc/$pid/cmdline ]] || return 1
    local cmd
    cmd=$(tr '\0' ' ' <"/proc/$pid/cmdline" 2>/dev/null) || return 1
    [[ $cmd == *"$D/"* ]] || return 1
    echo "$pid"
}

# A process is alive until it is gone or a zombie with no thread left: a daemon's main
# thread may exit (zombie leader) while other threads still save state, and a
# zombie may never be reaped where PID 1 does not reap (containers).
alive() {
    local st threads
    [[ -d /proc/$1 ]] || return 1
    st=$(awk '{print $3}' "/proc/$1/stat" 2>/dev/null) || return 1
    [[ $st != Z ]] && return 0
    threads=$(ls "/proc/$1/task" 2>/dev/null | wc -l)
    ((threads > 1))
}

# kill_wait PID NAME: SIGTERM, wait up to 15 s, then SIGKILL.
kill_wait() {
    local pid=$1 name=$2 i
    alive "$pid" || return 0
    kill -TERM "$pid" 2>/dev/null || true
    for ((i = 0; i < 150; i++)); do alive "$pid" || return 0; sleep 0.1; done
    info "$name (pid $pid) ignored SIGTERM for 15 s: SIGKILL"
    kill -KILL "$pid" 2>/dev/null || true
    for ((i = 0; i < 50; i++)); do alive "$pid" || return 0; sleep 0.1; done
    die "$name (pid $pid) still running after SIGKILL"
}

# all descendants of a pid (children first listed after parents)
descendants() {
    local p c
    for p in "$@"; do
        for c in $(ps -o pid= --ppid "$p" 2>/dev/null); do
            echo "$c"
            descendants "$c"
        done
    done
}

# slurmstepd processes of this cluster: they hold unix sockets in DIR/spool
# (SlurmdSpoolDir/<node>_<job>.<step>); slurmstepd re-parents to init, so it is not a
# child of slurmd, and its command line does not name DIR.
our_stepds() {
    local inodes pid fd
    inodes=$(awk -v d="$SPOOLD/" 'index($NF, d) == 1 {print $7}' /proc/net/unix 2>/dev/null | sort -u)
    [[ -n $inodes ]] || return 0
    for pid in $(pgrep -x slurmstepd 2>/dev/null || true); do
        for fd in /proc/"$pid"/fd/*; do
            local l
            l=$(readlink "$fd" 2>/dev/null) || continue
            [[ $l == socket:\[*\] ]] || continue
            l=${l#socket:[}; l=${l%]}
            if grep -qx "$l" <<<"$inodes"; then echo "$pid"; break; fi
        done
    done
}

# ---- configuration ----------------------------------------------------------------
port_busy() { [[ -n $(ss -Htln "sport = :$1" 2>/dev/null) ]]; }

pick_ports() {
    local p=${VOXLIGHT_SLURM_PORT:-6817}
    while port_busy "$p"; do p=$((p + 1)); done
    CPORT=$p
    p=$((p + 1))
    while port_busy "$p"; do p=$((p + 1)); done
    DPORT=$p
}

write_conf() {
    local host cpus mem jobcomp sched
    host=$(hostname -s)
    cpus=${VOXLIGHT_SLURM_CPUS:-$(nproc)}
    # RealMemory: what free reports as total, less 5 % so slurmd never finds less
    # than configured (a node with less memory than RealMemory is drained).
    mem=$(free -m | awk '/^Mem:/ {print int($2 * 0.95)}')
    case ${VOXLIGHT_SLURM_JOBCOMP:-none} in
        none) jobcomp="JobCompType=jobcomp/none" ;;
        filetxt) jobcomp="JobCompType=jobcomp/filetxt
JobCompLoc=$D/jobcomp.txt" ;;
        *) die "VOXLIGHT_SLURM_JOBCOMP must be none or filetxt" ;;
    esac
    sched=${VOXLIGHT_SLURM_SCHED_PARAMS:-batch_sched_delay=0,sched_min_interval=0,sched_interval=5,bf_interval=5}
    if [[ $sched == slurm-default ]]; then sched="#SchedulerParameters="; else sched="SchedulerParameters=$sched"; fi
    cat >"$CONF.tmp" <<EOF
# Generated by tools/cluster/test-cluster.sh for a one-node test cluster; do not edit.
ClusterName=voxtest
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$CPORT
SlurmdPort=$DPORT
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$MSOCK
MpiDefault=none
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
$jobcomp
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
# config_overrides: the node's CPUs and memory are the configured ones, not the
# hardware's (VOXLIGHT_SLURM_CPUS may exceed nproc without the node being drained).
SlurmdParameters=config_overrides
StateSaveLocation=$STATED
SlurmdSpoolDir=$SPOOLD
SlurmctldPidFile=$CPID
SlurmdPidFile=$DPID
SlurmctldLogFile=$CLOG
SlurmdLogFile=$DLOG
SlurmctldDebug=info
SlurmdDebug=info
MailProg=/bin/true
# Fast turn-around for short test jobs: schedule at submit and at every job end
# without batching (batch_sched_delay), keep finished jobs 10 min for scontrol/squeue.
SchedulerType=sched/backfill
$sched
MessageTimeout=10
MinJobAge=600
KillWait=5
InactiveLimit=0
Waittime=0
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=debug Nodes=$host Default=YES MaxTime=INFINITE State=UP OverSubscribe=NO
EOF
    mv "$CONF.tmp" "$CONF"
    # slurmd (22.05) detects the cgroup version from what is mounted on /sys/fs/cgroup and
    # refuses to start where nothing is (a chroot, as the fresh-machine check runs in). The
    # test cluster's plugins (proctrack/linuxproc, task/none) use no cgroup: name v1 there.
    if [[ $(stat -f -c %T /sys/fs/cgroup 2>/dev/null) != @(tmpfs|cgroup2fs|cgroupfs) ]]; then
        echo "CgroupPlugin=cgroup/v1" >"$D/cgroup.conf"
    else
        rm -f "$D/cgroup.conf"
    fi
}

# ---- subcommands ------------------------------------------------------------------
running_all() {
    our_pid "$MPID" >/dev/null && our_pid "$CPID" >/dev/null && our_pid "$DPID" >/dev/null
}

print_env() {
    echo "export SLURM_CONF=$CONF"
}

show_logs() {
    local f
    for f in "$MLOG" "$CLOG" "$DLOG"; do
        [[ -s $f ]] || continue
        echo "---- last lines of $f" >&2
        tail -n 15 "$f" >&2
    done
}

cmd_start() {
    [[ $(id -u) == 0 ]] || die "must run as root (slurmd runs jobs as their submitters)"
    need munged slurmctld slurmd sinfo scontrol squeue scancel ss pgrep
    local dir=$1
    mkdir -p -- "$dir"
    set_paths "$(cd -- "$dir" && pwd -P)"
    if [[ -n $(ls -A -- "$D") ]]; then
        [[ -f $D/$MARKER ]] ||
            die "$D is not empty and holds no cluster of this script: refusing to use it"
        if running_all; then
            info "cluster in $D already runs"
            print_env
            return 0
        fi
        info "restarting the stopped cluster in $D"
        cmd_stop_inner quiet
    fi
    # A unix socket path is at most 107 bytes.
    ((${#MSOCK} < 100)) || die "$D is too long a path for the munge socket ($MSOCK)"

    echo "voxlight one-node test cluster; stop with: $0 stop $D" >"$D/$MARKER"
    chmod 755 "$D"
    mkdir -p "$MDIR" "$LOGD" "$RUND" "$STATED" "$SPOOLD"
    chmod 755 "$MDIR" "$LOGD" "$RUND"
    chmod 700 "$STATED" "$SPOOLD"
    if [[ ! -s $MKEY ]]; then
        (umask 077; dd if=/dev/urandom of="$MKEY.tmp" bs=1024 count=1 status=none)
        mv "$MKEY.tmp" "$MKEY"
    fi
    chmod 600 "$MKEY"
    pick_ports
    write_conf

    # An error from here on stops what was started.
    trap 'rc=$?; if ((rc)); then show_logs; info "start failed: stopping what was started"; cmd_stop_inner quiet || true; fi' EXIT

    rm -f "$MSOCK" "$MSOCK.lock"
    # munged as root: --force accepts running as root and the key owned by root.
    munged --force --socket="$MSOCK" --key-file="$MKEY" --log-file="$MLOG" \
        --pid-file="$MPID" --seed-file="$MSEED" ||
        die "munged did not start"
    wait_for 10 "munged socket" test -S "$MSOCK"
    if command -v munge >/dev/null; then
        munge -n --socket="$MSOCK" | unmunge --socket="$MSOCK" >/dev/null ||
            die "munge round trip on $MSOCK failed"
    fi

    # -c: clean job state (this cluster never resumes old jobs); -f: our slurm.conf.
    slurmctld -c -f "$CONF" || die "slurmctld did not start"
    wait_for 20 "slurmctld" scontrol -Q ping
    local host timeout i st=""
    host=$(hostname -s)
    # -N: the node's name as slurm.conf has it, whatever the resolver says of this host.
    slurmd -N "$host" -f "$CONF" || die "slurmd did not start"

    timeout=${VOXLIGHT_SLURM_START_TIMEOUT:-60}
    for ((i = 0; i < timeout * 5; i++)); do
        st=$(SLURM_CONF=$CONF sinfo -h -N -n "$host" -o %t 2>/dev/null | head -n1 || true)
        [[ $st == idle ]] && break
        sleep 0.2
    done
    [[ $st == idle ]] ||
        die "node $host not idle after $timeout s (state: '${st:-none}'); see $LOGD"
    our_pid "$MPID" >/dev/null && our_pid "$CPID" >/dev/null && our_pid "$DPID" >/dev/null ||
        die "a daemon exited after start"
    trap - EXIT
    info "cluster up in $D: node $host idle, slurmctld port $CPORT, slurmd port $DPORT"
    print_env
}

# wait_for SECONDS WHAT COMMAND...: poll COMMAND (with SLURM_CONF set) every 0.1 s
wait_for() {
    local secs=$1 what=$2 i
    shift 2
    for ((i = 0; i < secs * 10; i++)); do
        SLURM_CONF=$CONF "$@" >/dev/null 2>&1 && return 0
        sleep 0.1
    done
    die "$what not ready after $secs s"
}

cmd_stop_inner() {
    local quiet=${1:-} cpid dpid mpid p stepds
    cpid=$(our_pid "$CPID" || true)
    dpid=$(our_pid "$DPID" || true)
    mpid=$(our_pid "$MPID" || true)
    # 1. Cancel every job so slurmstepd ends its processes itself.
    if [[ -n $cpid && -n $mpid ]]; then
        local jobs i
        jobs=$(SLURM_CONF=$CONF squeue -h -o %i 2>/dev/null || true)
        if [[ -n $jobs ]]; then
            [[ -n $quiet ]] || info "cancelling jobs: $(echo $jobs)"
            SLURM_CONF=$CONF scancel --full $jobs 2>/dev/null || true
            for ((i = 0; i < 100; i++)); do
                [[ -z $(SLURM_CONF=$CONF squeue -h -t PD,R,CG,S -o %i 2>/dev/null) ]] && break
                sleep 0.1
            done
        fi
    fi
    # 2. Daemons: slurmd first (it reports to slurmctld), then slurmctld.
    [[ -z $dpid ]] || kill_wait "$dpid" slurmd
    [[ -z $cpid ]] || kill_wait "$cpid" slurmctld
    # 3. Job steps left behind (a job still running when slurmd stopped) and their
    #    processes (proctrack/linuxproc: the step's descendants).
    stepds=$(our_stepds)
    if [[ -n $stepds ]]; then
        local victims
        victims="$(descendants $stepds) $stepds"
        info "killing left-over job steps: $(echo $victims)"
        for p in $victims; do kill -KILL "$p" 2>/dev/null || true; done
    fi
    # 4. munged last: the others needed it to the end.
    [[ -z $mpid ]] || kill_wait "$mpid" munged
    rm -f "$CPID" "$DPID" "$MPID" "$MSOCK" "$MSOCK.lock"
    [[ -n $quiet ]] || info "cluster in $D stopped"
}

cmd_stop() {
    local dir=$1
    [[ -d $dir ]] || { info "$dir does not exist: nothing to stop"; return 0; }
    set_paths "$(cd -- "$dir" && pwd -P)"
    [[ -f $D/$MARKER ]] || die "$D holds no cluster of this script: refusing to touch it"
    cmd_stop_inner
}

cmd_status() {
    local dir=$1
    [[ -d $dir ]] || die "$dir does not exist"
    set_paths "$(cd -- "$dir" && pwd -P)"
    [[ -f $D/$MARKER ]] || die "$D holds no cluster of this script"
    local ok=0 n f
    for n in munged:$MPID slurmctld:$CPID slurmd:$DPID; do
        f=${n#*:}
        if p=$(our_pid "$f"); then echo "${n%%:*} running (pid $p)"; else echo "${n%%:*} not running"; ok=1; fi
    done
    return $ok
}

(($# == 2)) || usage
case $1 in
    start) cmd_start "$2" ;;
    stop) cmd_stop "$2" ;;
    status) cmd_status "$2" ;;
    *) usage ;;
esac
