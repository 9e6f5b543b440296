#!/usr/bin/env bash
# End-to-end check of the SLURM profile on a real (single-node, localhost-only) SLURM.
#
#   sudo tests/cluster/run_slurm_test.sh        # or: make test as root (tests/test_cluster.py)
#
# 1. installs what is missing: slurm-wlm + munge (apt-get), snakemake-executor-plugin-slurm (pip);
# 2. starts a private munged, slurmctld and slurmd from tests/cluster/slurm.conf.in (one node,
#    `localhost`, all CPUs, RAM of /proc/meminfo minus a margin; no accounting database; free
#    ports; everything under one temporary directory, nothing under /etc is touched);
# 3. copies the workflow (Snakefile, workflow/, config/, envs/) into two directories, writes the same
#    small scene into both (representativity N=32; contact N=32 when roughcontact.solver imports),
#    runs it locally with -j2 in one and through profiles/slurm in the other;
# 4. compares every NetCDF and CSV output: byte-identical is required.
# The daemons are always stopped on exit. Prints "SKIP: <reason>" and exits 0 when it cannot run
# here (not root, no apt-get, packages cannot be installed); exits non-zero on a real failure.
#
# Environment: PYTHON (default: .venv/bin/python of the repository, else python3);
# ROUGHCONTACT_SLURM_KEEP=1 keeps the temporary directory. Time caps (they only catch a hang,
# ~15-25x the measured time; the failure message names the cap): ROUGHCONTACT_SLURM_UP_TIMEOUT
# (default 300 s) for the node to turn idle, ROUGHCONTACT_SLURM_LOCAL_TIMEOUT (default 600 s;
# measured 24 s) for the local run, ROUGHCONTACT_SLURM_RUN_TIMEOUT (default 1200 s; measured 77 s)
# for the SLURM run. (No SLURM_* names: the script unsets those.)
set -uo pipefail

HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
REPO=$(cd "$HERE/../.." && pwd)
export PATH="$PATH:/usr/sbin:/sbin"
T0=$(date +%s)
UP_TIMEOUT=${ROUGHCONTACT_SLURM_UP_TIMEOUT:-300}
LOCAL_TIMEOUT=${ROUGHCONTACT_SLURM_LOCAL_TIMEOUT:-600}
RUN_TIMEOUT=${ROUGHCONTACT_SLURM_RUN_TIMEOUT:-1200}
MUNGE_TIMEOUT=60

log() { echo "[slurm-test +$(($(date +%s) - T0))s] $*"; }
skip() { echo "SKIP: $*"; exit 0; }
fail() { echo "FAIL: $*" >&2; exit 1; }

PY=${PYTHON:-}
if [ -z "$PY" ]; then
    if [ -x "$REPO/.venv/bin/python" ]; then PY="$REPO/.venv/bin/python"; else PY=$(command -v python3 || true); fi
fi
if [ -z "$PY" ] || [ ! -x "$PY" ]; then skip "no Python interpreter found (set PYTHON)"; fi

# ---------------------------------------------------------------- can it run here?
[ "$(id -u)" = 0 ] || skip "not root: installing SLURM and starting its daemons needs root"
"$PY" -c 'import snakemake, xarray, roughcontact' 2>/dev/null \
    || skip "$PY cannot import snakemake, xarray and roughcontact (install the package first: make install)"

# A run from inside a SLURM job would otherwise talk to the outer cluster.
for var in $(env | sed -n 's/^\(SLURM_[A-Za-z0-9_]*\)=.*/\1/p'); do unset "$var"; done

have_slurm() {
    local b
    for b in munged munge unmunge slurmctld slurmd sbatch squeue sinfo scontrol scancel srun; do
        command -v "$b" >/dev/null 2>&1 || return 1
    done
}
if ! have_slurm; then
    command -v apt-get >/dev/null 2>&1 || skip "slurm-wlm/munge are not installed and apt-get is unavailable"
    log "installing slurm-wlm and munge with apt-get"
    export DEBIAN_FRONTEND=noninteractive
    APT_OPTS=(-q -o Acquire::Retries=1 -o Acquire::http::Timeout=30 -o DPkg::Lock::Timeout=60)
    if ! apt-get install -y "${APT_OPTS[@]}" slurm-wlm munge >/tmp/roughcontact-apt.log 2>&1; then
        apt-get update "${APT_OPTS[@]}" >>/tmp/roughcontact-apt.log 2>&1
        apt-get install -y "${APT_OPTS[@]}" slurm-wlm munge >>/tmp/roughcontact-apt.log 2>&1 \
            || skip "apt-get install slurm-wlm munge failed (log: /tmp/roughcontact-apt.log): $(tail -n 1 /tmp/roughcontact-apt.log)"
    fi
    have_slurm || skip "slurm-wlm/munge installed, but their programs are not on PATH"
