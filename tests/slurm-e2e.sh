#!/usr/bin/env bash
# The cluster test: a one-node Slurm cluster on localhost renders a 3-frame animated fire with motion blur as
# 3 frames × 4 tiles and merges them; every merged frame must equal a local `firemedium render --frames` of the
# same scene bit for bit (`firemedium diff`). Prints the farm's wall time against the local render's.
#
# Installs slurm-wlm and munge from Debian's packages when missing (as root), starts munged, slurmctld and
# slurmd from a generated slurm.conf in a temporary folder (their own socket, ports and state: nothing of the
# machine's is touched), and stops the daemons it started whatever happens.
#
#   tests/slurm-e2e.sh [path/to/firemedium]      (default: target/release/firemedium, built if missing)
set -euo pipefail
cd "$(dirname "$0")/.."
FM=${1:-target/release/firemedium}
if [ ! -x "$FM" ]; then
    cargo build --release -q
fi
FM=$(realpath "$FM")

say() { echo "slurm-e2e: $*"; }
fail() { echo "slurm-e2e: FAILED: $*" >&2; exit 1; }

# ---- Slurm and munge, from Debian's packages
[ "$(id -u)" = 0 ] || fail "needs root (slurmd runs jobs as their users)"
if ! command -v slurmctld >/dev/null || ! command -v slurmd >/dev/null || ! command -v munged >/dev/null; then
    say "installing slurm-wlm and munge (Debian packages)"
    export DEBIAN_FRONTEND=noninteractive
    apt-get install -y -q slurm-wlm munge >/dev/null 2>&1 \
        || { apt-get update -q >/dev/null && apt-get install -y -q slurm-wlm munge >/dev/null; } \
        || fail "apt-get install slurm-wlm munge"
fi

# ---- a one-node cluster in a temporary folder
T=$(mktemp -d /tmp/firemedium-slurm.XXXXXX)
chmod 755 "$T"
PIDS=()
cleanup() {
    for f in "$T/slurmd.pid" "$T/slurmctld.pid" "$T/munge/munged.pid"; do
        [ -f "$f" ] && kill "$(cat "$f")" 2>/dev/null || true
    done
    # Give them a moment, then make sure.
    sleep 1
    for f in "$T/slurmd.pid" "$T/slurmctld.pid" "$T/munge/munged.pid"; do
        [ -f "$f" ] && kill -9 "$(cat "$f")" 2>/dev/null || true
    done
    rm -rf "$T"
}
trap cleanup EXIT
mkdir -p "$T/state" "$T/spool" "$T/log" "$T/munge" "$T/work"
chmod 700 "$T/munge"
head -c 1024 /dev/urandom >"$T/munge/munge.key"
chmod 400 "$T/munge/munge.key"
SOCK="$T/munge/sock"
munged --force --socket="$SOCK" --key-file="$T/munge/munge.key" --log-file="$T/log/munged.log" \
    --pid-file="$T/munge/munged.pid" --seed-file="$T/munge/seed" || fail "munged did not start"
