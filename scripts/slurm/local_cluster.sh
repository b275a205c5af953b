#!/usr/bin/env bash
# Start/stop a throw-away single-node Slurm cluster (slurmctld + slurmd + munged)
# on this machine, for tests that need to submit real sbatch jobs.
#
#   local_cluster.sh start STATE_DIR   # install if needed, start, wait until the node is idle
#   local_cluster.sh stop  STATE_DIR   # stop what `start` started (safe to call repeatedly)
#
# Must run as root. Does not use systemd or /etc/slurm: the whole Slurm config, state,
# spool, logs and pid files live in STATE_DIR, and clients find it via SLURM_CONF.
# Only munge uses system paths (/etc/munge/munge.key, /run/munge), because that is
# where the Debian munge library expects the key and socket.
#
# Optional environment overrides:
#   SLURMCTLD_PORT (default 6817), SLURMD_PORT (default 6818)
#   LOCAL_CLUSTER_TIMEOUT  seconds to wait for the node to become idle (default 60)
set -euo pipefail

usage() {
    echo "usage: $0 {start|stop} STATE_DIR" >&2
    exit 2
}

[[ $# -eq 2 ]] || usage
action=$1
state_dir=$2

ctld_port=${SLURMCTLD_PORT:-6817}
slurmd_port=${SLURMD_PORT:-6818}
wait_secs=${LOCAL_CLUSTER_TIMEOUT:-60}

log() { echo "[local_cluster] $*" >&2; }

# True if process $1 is running and its command name is $2. Checking the name guards
# against signalling an unrelated process that reused a stale pid. A zombie counts as
# gone: in containers whose pid 1 does not reap orphans, exited daemons stay zombies.
proc_is() {
    local comm state
    [[ $1 =~ ^[0-9]+$ ]] || return 1
    comm=$(cat "/proc/$1/comm" 2>/dev/null) || return 1
    [[ $comm == "$2" ]] || return 1
    state=$(awk '/^State:/ {print $2}' "/proc/$1/status" 2>/dev/null) || return 1
    [[ $state != Z ]]
}

# True if the pid in pid file $1 is a live process named $2.
pid_alive() {
    [[ -s $1 ]] && proc_is "$(<"$1")" "$2"
}

# Wait up to 5 s for daemon $2 to write pid file $1: the daemons fork into the background
# and the parent returns before the child has written it.
wait_pidfile() {
    local i
    for ((i = 0; i < 50; i++)); do
        pid_alive "$1" "$2" && return 0
        sleep 0.1
    done
    log "$2 did not start (no live process in $1)"
    return 1
}

# Wait up to $3 tenths of a second for process $1 (named $2) to be gone; false if it is not.
wait_gone() {
    local i
    for ((i = 0; i < $3; i++)); do
        proc_is "$1" "$2" || return 0
        sleep 0.1
    done
    ! proc_is "$1" "$2"
}

# SIGTERM the process from pid file $1 (if it is really $2), wait until it is gone,
# SIGKILL as a last resort, and remove the pid file. The pid is read once up front: the
# Slurm daemons delete their own pid file early in shutdown, before they have exited.
# A missing or stale pid file is not an error, which is what makes `stop` idempotent.
stop_pidfile() {
    local pidfile=$1 name=$2 pid
    if pid_alive "$pidfile" "$name"; then
        pid=$(<"$pidfile")
        log "stopping $name (pid $pid)"
        kill -TERM "$pid" 2>/dev/null || true
        if ! wait_gone "$pid" "$name" 150; then
            log "$name did not exit 15 s after SIGTERM; sending SIGKILL"
            kill -KILL "$pid" 2>/dev/null || true
            wait_gone "$pid" "$name" 50 || true
        fi
    fi
    rm -f "$pidfile"
}

# Cancel jobs still queued or running (e.g. a test that failed mid-way), so that stopping
# slurmd does not leave their processes behind: slurmstepd and the job outlive slurmd.
cancel_jobs() {
    if ! pid_alive "$state_dir/slurmctld.pid" slurmctld ||
        ! pid_alive "$state_dir/slurmd.pid" slurmd; then
        return 0
    fi
    export SLURM_CONF=$state_dir/slurm.conf
    [[ -n $(squeue -h -o %i 2>/dev/null) ]] || return 0
    log "cancelling unfinished jobs"
    scancel --partition=debug 2>/dev/null || true
    local i
    for ((i = 0; i < 100; i++)); do
        [[ -z $(squeue -h -o %i 2>/dev/null) ]] && return 0
        sleep 0.2
    done
    log "jobs still listed after 20 s:"
    squeue >&2 || true
}

do_stop() {
    [[ -d $state_dir ]] || return 0
    cancel_jobs
    # Reverse of the start order: slurmd, then slurmctld, then munged, which both use.
    stop_pidfile "$state_dir/slurmd.pid" slurmd
    stop_pidfile "$state_dir/slurmctld.pid" slurmctld
    # This pid file only exists if *we* started munged (see start_munge); a munged that
    # was already running belongs to someone else and is left alone.
    stop_pidfile "$state_dir/munged.pid" munged
}

install_if_missing() {
    if command -v slurmctld >/dev/null && command -v slurmd >/dev/null &&
        command -v munged >/dev/null && command -v sbatch >/dev/null; then
        return 0
    fi
    log "installing slurm-wlm and munge with apt-get"
    # apt output goes to stderr: stdout is reserved for the "export SLURM_CONF=" line.
    # Package postinst scripts do not start the daemons here (no systemd, and policy-rc.d
    # forbids it in containers); we start them ourselves below either way.
    export DEBIAN_FRONTEND=noninteractive
    SECONDS=0
    apt-get update -q >&2
    apt-get install -y -q --no-install-recommends slurm-wlm munge >&2
    log "installed in ${SECONDS}s"
}

munge_works() {
    munge -n </dev/null 2>/dev/null | unmunge >/dev/null 2>&1
}

start_munge() {
    local key=/etc/munge/munge.key
    # munged refuses keys that are not owned by its user or that others can read.
    install -d -o munge -g munge -m 0700 /etc/munge
    if [[ ! -s $key ]]; then
        log "creating munge key $key"
        if command -v mungekey >/dev/null; then
            mungekey --create --keyfile="$key"
        else
            dd if=/dev/urandom of="$key" bs=1 count=1024 status=none
        fi
    fi
    chown munge:munge "$key"
    chmod 0400 "$key"

    if munge_works; then
        log "munged already running; reusing it"
        return 0
    fi
    # /run is a tmpfs normally populated by systemd-tmpfiles or the init script; neither
    # runs here, so create the socket/pid directory ourselves. The package creates the
    # other two; recreate them only if missing, so as not to change their permissions.
    install -d -o munge -g munge -m 0755 /run/munge
    local d
    for d in /var/lib/munge /var/log/munge; do
        [[ -d $d ]] || install -d -o munge -g munge -m 0700 "$d"
    done
    # A socket left behind by a killed munged makes the new one refuse to start.
    rm -f /run/munge/munge.socket.2 /run/munge/munge.socket.2.lock
    log "starting munged"
    # Run as the unprivileged munge user, the supported mode (no --force needed).
    # munged daemonizes itself and writes its pid file; once it answers, we copy that
    # into STATE_DIR, which is what marks it as ours for `stop`.
    runuser -u munge -- /usr/sbin/munged --pid-file=/run/munge/munged.pid
    local i
    for ((i = 0; i < 50; i++)); do
        if munge_works; then
            cp /run/munge/munged.pid "$state_dir/munged.pid"
            return 0
        fi
        sleep 0.1
    done
    log "munged does not answer; log follows"
    tail -n 50 /var/log/munge/munged.log >&2 || true
    return 1
}

write_config() {
    local node cpus mem
    node=$(hostname -s)
    cpus=$(nproc)
    # MemTotal in MiB, the same source slurmd uses; if we configured more than slurmd
    # measures, the node would be drained with "Low RealMemory".
    mem=$(free -m | awk '/^Mem:/ {print $2}')

    # Explicit 127.0.0.1 addresses: the cluster never leaves this machine and we do not
    # want to depend on how (or whether) the hostname resolves. slurmctld still requires
    # the *name* in SlurmctldHost to equal `hostname -s`.
    cat >"$state_dir/slurm.conf" <<EOF
# Generated by $(basename "$0"); single-node test cluster, not for production.
ClusterName=localtest
SlurmctldHost=$node(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge

StateSaveLocation=$state_dir/state
SlurmdSpoolDir=$state_dir/spool
SlurmctldPidFile=$state_dir/slurmctld.pid
SlurmdPidFile=$state_dir/slurmd.pid
SlurmctldLogFile=$state_dir/slurmctld.log
SlurmdLogFile=$state_dir/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info

# No cgroups: containers rarely allow creating them, and tests do not need limits.
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MpiDefault=none
MailProg=/bin/true

# Allocate individual CPUs (not whole nodes) so array tasks run side by side.
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
# Start jobs freed-up CPUs allow within ~1 s rather than after the default 3 s batching
# delay: array tasks beyond the CPU count otherwise wait an extra scheduler pass.
SchedulerParameters=batch_sched_delay=0

# A node that was down (e.g. across stop/start) rejoins as soon as slurmd registers.
ReturnToService=2
# sbatch --wait polls slurmctld after 2 s, then backs off to 8 s and 32 s, but only while
# the interval stays below MinJobAge/2 (_job_wait in sbatch.c), so that a finished job is
# never purged before it is seen. 5 is the largest value that keeps the 2 s poll (the
# default 300 makes even a trivial job take 10 s); slurmctld rejects values below 2.
# Trade-off: finished jobs vanish from squeue/scontrol about 5 s after they end, and
# there is no accounting database to ask afterwards.
MinJobAge=5

NodeName=$node NodeAddr=127.0.0.1 NodeHostname=$node CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=debug Nodes=ALL Default=YES MaxTime=INFINITE State=UP
EOF
}

dump_logs() {
    local f
    for f in "$state_dir/slurmctld.log" "$state_dir/slurmd.log"; do
        echo "===== $f (last 40 lines) =====" >&2
        tail -n 40 "$f" >&2 2>/dev/null || echo "(missing)" >&2
    done
}

do_start() {
    [[ $EUID -eq 0 ]] || { log "must run as root"; exit 1; }
    mkdir -p "$state_dir"
    state_dir=$(cd "$state_dir" && pwd)  # absolute: it goes into slurm.conf

    # A previous start with the same STATE_DIR may still be running; restart cleanly.
    do_stop

    install_if_missing
    start_munge
    mkdir -p "$state_dir/state" "$state_dir/spool"
    write_config
    export SLURM_CONF=$state_dir/slurm.conf

    # Both daemons daemonize and write the pid files named in slurm.conf. If one fails,
    # clean up whatever did start so a failed `start` leaves nothing running.
    log "starting slurmctld"
    if ! slurmctld -f "$SLURM_CONF" || ! wait_pidfile "$state_dir/slurmctld.pid" slurmctld; then
        dump_logs; do_stop; exit 1
    fi
    log "starting slurmd"
    if ! slurmd -f "$SLURM_CONF" || ! wait_pidfile "$state_dir/slurmd.pid" slurmd; then
        dump_logs; do_stop; exit 1
    fi

    local node state="" i
    node=$(hostname -s)
    for ((i = 0; i < wait_secs * 2; i++)); do
        # A daemon can die after daemonizing (e.g. port already in use): fail fast.
        if ! pid_alive "$state_dir/slurmctld.pid" slurmctld ||
            ! pid_alive "$state_dir/slurmd.pid" slurmd; then
            state="a daemon exited"
            break
        fi
        # "idle" (not "idle*", not "unknown") means slurmd has registered with slurmctld.
        state=$(sinfo -h -N -n "$node" -o '%T' 2>/dev/null || true)
        [[ $state == idle ]] && break
        sleep 0.5
    done
    if [[ $state != idle ]]; then
        log "node $node did not become idle (state: '${state:-no answer}', timeout ${wait_secs}s)"
        timeout 10 sinfo -N -l >&2 || true
        dump_logs
        do_stop
        exit 1
    fi
    log "cluster up: node $node idle"
    echo "export SLURM_CONF=$SLURM_CONF"
}

case $action in
start) do_start ;;
stop) do_stop ;;
*) usage ;;
esac