fi
if ! "$PY" -c 'import snakemake_executor_plugin_slurm' 2>/dev/null; then
    log "installing snakemake-executor-plugin-slurm with pip"
    "$PY" -m pip install -q --retries 1 --timeout 30 snakemake-executor-plugin-slurm >/tmp/roughcontact-pip.log 2>&1 \
        || skip "pip install snakemake-executor-plugin-slurm failed (log: /tmp/roughcontact-pip.log)"
fi
log "slurm-wlm $(dpkg-query -W -f '${Version}' slurm-wlm 2>/dev/null || sinfo --version), plugin $("$PY" -c \
    'import importlib.metadata as m; print(m.version("snakemake-executor-plugin-slurm"))'), $("$PY" -m snakemake --version)"

# ---------------------------------------------------------------- private SLURM
WORK=$(mktemp -d "${TMPDIR:-/tmp}/roughcontact-slurm.XXXXXX") || fail "mktemp failed"
RUNDIR="$WORK/slurm-daemons"
mkdir -p "$RUNDIR"/{munge,state,spool,log,bin}
chmod 711 "$RUNDIR/munge"   # munged: the socket's directory must be searchable by all
PIDS=()
SNAKE_PID=""

stop_pid() {  # TERM, up to 10 s grace, then KILL
    local pid=$1
    [ -n "$pid" ] && kill "$pid" 2>/dev/null || return 0
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || return 0; sleep 0.2; done
    kill -9 "$pid" 2>/dev/null || true
}

