#!/bin/bash
# Per-frame report of every shipped recipe at 1920x1080, 120 frames (issue 23 item 7): the
# `deferred` program's own sequence outputs (timings.csv, trace.json, timings.svg,
# preview.gif) and two full frames each; the SM clock before and after each recipe.
set -e
source docs/bench/device-env.sh
chmod +x .gpu-bin/deferred
# Warm-up until the SM clock is up (it idles at 345 MHz).
for i in 1 2 3; do
  .gpu-bin/deferred --recipe fixtures/recipes/sponza-lights-gi.toml --size 1920x1080 --frames 24 --out /tmp/warm >/dev/null 2>&1
  echo "warm-up $i: SM $(clock)" | tee -a "$OUT/clock.txt"
done
for r in cornell-gi cesium-man-cornell fox-walls sponza-lights-gi; do
  echo "$r: SM before $(clock)" | tee -a "$OUT/clock.txt"
  .gpu-bin/deferred --recipe fixtures/recipes/$r.toml --size 1920x1080 --frames 120 --out /tmp/$r > "$OUT/$r.txt" 2>&1
  echo "$r: SM after $(clock)" | tee -a "$OUT/clock.txt"
  mkdir -p "$OUT/$r"
  cp /tmp/$r/timings.csv /tmp/$r/trace.json /tmp/$r/timings.svg /tmp/$r/preview.gif "$OUT/$r/"
  cp /tmp/$r/frames/frame-00000.png /tmp/$r/frames/frame-00060.png "$OUT/$r/"
done
