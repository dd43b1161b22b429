#!/usr/bin/env bash
# Issue 22: what the material made the untextured G-buffer cost. frame-gpu (Sponza, factors
# only) built at e182137 (before: 5 targets, 32-byte interleaved vertices) and at this commit
# (6 targets with emission, positions + 60-byte attributes, the full material shader), run
# alternately in one call after a warm-up.
set -u
source docs/bench/device-env.sh
.gpu-bin/frame-gpu --bench --frames 50 --out /tmp/warm > /dev/null 2>&1
echo "clock after warm-up $(clock)" | tee -a $OUT/gpu.txt
run() { "$@" 2>&1 | grep -v "^\s*[0-9]*:\|^\s*at " | tee -a $OUT/frame.log; }
echo "## before (e182137)" >> $OUT/frame.log; run .gpu-bin/frame-gpu-before --bench --out $OUT/before
echo "## after" >> $OUT/frame.log; run .gpu-bin/frame-gpu --bench --out $OUT/after
echo "## before again" >> $OUT/frame.log; run .gpu-bin/frame-gpu-before --bench --out /tmp/b2
echo "## after again" >> $OUT/frame.log; run .gpu-bin/frame-gpu --bench --out /tmp/a2
echo "clock after $(clock)" | tee -a $OUT/gpu.txt
