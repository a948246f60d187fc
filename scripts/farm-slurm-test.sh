#!/usr/bin/env bash
# The render farm on a real Slurm cluster (issue 17): starts a one-node cluster with
# scripts/slurm-local.sh (stopped by its PIDs on exit), then
#   1. an 8-task array renders a 256x192 still in 8 tiles; the assembled PNG must equal a
#      single-process `fathom render` byte for byte;
#   2. an 8-task array renders 16 frames of a flight path (`farm slurm --submit --wait`); each
#      frame must equal `fathom render --path`'s, and assembly makes a 16-frame video;
#   3. the same animation as a new job, with task 5 killed (scancel) after the first of its
#      two frames: exactly the other is missing; resubmitting the array renders exactly that
#      frame, and across both runs every frame was rendered once;
#   4. a full disk (a 40 KiB tmpfs) fails with a clear error and no file under a final name.
# Needs slurmctld slurmd slurm-client munge (scripts/setup.sh installs them) and root for
# the tmpfs. Takes about half a minute after the build.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)

# The binary of the workspace's test build (`cargo test --workspace` builds it for the
# integration tests; after scripts/test.sh this is instant). `cargo build -p fathom` resolves
# features for that one package, not for the workspace, and compiled naga, fathom-svo,
# fathom-trace and more a second time: about 7 minutes of a test run.
cargo test -q --workspace --no-run
fathom="${CARGO_TARGET_DIR:-$root/target}/debug/fathom"
fathom=$(cd "$(dirname "$fathom")" && pwd)/fathom
work=$(mktemp -d /tmp/fathom-farm-test.XXXXXX)
tiny=""
cleanup() {
  bash "$root/scripts/slurm-local.sh" stop "$work/slurm" || true
  if [[ -n "$tiny" ]]; then umount "$tiny" 2>/dev/null || true; fi
  rm -rf "$work"
}
trap cleanup EXIT
fail() {
  echo "farm-slurm-test: FAIL: $*" >&2
  exit 1
}
start=$(date +%s)

eval "$(bash scripts/slurm-local.sh start "$work/slurm")"
echo "farm-slurm-test: cluster up ($(sinfo -h -o '%D node, %c CPUs, %T'))"

# Waits until no task of Slurm job $1 is pending or running.
wait_job() {
  while [[ -n "$(squeue -h -o %i -j "$1" 2>/dev/null)" ]]; do sleep 0.2; done
}

# 1. A tiled still.
"$fathom" render --preset mandelbulb --size 256x192 --threads 1 -q -o "$work/still-ref.png"
"$fathom" farm slurm --preset mandelbulb --size 256x192 --tiles 8 --tasks 8 -o "$work/still" \
  --submit --wait -q >/dev/null
"$fathom" farm status "$work/still"
"$fathom" farm assemble "$work/still" -o "$work/still.png"
cmp "$work/still.png" "$work/still-ref.png" || fail "the assembled still differs from the single render"
n=$(ls "$work"/still/logs/task-*.out | wc -l)
[[ $n -eq 8 ]] || fail "expected 8 task logs, found $n"
echo "farm-slurm-test: still: 8 tasks, assembled PNG identical to the single-process render"

# 2. An animation.
scene=docs/examples/mandelbulb-dive.ron
anim=(--size 64x48 --path dive --frames 16)
"$fathom" render "$scene" "${anim[@]}" --threads 1 --no-video -q -o "$work/anim-ref/"
"$fathom" farm slurm "$scene" "${anim[@]}" --tasks 8 -o "$work/anim" --submit --wait -q >/dev/null
for i in $(seq 0 15); do
  cmp "$work/anim/frame-$(printf %06d "$i").png" "$work/anim-ref/dive-$(printf %05d "$i").png" ||
    fail "frame $i differs from fathom render --path"
done
"$fathom" farm assemble "$work/anim" -o "$work/anim.mp4"
frames=$(ffprobe -v error -count_frames -select_streams v:0 -show_entries stream=nb_read_frames \
  -of csv=p=0 "$work/anim.mp4")
[[ "$frames" == 16 ]] || fail "the video has $frames frames, not 16"
echo "farm-slurm-test: animation: 16 frames identical to fathom render --path; 16-frame video"

