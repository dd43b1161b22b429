#!/usr/bin/env bash
# Issue 22: the G-buffer's cost of the glTF material on the H200 (materials-gpu), after a
# warm-up run that brings the SM clock up.
set -u
source docs/bench/device-env.sh
.gpu-bin/materials-gpu --bench --frames 50 --out /tmp/warm > /dev/null 2>&1
echo "clock after warm-up $(clock)" | tee -a $OUT/gpu.txt
.gpu-bin/materials-gpu --bench --out $OUT 2>&1 | grep -v "^\s*[0-9]*:\|^\s*at " | tee $OUT/materials.log
echo "clock after $(clock)" | tee -a $OUT/gpu.txt