cleanup() {
    local rc=$? pid i
    trap - EXIT INT TERM
    stop_pid "${SNAKE_PID:-}"
    if [ -n "${SLURM_CONF:-}" ] && [ -f "$SLURM_CONF" ]; then
        timeout 10 scancel --user=root >/dev/null 2>&1 || true   # only this private cluster's jobs
    fi
    for ((i = ${#PIDS[@]} - 1; i >= 0; i--)); do stop_pid "${PIDS[i]}"; done
    wait 2>/dev/null
    if [ "$rc" = 0 ] && [ "${ROUGHCONTACT_SLURM_KEEP:-0}" != 1 ]; then
        rm -rf "$WORK"
    else
        echo "[slurm-test] kept $WORK (daemon logs in $RUNDIR/log, run logs in $WORK/*.log)"
    fi
    exit "$rc"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

show_logs() {
    local f
    for f in "$RUNDIR"/log/*; do
        [ -s "$f" ] || continue
        echo "----- $f (last 20 lines)" >&2
        tail -n 20 "$f" >&2
    done
}

read -r CTLD_PORT SLURMD_PORT < <("$PY" - <<'EOF'
import socket
socks = [socket.socket() for _ in range(2)]
for s in socks:
    s.bind(("127.0.0.1", 0))
print(*(s.getsockname()[1] for s in socks))
EOF
)
# the CPUs this process may use (nproc alone honours OMP_NUM_THREADS, which a test run may set to 1)
CPUS=$(env -u OMP_NUM_THREADS -u OMP_THREAD_LIMIT nproc)
MEM_TOTAL=$(awk '/^MemTotal:/ {print int($2 / 1024)}' /proc/meminfo)   # MB, as `free -m`
MARGIN=$((MEM_TOTAL / 10 > 512 ? MEM_TOTAL / 10 : 512))
REAL_MEMORY=$((MEM_TOTAL - MARGIN))
sed -e "s|@RUNDIR@|$RUNDIR|g" -e "s|@CTLD_PORT@|$CTLD_PORT|g" -e "s|@SLURMD_PORT@|$SLURMD_PORT|g" \
    -e "s|@CPUS@|$CPUS|g" -e "s|@REAL_MEMORY@|$REAL_MEMORY|g" \
    "$HERE/slurm.conf.in" >"$RUNDIR/slurm.conf"
: >"$RUNDIR/plugstack.conf"
export SLURM_CONF="$RUNDIR/slurm.conf"
# Inside a SLURM job, snakemake-executor-plugin-slurm-jobstep (0.6) starts each rule with `srun`
# in an environment stripped of SLURM_* variables, SLURM_CONF included; a real cluster's srun
# finds /etc/slurm/slurm.conf (or its configless server), this private one would find nothing.
# So an `srun` first on PATH (PATH reaches the job: sbatch --export=ALL) puts SLURM_CONF back.
cat >"$RUNDIR/bin/srun" <<EOF
#!/bin/sh
SLURM_CONF="$SLURM_CONF" exec "$(command -v srun)" "\$@"
EOF
chmod 755 "$RUNDIR/bin/srun"
export PATH="$RUNDIR/bin:$PATH"
log "slurm.conf: node localhost, CPUs=$CPUS, RealMemory=$REAL_MEMORY MB, ports $CTLD_PORT/$SLURMD_PORT, in $RUNDIR"

SOCK="$RUNDIR/munge/munge.socket.2"
mungekey --create --keyfile="$RUNDIR/munge/munge.key" >/dev/null 2>&1 \
    || dd if=/dev/urandom of="$RUNDIR/munge/munge.key" bs=1024 count=1 status=none
chmod 600 "$RUNDIR/munge/munge.key"
munged --foreground --force --socket="$SOCK" --key-file="$RUNDIR/munge/munge.key" \
    --pid-file="$RUNDIR/munge/munged.pid" --seed-file="$RUNDIR/munge/munged.seed" \
    --log-file="$RUNDIR/log/munged.log" >"$RUNDIR/log/munged.out" 2>&1 &
PIDS+=($!)
for _ in $(seq $((MUNGE_TIMEOUT * 5))); do [ -S "$SOCK" ] && break; sleep 0.2; done
[ -S "$SOCK" ] || { show_logs; fail "munged did not create its socket $SOCK within ${MUNGE_TIMEOUT}s"; }
munge --socket="$SOCK" -n 2>/dev/null | unmunge --socket="$SOCK" >/dev/null 2>&1 \
    || { show_logs; fail "munged is up but a munge | unmunge round trip failed (socket $SOCK)"; }

UP_T0=$(date +%s)
slurmctld -D -c -f "$SLURM_CONF" >"$RUNDIR/log/slurmctld.out" 2>&1 &
PIDS+=($!)
slurmd -D -N localhost -f "$SLURM_CONF" >"$RUNDIR/log/slurmd.out" 2>&1 &
PIDS+=($!)
log "munged, slurmctld, slurmd started (pids ${PIDS[*]})"

# run_snakemake DIR LOG LIMIT_S WATCH_SLURM ARGS...: snakemake in DIR, output to LOG, killed after
# LIMIT_S seconds; with WATCH_SLURM=1 it also fails fast on a job SLURM can never start.
# STOPPED says why it was stopped ("" if it ended by itself), for the caller's failure message.
STOPPED=""
run_snakemake() {
    local dir=$1 logf=$2 limit=$3 watch=$4 start bad rc
    shift 4
    STOPPED=""
    start=$(date +%s)
    (cd "$dir" && exec "$PY" -m snakemake "$@") >"$logf" 2>&1 &
    SNAKE_PID=$!
    while kill -0 "$SNAKE_PID" 2>/dev/null; do
        if [ $(($(date +%s) - start)) -ge "$limit" ]; then
            stop_pid "$SNAKE_PID"
            STOPPED="was killed by the time cap: not finished within ${limit}s"
            echo "snakemake $STOPPED" >>"$logf"
            break
        fi
        if [ "$watch" = 1 ]; then
            # pending reasons that never clear: the request exceeds the node or partition
            bad=$(timeout 10 squeue -h -t PD -o '%i %r' 2>/dev/null \
                | awk '$2 ~ /^(PartitionConfig|PartitionNodeLimit|PartitionTimeLimit|BadConstraints)$/' | head -n 1)
            if [ -n "$bad" ]; then
                stop_pid "$SNAKE_PID"
                STOPPED="was stopped: SLURM job ${bad% *} can never start (reason ${bad#* })"
                echo "SLURM job ${bad% *} can never start (reason ${bad#* }):" >>"$logf"
                timeout 10 scontrol show job "${bad% *}" >>"$logf" 2>&1
                break
            fi
        fi
        sleep 2
    done
    wait "$SNAKE_PID"
    rc=$?
    SNAKE_PID=""
    return "$rc"
}

# ---------------------------------------------------------------- the scene, twice
SCENE_YAML="$WORK/config.yaml"
if "$PY" -c 'import roughcontact.solver' 2>/dev/null; then WITH_CONTACT=1; else WITH_CONTACT=0; fi
# one case over 2 MPI ranks (contact.solver.ranks) where mpi4py imports: an MPI job under SLURM (srun)
# (2 tasks: a node of at least 2 CPUs)
if [ "$WITH_CONTACT" = 1 ] && [ "$CPUS" -ge 2 ] && "$PY" -c 'import mpi4py' 2>/dev/null; then WITH_MPI=1; else WITH_MPI=0; fi
WITH_CONTACT=$WITH_CONTACT WITH_MPI=$WITH_MPI "$PY" - "$SCENE_YAML" <<'EOF' || fail "could not write the scene config"
import os, sys, yaml
scene = {
    "description": "tests/cluster: the same small scene run locally and through SLURM",
    "representativity": {
        "surface": {"N": 32, "rms_height": 0.1},
        "grid": {"k_l": ["1", "4"], "k_s": ["8"], "H": ["0.8"]},
        "seeds": 2,
        "n_bins": 20,
        "examples": [{"k_l": "1", "k_s": "8"}, {"k_l": "4", "k_s": "8"}],
    },
}
if os.environ["WITH_CONTACT"] == "1":
    scene["contact"] = {
        "surface": {"N": 32, "rms_slope": 0.1},
        "grid": {"k_l": ["2"], "k_s": ["8"], "H": ["0.5", "0.8"]},
        "seeds": 2,
        "load": {"p_max": 0.01, "n_steps": 12},
        "solver": {"tol": 1e-8},
    }
    scene["fit"] = {"window": [0.01, 0.3], "n_boot": 20}
scenes = {"slurmtest": scene}
if os.environ["WITH_MPI"] == "1":
    scenes["slurmmpi"] = {"contact": {"surface": {"N": 64, "rms_slope": 0.1},
                                      "grid": {"k_l": ["2"], "k_s": ["8"], "H": ["0.8"]}, "seeds": 2,
                                      "load": {"p_max": 0.01, "n_steps": 6}, "solver": {"tol": 1e-8, "ranks": 2}}}
with open(sys.argv[1], "w") as fh:
    yaml.safe_dump({"scene": "slurmtest", "scenes": scenes}, fh, sort_keys=False)
EOF
# the scene's targets (rule all), and with MPI the 2-rank case's file too
TARGETS=(all)
[ "$WITH_MPI" = 1 ] && TARGETS+=(results/slurmmpi/contact/kl2_ks8_H0.8_s0.nc)
if [ "$WITH_MPI" = 1 ]; then
    log "scene: representativity N=32 (4 surfaces) + contact N=32 (4 cases); one N=64 case over 2 MPI ranks"
elif [ "$WITH_CONTACT" = 1 ]; then
    log "scene: representativity N=32 (4 surfaces) + contact N=32 (4 cases)"
else
    log "scene: representativity only (roughcontact.solver does not import, contact left out)"
fi
for d in local slurm; do
    mkdir -p "$WORK/$d"
    cp "$REPO/Snakefile" "$WORK/$d/"
    # profiles/ too: Snakemake skips a --workflow-profile it cannot find without a word, and the SLURM
    # run would then run locally
    cp -r "$REPO/workflow" "$REPO/profiles" "$REPO/config" "$WORK/$d/"
    [ -d "$REPO/envs" ] && cp -r "$REPO/envs" "$WORK/$d/"   # the rules' conda: files (run metadata reads them)
    rm -rf "$WORK/$d/results" "$WORK/$d/.snakemake"
    cp "$SCENE_YAML" "$WORK/$d/config/config.yaml"
done

log "local run: snakemake --workflow-profile profiles/default -j2"
t=$(date +%s)
run_snakemake "$WORK/local" "$WORK/local.log" "$LOCAL_TIMEOUT" 0 --workflow-profile profiles/default \
    -j2 --nocolor "${TARGETS[@]}" \
    || { rc=$?; tail -n 40 "$WORK/local.log" >&2
         fail "the local -j2 run ${STOPPED:-failed} (status $rc; log above)"; }
LOCAL_S=$(($(date +%s) - t))
log "local run done in ${LOCAL_S}s"

# ---------------------------------------------------------------- wait for the node
state=""
while :; do
    state=$(timeout 10 sinfo -h -n localhost -o %t 2>/dev/null | head -n 1)
    [ "$state" = idle ] && break
    case "$state" in  # states this node cannot leave by itself: its slurm.conf line is wrong
        inval* | drain* | drng*)
            show_logs
            timeout 10 sinfo -R >&2 2>/dev/null || true
            fail "SLURM node 'localhost' is '$state' (reason above), not idle" ;;
    esac
    for pid in "${PIDS[@]}"; do
        kill -0 "$pid" 2>/dev/null || { show_logs; fail "a SLURM daemon (pid $pid) exited before the node came up"; }
    done
    if [ $(($(date +%s) - UP_T0)) -ge "$UP_TIMEOUT" ]; then
        show_logs
        timeout 10 sinfo -R >&2 2>/dev/null || true
        fail "SLURM node 'localhost' not idle ${UP_TIMEOUT}s after slurmctld/slurmd started (sinfo state: '${state:-no answer}')"
    fi
    sleep 2
done
log "SLURM node localhost is idle (checked from $(($(date +%s) - UP_T0))s after slurmctld/slurmd started)"

# ---------------------------------------------------------------- through SLURM
# --cores: the node has $CPUS CPUs, so a group job may be at most that wide (the profile says 8).
# squeue for status: there is no accounting database for sacct. --slurm-no-account: there are
# no accounts (plugin 2.8 still tries to guess one and then submits without, harmlessly).
SLURM_ARGS=(--workflow-profile profiles/slurm --cores "$CPUS"
    --slurm-status-command squeue --slurm-no-account --slurm-init-seconds-before-status-checks 5
    --slurm-keep-successful-logs --nocolor)
log "SLURM run: snakemake ${SLURM_ARGS[*]}"
t=$(date +%s)
run_snakemake "$WORK/slurm" "$WORK/slurm.log" "$RUN_TIMEOUT" 1 "${SLURM_ARGS[@]}" "${TARGETS[@]}"
rc=$?
SLURM_S=$(($(date +%s) - t))
if [ "$rc" != 0 ]; then
    show_logs
    find "$WORK/slurm/.snakemake/slurm_logs" -name '*.log' -exec tail -n 20 {} + >&2 2>/dev/null
    echo "----- $WORK/slurm.log (last 60 lines)" >&2
    tail -n 60 "$WORK/slurm.log" >&2
    fail "the SLURM run ${STOPPED:-failed} (status $rc after ${SLURM_S}s; its log above, daemon logs before it)"
fi
N_SUBMITTED=$(grep -c "submitted with SLURM jobid" "$WORK/slurm.log")
[ "$N_SUBMITTED" -gt 0 ] || { tail -n 40 "$WORK/slurm.log" >&2; fail "the SLURM run submitted no SLURM job"; }
log "SLURM run done in ${SLURM_S}s: $N_SUBMITTED SLURM job(s) (id, state, elapsed, CPUs, memory, comment):"
timeout 10 squeue --states=all -h -o '    %i %T %M %C %m %k' 2>/dev/null | head -n 20

# ---------------------------------------------------------------- same results?
"$PY" "$HERE/compare_results.py" "$WORK/local/results" "$WORK/slurm/results" \
    || fail "the SLURM run's outputs differ from the local -j2 run's"
log "PASS: local -j2 ${LOCAL_S}s, SLURM ${SLURM_S}s ($N_SUBMITTED SLURM jobs), outputs byte-identical"
