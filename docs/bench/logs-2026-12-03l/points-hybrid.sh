# Single-view point rendering and the hybrid CPU/GPU cut, on the device:
# `bash docs/bench/logs-2026-12-03l/points-hybrid.sh` with .gpu-bin/{points-gpu,hybrid-gpu}
# (stripped `cargo bench -p deferred-pipeline --bench points-gpu --bench hybrid-gpu --no-run`
# executables) and spot, the dragon and Sponza under .gpu-data/fixtures. A short discarded GPU
# run first raises the SM clock; results packed into $OUT/results.tgz.
RESULTS=$OUT; OUT=/tmp/res; mkdir -p $OUT
source docs/bench/device-env.sh
chmod +x .gpu-bin/*
nvidia-smi --query-gpu=clocks.sm --format=csv,noheader,nounits -lms 100 > "$OUT/clock.log" &
sampler=$!
.gpu-bin/points-gpu > /dev/null 2>&1
echo "SM clock after the warm-up run: $(clock)" > "$OUT/points.txt"
.gpu-bin/points-gpu --bench --out "$OUT" >> "$OUT/points.txt" 2>&1 || echo "points-gpu failed" >> "$OUT/points.txt"
echo "SM clock before: $(clock)" > "$OUT/hybrid.txt"
.gpu-bin/hybrid-gpu --bench --out "$OUT" >> "$OUT/hybrid.txt" 2>&1 || echo "hybrid-gpu failed" >> "$OUT/hybrid.txt"
kill $sampler
tail -14 "$OUT/points.txt"; tail -12 "$OUT/hybrid.txt"
tar czf "$RESULTS/results.tgz" -C /tmp/res .