# Ports: two free ones above 20000 (the daemons' defaults may be in use by a real cluster).
port() { python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'; }
CTLD_PORT=$(port)
D_PORT=$(port)
PLUGINS=$(dirname "$(find /usr/lib -name 'select_cons_tres.so' -path '*slurm*' | head -n1)")
[ -d "$PLUGINS" ] || fail "no Slurm plugin folder found under /usr/lib"
CPUS=$(nproc)
cat >"$T/slurm.conf" <<EOF
ClusterName=firemedium
SlurmctldHost=localhost(127.0.0.1)
SlurmUser=root
SlurmdUser=root
SlurmctldPort=$CTLD_PORT
SlurmdPort=$D_PORT
AuthType=auth/munge
AuthInfo=socket=$SOCK
CryptoType=crypto/munge
StateSaveLocation=$T/state
SlurmdSpoolDir=$T/spool
SlurmctldPidFile=$T/slurmctld.pid
SlurmdPidFile=$T/slurmd.pid
SlurmctldLogFile=$T/log/slurmctld.log
SlurmdLogFile=$T/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SchedulerType=sched/backfill
SchedulerParameters=sched_interval=1,bf_interval=1,sched_min_interval=100000
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
MpiDefault=none
SwitchType=switch/none
PluginDir=$PLUGINS
NodeName=fmnode NodeHostname=$(hostname) NodeAddr=127.0.0.1 CPUs=$CPUS State=UNKNOWN
PartitionName=firemedium Nodes=fmnode Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF="$T/slurm.conf"
slurmctld -f "$SLURM_CONF" || fail "slurmctld did not start: $(tail -n 5 "$T/log/slurmctld.log" 2>/dev/null)"
slurmd -f "$SLURM_CONF" -N fmnode || fail "slurmd did not start: $(tail -n 5 "$T/log/slurmd.log" 2>/dev/null)"
for _ in $(seq 1 30); do
    sinfo -h -o '%T' 2>/dev/null | grep -q idle && break
    sleep 1
done
sinfo -h -o '%T' | grep -q idle || fail "the node never became idle: $(sinfo 2>&1; tail -n 5 "$T/log/slurmctld.log")"
say "cluster up: $(sinfo -h -o '%P %D node(s) %T, %c CPUs')"

# ---- a 3-frame animated fire with velocity, and a scene that blurs it
W="$T/work"
"$FM" gen torch --resolution 24 --frames 30-32 --velocity -o "$W/torch.####.vdb" >/dev/null
cat >"$W/torch.pbrt" <<'EOF'
# A torch over three frames, blurred by its own velocity over half a frame (a 180° shutter).
LookAt 0 -3 0.6  0 0 0.5  0 0 1
Camera "perspective" "float fov" 40 "float shutteropen" 0 "float shutterclose" 0.5
Film "rgb" "integer xresolution" 48 "integer yresolution" 36 "string filename" "torch.####.exr"
Sampler "zsobol" "integer pixelsamples" 4
Integrator "volpath" "integer maxdepth" 1
WorldBegin
MakeNamedMedium "fire" "string type" "fire" "string dataset" "torch.####.vdb" "string fuel" "propane"
  "string velocitygrid" "vel"
AttributeBegin
  MediumInterface "fire" ""
  Material "interface"
  Shape "sphere" "float radius" 1.5
AttributeEnd
EOF

# ---- the farm: 3 frames × 4 tiles, then the merge; wait for the merge job
start=$(date +%s%N)
out=$("$FM" farm slurm "$W/torch.pbrt" --frames 30-32 --tiles 4 --dir "$W/farm" -o "$W/farm.####.exr" --submit)
echo "$out"
merge_job=$(echo "$out" | sed -n 's/.*merge job \([0-9]*\).*/\1/p')
[ -n "$merge_job" ] || fail "no merge job id in: $out"
state=""
for _ in $(seq 1 600); do
    state=$(scontrol show job "$merge_job" 2>/dev/null | sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p' | sort -u | tr '\n' ' ')
    case "$state" in
        *PENDING* | *RUNNING* | *CONFIGURING* | *COMPLETING* | "") sleep 0.5 ;;
        *) break ;;
    esac
done
farm_ms=$((($(date +%s%N) - start) / 1000000))
[ "$state" = "COMPLETED " ] || fail "merge job $merge_job ended $state; logs: $(tail -n 3 "$W"/farm/logs/*.log)"

# ---- a local render of the same frames, and the comparison
start=$(date +%s%N)
"$FM" render "$W/torch.pbrt" --frames 30-32 -q -o "$W/local.####.exr"
local_ms=$((($(date +%s%N) - start) / 1000000))
for f in 30 31 32; do
    "$FM" diff "$W/farm.00$f.exr" "$W/local.00$f.exr" || fail "frame $f: the farm's frame is not the local render"
done
say "3 frames × 4 tiles on Slurm equal the local render bit for bit"
say "wall time: farm $farm_ms ms (submitted to merged: 12 render and 3 merge tasks on $CPUS CPUs), local $local_ms ms"
