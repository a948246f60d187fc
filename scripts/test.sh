#!/usr/bin/env bash
# Runs every test of the workspace: formatting, lints, unit/integration/property tests, and the
# short fuzz pass over the scene parser and tape compiler. Installs what the tests need (see
# scripts/setup.sh) when it is missing. This is the command .ci/run calls.
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/setup.sh

echo "== rustfmt"
cargo fmt --all -- --check
echo "== clippy"
cargo clippy --workspace --all-targets --quiet -- -D warnings
echo "== tests"
cargo test --workspace
echo "== render farm on a local Slurm cluster"
bash scripts/farm-slurm-test.sh
