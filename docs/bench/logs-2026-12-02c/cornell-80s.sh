#!/usr/bin/env bash
# Issue 21: the Cornell box's progressive floor with the rim lookup and slope tolerance, 64² and 128² VPL tiles.
set -u
for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json WGPU_BACKEND=vulkan
export DEFERRED_FIXTURES=$PWD/.gpu-data/fixtures SUBDIV_BFT_DIR=$PWD/.gpu-data/bft
(cd .gpu-bin && tar xf bins.tar.xz)
clock() { nvidia-smi --query-gpu=clocks.sm --format=csv,noheader; }
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm --format=csv,noheader | tee $OUT/gpu.txt
timeout 30 .gpu-bin/subdiv-gpu --bench --out /tmp/warm > /dev/null 2>&1
echo "clock after the discarded warm-up: $(clock)" | tee -a $OUT/gpu.txt
for t in 64 128; do
  echo "== tile $t"
  timeout 250 .gpu-bin/progressive-gpu --bench --out $OUT/t$t --side 128 --spp 4096 --seconds ${1:-90} --scenes cornell --patterns 1 --vpl-tile $t 2>&1 | grep -v "^\s*[0-9]*:\|^\s*at " | grep -v "^wrote"
done | tee $OUT/exp3.log
echo "clock after $(clock)" | tee -a $OUT/gpu.txt
