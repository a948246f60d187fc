#!/usr/bin/env bash
# Installs what the tests need on a fresh Debian machine that has only the Rust toolchain.
# Idempotent: does nothing when everything is present.
set -euo pipefail

need=()
# (GPU and window tests add their packages here: mesa-vulkan-drivers libvulkan1 xvfb ...)

if [ ${#need[@]} -gt 0 ]; then
  echo "setup: installing ${need[*]}"
  sudo_cmd=""
  [ "$(id -u)" -ne 0 ] && sudo_cmd="sudo"
  $sudo_cmd apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq "${need[@]}"
fi
