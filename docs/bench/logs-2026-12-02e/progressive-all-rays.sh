#!/usr/bin/env bash
# Issue 21: the progressive mode with rays for the VPLs and the direct lights on the H200, without
# and with the VPLs' near field (truths traced beforehand, carried). A first short run warms the
# SM clock up.
set -u
for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json WGPU_BACKEND=vulkan
export DEFERRED_FIXTURES=$PWD/.gpu-data/fixtures
clock() { nvidia-smi --query-gpu=clocks.sm --format=csv,noheader; }
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm --format=csv,noheader | tee $OUT/gpu.txt
run() {
  .gpu-bin/progressive-gpu --bench --truth-cache .gpu-data/truth --side 128 --spp 4096 \
    --scenes cornell --visibility rays --direct rays "$@" 2>&1 | grep -v "^\s*[0-9]*:\|^\s*at "
}
run --out /tmp/warm --patterns 1 --seconds 15 > /dev/null
echo "clock after warm-up $(clock)" | tee -a $OUT/gpu.txt
run --out $OUT/r --images $OUT/i --patterns 1,2 --seconds ${SECONDS_PER_ROW:-60} | tee $OUT/all-rays.log
run --out $OUT/r --patterns 1,2 --seconds ${SECONDS_PER_ROW:-60} --near-field | tee $OUT/near-field.log
echo "clock after $(clock)" | tee -a $OUT/gpu.txt
