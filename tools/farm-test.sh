#!/usr/bin/env bash
# The render-farm job descriptions (farm/, docs/farm.md) on real engines, against one
# process: run by .ci/run after the tests, with the atmo they built.
#
#   tools/farm-test.sh [ATMO]        (default target/debug/atmo; needs root or sudo)
#
# Slurm: installs Slurm and MUNGE from Debian's packages, starts munged, slurmctld and
# slurmd on localhost (one node, 2 CPUs, every file in a temporary folder), and
# - precomputes a table in 4 parts as a job array and merges it in a job that depends on
#   the array (afterok): the table must equal a one-process precompute, byte for byte;
# - draws a show as a job array of 4 chunks, cancels chunk 2 while it draws (scancel)
#   and requeues it: the cancelled task leaves only whole frames, the requeued one draws
#   only what is missing, and the frames and the assembled show equal one process's.
# Open Job Description: the template passes `openjd check` (openjd-cli from PyPI) and
# `openjd run` draws one chunk, equal to the same frames of one process.
# Kubernetes: the Indexed Job's command is run for every index as its pods would run it
# (JOB_COMPLETION_INDEX set, in sh), then the assemble job's: equal to one process.
# Every daemon it started is stopped, whatever happens.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
atmo=$(realpath "${1:-target/debug/atmo}")
[ -x "$atmo" ] || { echo "farm-test: no atmo binary at $atmo (build it first)" >&2; exit 1; }
sudo=""
if [ "$(id -u)" != 0 ]; then sudo="sudo"; fi

say() { echo "farm-test: $*"; }
fail() { echo "farm-test: FAILED: $*" >&2; exit 1; }

if ! command -v slurmctld >/dev/null || ! command -v slurmd >/dev/null \
  || ! command -v sbatch >/dev/null || ! command -v munged >/dev/null; then
  say "installing Slurm and MUNGE"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends \
    slurm-wlm munge >/dev/null
fi
# The job array's folders must be readable by the jobs, which run as this user.
work=$(mktemp -d /tmp/atmo-farm.XXXXXX)
chmod 755 "$work"
export SLURM_CONF=$work/slurm.conf

