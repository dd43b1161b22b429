# Single-view point rendering against rasterisation, on the device:
# `bash docs/bench/logs-2026-12-03k/points.sh` with .gpu-bin/points-gpu (a stripped
# `cargo bench -p deferred-pipeline --bench points-gpu --no-run` executable) and spot and the
# dragon under .gpu-data/fixtures. A short discarded GPU run first raises the SM clock; results
# packed into $OUT/results.tgz.
RESULTS=$OUT; OUT=/tmp/res; mkdir -p $OUT
source docs/bench/device-env.sh
chmod +x .gpu-bin/points-gpu
nvidia-smi --query-gpu=clocks.sm --format=csv,noheader,nounits -lms 100 > "$OUT/clock-points.log" &
sampler=$!
.gpu-bin/points-gpu > /dev/null 2>&1
echo "SM clock after the warm-up run: $(clock)" > "$OUT/points.txt"
.gpu-bin/points-gpu --bench --out "$OUT" >> "$OUT/points.txt" 2>&1 || echo "points-gpu failed" >> "$OUT/points.txt"
kill $sampler
cat "$OUT/points.txt" | tail -30
tar czf "$RESULTS/results.tgz" -C /tmp/res .
