#!/usr/bin/env bash
# Issue 21: Segovia's Table 5 at a resolution where the shading counts: the Cornell box at 512²
# on the H200, rays for both and SSM, with the near field, interleaving without the blur. The
# truth is traced on the device's 16 cores (cached under .gpu-data/truth for later runs).
set -u
for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json WGPU_BACKEND=vulkan
export DEFERRED_FIXTURES=$PWD/.gpu-data/fixtures
clock() { nvidia-smi --query-gpu=clocks.sm --format=csv,noheader; }
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm --format=csv,noheader | tee $OUT/gpu.txt
run() {
  .gpu-bin/progressive-gpu --bench --truth-cache .gpu-data/truth --side 512 --spp 4096 \
    --scenes cornell --blur false "$@" 2>&1 | grep -v "^\s*[0-9]*:\|^\s*at "
}
start=$(date +%s)
run --out /tmp/truth --patterns 1 --seconds 0 > $OUT/truth.log
echo "truth traced in $(( $(date +%s) - start )) s; clock $(clock)" | tee -a $OUT/gpu.txt
run --out /tmp/warm --patterns 1 --visibility rays --direct rays --seconds 10 > /dev/null
echo "clock after warm-up $(clock)" | tee -a $OUT/gpu.txt
run --out $OUT/r --patterns 1,2,4 --visibility rays --direct rays --seconds 45 | tee $OUT/rays-512.log
run --out $OUT/r --patterns 1,2,4 --seconds 45 | tee $OUT/ssm-512.log
echo "clock after $(clock)" | tee -a $OUT/gpu.txt