stop() {
  local rc=$?
  for pid in slurmd.pid slurmctld.pid munged.pid; do
    [ -f "$work/$pid" ] && $sudo kill "$(cat "$work/$pid")" 2>/dev/null || true
  done
  sleep 1
  for pid in slurmd.pid slurmctld.pid munged.pid; do
    [ -f "$work/$pid" ] && $sudo kill -9 "$(cat "$work/$pid")" 2>/dev/null || true
  done
  if [ "$rc" != 0 ]; then
    for log in "$work"/*.log "$work"/jobs/*.log; do
      [ -f "$log" ] && { echo "--- $log"; tail -n 20 "$log"; }
    done
  fi
  $sudo rm -rf "$work"
  exit "$rc"
}
trap stop EXIT

# --- the daemons: a private munged on its own socket and key, one Slurm node ---
$sudo mungekey --create --keyfile "$work/munge.key" 2>/dev/null \
  || $sudo dd if=/dev/urandom of="$work/munge.key" bs=1024 count=1 status=none
$sudo chmod 600 "$work/munge.key"
$sudo munged --force --key-file="$work/munge.key" --socket="$work/munge.socket" \
  --pid-file="$work/munged.pid" --log-file="$work/munged.log" --seed-file="$work/munge.seed"
user=$(id -un)
# Two CPUs, or one on a machine with one: a node declared with more CPUs than it has
# is drained by slurmd.
cpus=$(($(nproc) < 2 ? $(nproc) : 2))
cat >"$SLURM_CONF" <<EOF
ClusterName=atmo-farm-test
SlurmctldHost=localhost(127.0.0.1)
SlurmUser=root
SlurmdUser=root
SlurmctldPort=16817
SlurmdPort=16818
AuthType=auth/munge
AuthInfo=socket=$work/munge.socket
CredType=cred/munge
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MpiDefault=none
MailProg=/bin/true
KillWait=5
NodeName=localhost NodeAddr=127.0.0.1 CPUs=$cpus State=UNKNOWN
PartitionName=main Nodes=localhost Default=YES MaxTime=INFINITE State=UP
EOF
mkdir -p "$work/state" "$work/spool" "$work/jobs"
say "starting slurmctld and slurmd ($user submits)"
$sudo env SLURM_CONF="$SLURM_CONF" slurmctld
$sudo env SLURM_CONF="$SLURM_CONF" slurmd -N localhost
for _ in $(seq 60); do
  [ "$(sinfo -h -o %T 2>/dev/null)" = idle ] && break
  sleep 0.5
done
[ "$(sinfo -h -o %T)" = idle ] || fail "the node is not idle: $(sinfo -h -o '%T %E')"

# The state of a job (or an array's task, JOB_K) while slurmctld remembers it.
state() { scontrol -o show job "$1" 2>/dev/null | grep -oE 'JobState=[A-Z_]+' | head -n 1 | cut -d= -f2; }
# Waits until none of these jobs is pending or running (at most $2 s).
wait_jobs() {
  local ids=$1 limit=$2 t=0
  while squeue -h -j "$ids" -t PENDING,RUNNING,CONFIGURING,COMPLETING,REQUEUED 2>/dev/null | grep -q .; do
    sleep 0.5
    t=$((t + 1))
    [ "$t" -lt $((limit * 2)) ] || fail "jobs $ids still not done after $limit s: $(squeue -h -j "$ids")"
  done
}
same() { cmp -s "$1" "$2" || fail "$2 differs from one process's $1"; }

# --- one process: the references ---
tiny=(--directions 8 --sun-steps 6 --altitude-steps 3 --shells 12 --scattering-directions 16)
show=(shafts "$root/scenes/show.toml" --animate --fps 10 --backend cpu)
say "one process: the table and the show"
"$atmo" precompute sky "${tiny[@]}" -o "$work/one.atmo-sky" 2>"$work/one.log"
RAYON_NUM_THREADS=2 "$atmo" "${show[@]}" -o "$work/one" 2>>"$work/one.log"
frames=$(find "$work/one" -name 'frame_*.png' | wc -l)
[ "$frames" -gt 40 ] || fail "the show has $frames frames"

cd "$work/jobs"
# --- the table: 4 parts as an array, the merge after them ---
parts=$(sbatch --parsable --array=1-4 --cpus-per-task=1 --export=ALL,ATMO="$atmo" \
  "$root/farm/slurm/table-part.sbatch" "$work/parts" "${tiny[@]}")
merge=$(sbatch --parsable --dependency=afterok:"$parts" --cpus-per-task=1 \
  --export=ALL,ATMO="$atmo" "$root/farm/slurm/table-merge.sbatch" "$work/parts" "$work/farm.atmo-sky")
say "table: parts job $parts, merge job $merge (afterok)"

# --- the show: 4 chunks as an array; chunk 2 cancelled while it draws, then requeued ---
chunks=$(sbatch --parsable --array=1-4 --cpus-per-task=1 --export=ALL,ATMO="$atmo" \
  "$root/farm/slurm/animate.sbatch" "$work/frames" "${show[@]}")
say "show: $frames frames in job array $chunks"
# Chunk 2's frames, as atmo splits them: frames count * 1/4 up to count * 2/4.
first=$((frames / 4))
last=$((frames * 2 / 4))
drawn() {
  local n=0 k
  for ((k = first; k < last; k++)); do
    [ -f "$work/frames/$(printf 'frame_%06d.png' "$k")" ] && n=$((n + 1))
  done
  echo "$n"
}
for _ in $(seq 1200); do
  [ "$(state "${chunks}_2")" = RUNNING ] && [ "$(drawn)" -ge 1 ] && break
  sleep 0.1
done
[ "$(drawn)" -ge 1 ] || fail "chunk 2 drew nothing (state $(state "${chunks}_2"))"
scancel "${chunks}_2"
for _ in $(seq 100); do
  [ "$(state "${chunks}_2")" = CANCELLED ] && break
  sleep 0.1
done
[ "$(state "${chunks}_2")" = CANCELLED ] || fail "chunk 2 is $(state "${chunks}_2") after scancel"
before=$(drawn)
[ "$before" -lt $((last - first)) ] || fail "chunk 2 was done before it was cancelled"
# What the cancelled task left: whole frames only, no temporary.
leftovers=$(find "$work/frames" -name '.*' -type f | wc -l)
[ "$leftovers" = 0 ] || fail "the cancelled task left $leftovers temporary files"
for f in "$work"/frames/frame_*.png; do same "$work/one/$(basename "$f")" "$f"; done
say "chunk 2 cancelled with $before of $((last - first)) frames drawn; requeued"
scontrol requeue "${chunks}_2"
# A requeued job waits a while before it is eligible again; a user who requeues by
# hand may start it at once.
scontrol update JobId="${chunks}_2" StartTime=now 2>/dev/null || true
case $(state "${chunks}_2") in
  PENDING | REQUEUED | RUNNING | COMPLETING | COMPLETED) ;;
  *) fail "chunk 2 is $(state "${chunks}_2") after scontrol requeue" ;;
esac
# afterany, not afterok: Slurm never satisfies afterok on an array one of whose tasks
# was cancelled, requeued or not; atmo assemble itself refuses an incomplete set.
assemble=$(sbatch --parsable --dependency=afterany:"$chunks" --cpus-per-task=1 \
  --export=ALL,ATMO="$atmo" "$root/farm/slurm/assemble.sbatch" "$work/frames" "$work/farm.png")
say "assemble job $assemble (afterany on the array)"
wait_jobs "$parts,$merge,$chunks,$assemble" 240
for job in "$merge" "$assemble"; do
  [ "$(state "$job")" = COMPLETED ] || fail "job $job ended $(state "$job")"
done
grep -q ", $before kept from an earlier run" atmo-frames-"${chunks}"_2.log \
  || fail "the requeued chunk did not resume: $(tail -n 3 atmo-frames-"${chunks}"_2.log)"
same "$work/one.atmo-sky" "$work/farm.atmo-sky"
for f in "$work"/one/frame_*.png; do same "$f" "$work/frames/$(basename "$f")"; done
same "$work/one/animation.png" "$work/farm.png"
say "Slurm: the merged table and the $frames frames and show equal one process's"

# --- Open Job Description: checked, and one chunk run locally ---
venv=$root/target/farm-venv
[ -x "$venv/bin/openjd" ] || {
  python3 -m venv "$venv"
  "$venv/bin/python" -m pip install -q openjd-cli
}
"$venv/bin/openjd" check "$root/farm/openjd/show.yaml" >/dev/null
"$venv/bin/openjd" run "$root/farm/openjd/show.yaml" --step Render --task-param Chunk=3 \
  -p Scene="$root/scenes/show.toml" -p OutputDir="$work/openjd" -p Chunks=4 -p Fps=10 \
  -p Atmo="$atmo" >"$work/openjd.log" 2>&1 || fail "openjd run: $(tail -n 5 "$work/openjd.log")"
n=0
for f in "$work"/openjd/frame_*.png; do same "$work/one/$(basename "$f")" "$f"; n=$((n + 1)); done
[ "$n" -gt 0 ] || fail "openjd run drew no frame"
say "Open Job Description: valid; chunk 3 of 4 ($n frames) equals one process's"

# --- Kubernetes: the Indexed Job's command as its pods run it ---
manifest() {
  "$venv/bin/python" - "$@" <<'EOF'
import sys, yaml
docs = [d for d in yaml.safe_load_all(open(sys.argv[1])) if d and d["kind"] == "Job"]
job = docs[0]["spec"]
container = job["template"]["spec"]["containers"][0]
env = {e["name"]: e["value"] for e in container.get("env", [])}
if sys.argv[2] == "completions":
    print(job.get("completions", 1), env.get("CHUNKS", ""))
else:
    print(" ".join(container["command"][:2]) + "\t" + container["args"][0])
EOF
}
read -r completions chunks_env < <(manifest "$root/farm/k8s/show-job.yaml" completions)
[ "$completions" = "$chunks_env" ] || fail "show-job.yaml: completions $completions, CHUNKS $chunks_env"
IFS=$'\t' read -r shell script < <(manifest "$root/farm/k8s/show-job.yaml" command)
[ "$shell" = "sh -c" ] || fail "show-job.yaml runs '$shell', not sh -c"
mkdir -p "$work/bin"
ln -s "$atmo" "$work/bin/atmo"
for ((k = 0; k < completions; k++)); do
  PATH=$work/bin:$PATH JOB_COMPLETION_INDEX=$k SCENE="$root/scenes/show.toml" \
    FRAMES="$work/k8s" FPS=10 CHUNKS=$completions RAYON_NUM_THREADS=2 \
    sh -c "$script" 2>>"$work/k8s.log"
done
IFS=$'\t' read -r shell script < <(manifest "$root/farm/k8s/assemble-job.yaml" command)
PATH=$work/bin:$PATH FRAMES="$work/k8s" OUTPUT="$work/k8s.png" sh -c "$script" 2>>"$work/k8s.log"
same "$work/one/animation.png" "$work/k8s.png"
say "Kubernetes: $completions indexed pods' commands and the assembly equal one process"
say "passed"
