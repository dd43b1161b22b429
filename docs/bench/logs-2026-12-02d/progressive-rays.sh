#!/usr/bin/env bash
# Issue 21: progressive mode with VPL visibility by rays on the H200 (truths traced beforehand, carried).
set -u
for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json WGPU_BACKEND=vulkan
export DEFERRED_FIXTURES=$PWD/.gpu-data/fixtures
clock() { nvidia-smi --query-gpu=clocks.sm --format=csv,noheader; }
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm --format=csv,noheader | tee $OUT/gpu.txt
.gpu-bin/progressive-gpu --bench --out $OUT/r --images $OUT/i --truth-cache .gpu-data/truth --side 128 --spp 4096 \
  --scenes ${SCENES:-cornell,sponza,large} --patterns 1,2 --visibility rays --seconds ${SECONDS_PER_ROW:-20} 2>&1 \
  | grep -v "^\s*[0-9]*:\|^\s*at " | tee $OUT/progressive.log
echo "clock after $(clock)" | tee -a $OUT/gpu.txt
