#!/usr/bin/env bash
# Issue 21: the progressive mode with the VPLs' near field (default since 2026-12-02, clamp 2 %
# of the diagonal) on the H200: rays for both on the Cornell box, the paper's rasterised maps
# (SSM, direct shadow maps) on the Cornell box, rays for both on Sponza and the larger scene
# (truths traced beforehand, carried). A first short run warms the SM clock up. The first run
# of this script had the blur on and the near field's y lit by all 1024 VPLs (logs *-blur.log).
set -u
for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json WGPU_BACKEND=vulkan
export DEFERRED_FIXTURES=$PWD/.gpu-data/fixtures
clock() { nvidia-smi --query-gpu=clocks.sm --format=csv,noheader; }
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm --format=csv,noheader | tee $OUT/gpu.txt
run() {
  .gpu-bin/progressive-gpu --bench --truth-cache .gpu-data/truth --side 128 --spp 4096 "$@" 2>&1 \
    | grep -v "^\s*[0-9]*:\|^\s*at "
}
run --out /tmp/warm --scenes cornell --patterns 1 --visibility rays --direct rays --seconds 15 > /dev/null
echo "clock after warm-up $(clock)" | tee -a $OUT/gpu.txt
# Interleaving with and without the blur (its bias floor stays above 1 %).
run --out $OUT/r --scenes cornell,sponza,large --patterns 1,2,4 --blur false --visibility rays --direct rays --seconds 30 | tee $OUT/rays.log
run --out $OUT/r --scenes cornell --patterns 1,2,4 --blur false --seconds 40 | tee $OUT/cornell-ssm.log
echo "clock after $(clock)" | tee -a $OUT/gpu.txt
