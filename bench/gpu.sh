#!/usr/bin/env bash
# The GPU engine's figures (issue 30), for a machine with a GPU, in one go:
# gpu_figures (the issue-5 workload and the demo night street at 1080p and
# 4K: plan, steady-state frame from planes in memory to result planes, GPU
# against CPU), the night street's 4K kernel composed on each device, and
# the studio's preview latency on both devices, 1280 and 3840 wide. Build
# here first, then run there with the binaries carried:
#   cargo build --release -p aureole-cli -p aureole-tools --bin aureole --bin gpu_figures
#   bash bench/gpu.sh [OUT]      # OUT defaults to bench/out/gpu
# Where Vulkan's loader is missing (a bare GPU machine), unpack Debian's
# libvulkan1 first (the device tool's README says how).
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-bench/out/gpu}
mkdir -p "$out"
{
  echo "load: $(uptime | sed 's/.*load average: //')"
  target/release/gpu_figures 1080p 4k
  # The night street's 4K kernel (bloom ⊛ a spectral 7-blade stop), its
  # effects composed on each device.
  for device in gpu cpu; do
    target/release/aureole psf --config configs/night-street.toml --size 7679x4319 \
      --image-width 3840 --device "$device" -o "$out/kernel-$device.exr"
  done
  for device in gpu cpu; do
    for width in 1280 3840; do
      python3 bench/studio_latency.py --device "$device" --width "$width" | sed '/In the page/,$d'
    done
  done
} 2>&1 | tee "$out/figures.txt"