# 3. Kill a task midway, then rerun.
"$fathom" farm slurm "$scene" "${anim[@]}" --tasks 8 -o "$work/kill" -q
# The same script, with task 5 pausing 20 s after each frame so it can be killed between its
# two frames.
sed 's|--threads 1$|--threads 1 --unit-delay-ms $([ "$SLURM_ARRAY_TASK_ID" = 5 ] \&\& echo 20000 \|\| echo 0)|' \
  "$work/kill/farm.sbatch" >"$work/kill/slow.sbatch"
grep -q "unit-delay-ms" "$work/kill/slow.sbatch" || fail "could not make the slow script"
id=$(sbatch --parsable "$work/kill/slow.sbatch")
log5="$work/kill/logs/task-$id-5.out"
for _ in $(seq 300); do
  grep -q "rendered frame-" "$log5" 2>/dev/null && break
  sleep 0.1
done
grep -q "rendered frame-" "$log5" 2>/dev/null || fail "task 5 never finished its first frame"
scancel "${id}_5"
wait_job "$id"
grep -c "rendered frame-" "$log5" | grep -qx 1 || fail "task 5 was not killed between its frames"
status=$("$fathom" farm status "$work/kill" --json)
missing=$(echo "$status" | tr -d ' \n' | sed 's/.*"missing":\[\([^]]*\)\].*/\1/')
[[ "$missing" =~ ^[0-9]+$ ]] || fail "after the kill, missing units are [$missing], expected one"
lost=frame-$(printf %06d "$missing").png
grep -q "rendered $lost" "$work"/kill/logs/task-"$id"-*.out && fail "$lost was rendered yet is missing"
ls -a "$work/kill" | grep -q "^$lost$" && fail "a file under the killed unit's final name"
echo "farm-slurm-test: killed task 5 after its first frame: only $lost missing, nothing partial"
id2=$(sbatch --parsable "$work/kill/farm.sbatch")
wait_job "$id2"
"$fathom" farm status "$work/kill"
again=$(grep -h "rendered frame-" "$work"/kill/logs/task-"$id2"-*.out | sed 's/.*rendered \(frame-[0-9]*\.png\).*/\1/')
[[ "$again" == "$lost" ]] || fail "the rerun rendered [$again], expected only $lost"
counts=$(grep -h "rendered frame-" "$work"/kill/logs/task-*.out | sed 's/.*rendered \(frame-[0-9]*\.png\).*/\1/' | sort | uniq -c)
[[ $(echo "$counts" | wc -l) -eq 16 ]] || fail "not every frame was rendered: $counts"
echo "$counts" | awk '$1 != 1 { bad = 1 } END { exit bad }' || fail "a frame was rendered twice: $counts"
for i in $(seq 0 15); do
  cmp "$work/kill/frame-$(printf %06d "$i").png" "$work/anim-ref/dive-$(printf %05d "$i").png" ||
    fail "frame $i of the resumed job differs"
done
echo "farm-slurm-test: the rerun rendered only $lost; every frame rendered exactly once; frames identical"

# 4. A full disk.
tiny="$work/tiny"
mkdir -p "$tiny"
if mount -t tmpfs -o size=40k tmpfs "$tiny" 2>"$work/mount.err"; then
  if "$fathom" render --preset mandelbulb --size 256x192 --tiles 2 --shard 0/1 --threads 1 -q \
    -o "$tiny/job" 2>"$work/full.err"; then
    fail "rendering onto a full disk succeeded"
  fi
  grep -q "No space left on device" "$work/full.err" || fail "unclear full-disk error: $(cat "$work/full.err")"
  # Nothing under a final name without its receipt; no temporary file left.
  for f in "$tiny"/job/tile-*.png; do
    [[ -e "$f" ]] || continue
    [[ -f "$tiny/job/receipts/$(basename "$f").json" ]] || fail "a tile without its receipt: $f"
  done
  "$fathom" farm status "$tiny/job" --json | tr -d ' \n' | grep -q '"corrupt":\[\]' ||
    fail "a corrupt unit after the full disk: $("$fathom" farm status "$tiny/job")"
  ls -a "$tiny/job" | grep -q "\.tmp-" && fail "a temporary file was left behind"
  echo "farm-slurm-test: full disk: \"$(head -c 160 "$work/full.err")\"; no partial file"
  umount "$tiny"
  tiny=""
else
  fail "cannot mount a tmpfs for the full-disk case (needs root): $(cat "$work/mount.err")"
fi

echo "farm-slurm-test: ok in $(($(date +%s) - start)) s"
