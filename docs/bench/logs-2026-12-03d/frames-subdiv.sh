#!/bin/bash
# Subdivision per frame on the H200 (issue 23): the CesiumMan recipe (skinned every frame,
# adaptive Loop subdivision up to level 4 at 2-pixel edges, shadow maps, 1024 VPLs with ManyLoD
# visibility refit every frame) at 1920x1080, 120 timed frames after 120 warm-up frames, beside
# the same recipe subdivided uniformly to level 2 and not subdivided, in the same run; then the
# three with direct light only. The SM clock is sampled every 50 ms while each runs
# (clock-<run>.log).
set -e
source docs/bench/sequence-runs.sh
r=fixtures/recipes/cesium-man-cornell.toml
grep -v -e '^subdiv' $r > /tmp/cesium-plain.toml
grep -v -e '^subdiv' $r > /tmp/cesium-uniform.toml
echo 'subdiv = 2' >> /tmp/cesium-uniform.toml
run cesium-plain --recipe /tmp/cesium-plain.toml
run cesium-uniform-2 --recipe /tmp/cesium-uniform.toml
run cesium-adaptive --recipe $r
# The same three with direct light only (no VPLs, no shadow maps): nothing is done on the CPU
# per frame, so the GPU is not starved and the skinning + subdivision passes run at full clock.
for v in plain uniform; do
  grep -v -e '^vpls' -e '^vpl-shadows' -e '^shadows' /tmp/cesium-$v.toml > /tmp/cesium-$v-direct.toml
done
grep -v -e '^vpls' -e '^vpl-shadows' -e '^shadows' $r > /tmp/cesium-adaptive-direct.toml
run cesium-plain-direct --recipe /tmp/cesium-plain-direct.toml
run cesium-uniform-2-direct --recipe /tmp/cesium-uniform-direct.toml
run cesium-adaptive-direct --recipe /tmp/cesium-adaptive-direct.toml
cp /tmp/cesium-adaptive/timings.svg "$OUT/cesium-adaptive.svg"
cp /tmp/cesium-adaptive/trace.json "$OUT/cesium-adaptive.trace.json"
cp /tmp/cesium-adaptive/frames/frame-00060.png "$OUT/cesium-adaptive.png"
pack
