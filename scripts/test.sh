#!/usr/bin/env bash
# Runs every test of the workspace: formatting, lints, unit/integration/property tests, and the
# short fuzz pass over the scene parser and tape compiler. Installs what the tests need (see
# scripts/setup.sh) when it is missing. This is the command .ci/run calls.
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/setup.sh

echo "== rustfmt"
cargo fmt --all -- --check
echo "== clippy and tests"
# One build for both: cargo runs clippy-driver (clippy's rustc, which compiles as rustc does
# and lints on the way) in place of rustc for the workspace's own crates, the way `cargo
# clippy` does, but for the test build instead of a separate check build. A separate
# `cargo clippy --all-targets` checked every dependency (wgpu, egui, ...) a second time: 10 of
# the 47 minutes of a clean run. The lints are clippy's defaults with warnings denied,
# exactly `cargo clippy -- -D warnings` (CLIPPY_ARGS is how cargo-clippy passes those
# arguments to the driver); every target `cargo test` builds is linted (libraries, binaries,
# examples, unit and integration tests).
clippy_driver="$(rustup which clippy-driver 2>/dev/null || command -v clippy-driver || true)"
if [ -z "$clippy_driver" ]; then
  echo "test.sh: clippy-driver not found; install clippy (rustup component add clippy)" >&2
  exit 1
fi
# Exported: the farm test's `cargo build` below then finds the same (linted) build fresh
# instead of rebuilding the workspace without the driver.
export RUSTC_WORKSPACE_WRAPPER="$clippy_driver"
export CLIPPY_ARGS="-D__CLIPPY_HACKERY__warnings__CLIPPY_HACKERY__"
cargo test --workspace
echo "== render farm on a local Slurm cluster"
bash scripts/farm-slurm-test.sh
