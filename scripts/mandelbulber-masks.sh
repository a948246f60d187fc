#!/usr/bin/env bash
# Renders the golden silhouettes of crates/fathom/tests/mandelbulber-masks/ with Mandelbulber2
# itself (headless), from the example files its Debian package ships. Run after changing the
# list in sources.txt; commit the .pbm files it writes.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cargo test -p fathom --release -- --ignored regenerate_mandelbulber_masks
