#!/bin/bash
# Per-frame report of every shipped recipe at 1920x1080, 120 timed frames after 120 warm-up
# frames (issue 23 item 7), from the `deferred` program's own sequence outputs: timings.csv and
# timings.svg per recipe (trace.json for one), frame 60 of each. The SM clock is sampled every
# 50 ms in the background while each recipe runs (clock-<recipe>.log).
set -e
source docs/bench/device-env.sh
chmod +x .gpu-bin/deferred
for r in cornell-gi cesium-man-cornell fox-walls sponza-lights-gi; do
  nvidia-smi --query-gpu=clocks.sm --format=csv,noheader,nounits -lms 50 > "$OUT/clock-$r.log" &
  sampler=$!
  .gpu-bin/deferred --recipe fixtures/recipes/$r.toml --size 1920x1080 --frames 120 \
    --warm-up 120 --frame-every 60 --out /tmp/$r > "$OUT/$r.txt" 2>&1
  kill $sampler
  cp /tmp/$r/timings.csv "$OUT/$r.csv"
  cp /tmp/$r/timings.svg "$OUT/$r.svg"
  cp /tmp/$r/frames/frame-00060.png "$OUT/$r.png"
done
cp /tmp/cesium-man-cornell/trace.json "$OUT/cesium-man-cornell.trace.json"
