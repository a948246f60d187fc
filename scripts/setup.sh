#!/usr/bin/env bash
# Installs what the tests need on a fresh Debian machine that has only the Rust toolchain.
# Idempotent: does nothing when everything is present.
set -euo pipefail

need=()
have() { dpkg -s "$1" >/dev/null 2>&1; }
# GPU tests (crates/fathom-gpu): wgpu through Vulkan; on a machine without a GPU, Mesa's
# lavapipe driver runs the same shaders on the CPU. The tests fail (never skip) without it.
for p in mesa-vulkan-drivers libvulkan1; do
  have "$p" || need+=("$p")
done
# Mandelbulber2: its shipped example .fract files are the import tests' input (and
# scripts/mandelbulber-masks.sh renders the golden silhouettes with it).
have mandelbulber2 || need+=(mandelbulber2)
# ffmpeg: `fathom render --path` makes a video of a flight path's frames with it, and a test
# (crates/fathom/src/cmd_flight.rs) makes one.
have ffmpeg || need+=(ffmpeg)
# Slurm: scripts/slurm-local.sh runs a one-node cluster (munge, slurmctld, slurmd) for the
# render-farm test (scripts/farm-slurm-test.sh); it starts them itself, by PID, never as services.
for p in slurmctld slurmd slurm-client munge; do
  have "$p" || need+=("$p")
done
# The window tests run the real explorer window on a virtual X server: the smoke test
# (crates/fathom/tests/window_smoke.rs) through xvfb-run (Xvfb with an xauth cookie for the one
# command), the real-input tests (crates/fathom/tests/window_input.rs, crates/fathom-xdrive)
# on an Xvfb of their own, started and stopped by its PID, with X events from xdotool and
# screen captures from ImageMagick's `import`.
for p in xvfb xauth xdotool imagemagick; do
  have "$p" || need+=("$p")
done

if [ ${#need[@]} -gt 0 ]; then
  echo "setup: installing ${need[*]}"
  sudo_cmd=""
  [ "$(id -u)" -ne 0 ] && sudo_cmd="sudo"
  $sudo_cmd apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq "${need[@]}"
fi
