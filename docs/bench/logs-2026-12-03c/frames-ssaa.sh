#!/bin/bash
# Supersampling inside the frame on the H200 (issue 23): the Sponza recipe (4096 lights tiled +
# a sun, 1024 VPLs 4x4 with ManyLoD visibility, adaptive 4x4 SSAA) at 1920x1080, 120 timed
# frames after 120 warm-up frames, beside the same recipe without supersampling and with full
# 4x4 supersampling in the same run; and the Cornell box with GI with adaptive 4x4. The SM
# clock is sampled every 50 ms while each runs (clock-<run>.log).
set -e
source docs/bench/sequence-runs.sh
r=fixtures/recipes/sponza-lights-gi.toml
grep -v -e '^ssaa' -e '^adaptive' $r > /tmp/sponza-no-ssaa.toml
grep -v -e '^adaptive' $r > /tmp/sponza-full-ssaa.toml
run sponza-no-ssaa --recipe /tmp/sponza-no-ssaa.toml
run sponza-adaptive-ssaa --recipe $r
run sponza-full-ssaa --recipe /tmp/sponza-full-ssaa.toml
run cornell-gi-adaptive-ssaa --recipe fixtures/recipes/cornell-gi.toml --ssaa 4 --adaptive
# One frame of the recipe (no sequence keys) says the share of samples adaptive SSAA took.
grep -v -e '^frames' -e '^fps' -e '^light-orbit' $r > /tmp/sponza-one.toml
.gpu-bin/deferred --recipe /tmp/sponza-one.toml --size 1920x1080 --out /tmp/sponza-one \
  > "$OUT/sponza-one-frame.txt" 2>&1
cp /tmp/sponza-one/ssaa-samples.png "$OUT/sponza-ssaa-samples.png"
cp /tmp/sponza-adaptive-ssaa/timings.svg "$OUT/sponza-adaptive-ssaa.svg"
cp /tmp/sponza-adaptive-ssaa/frames/frame-00060.png "$OUT/sponza-adaptive-ssaa.png"
pack
