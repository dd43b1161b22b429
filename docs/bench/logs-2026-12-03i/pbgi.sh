# The pbgi benchmark on the device: `bash docs/bench/logs-2026-12-03i/pbgi.sh` with
# .gpu-bin/pbgi-gpu (a stripped `cargo bench -p deferred-pipeline --bench pbgi-gpu --no-run`
# executable) and Sponza under .gpu-data/fixtures; a short discarded run first raises the SM
# clock, which is sampled every 100 ms meanwhile; results packed into $OUT/results.tgz.
RESULTS=$OUT; OUT=/tmp/res; mkdir -p $OUT
source docs/bench/device-env.sh
chmod +x .gpu-bin/pbgi-gpu
nvidia-smi --query-gpu=clocks.sm --format=csv,noheader,nounits -lms 100 > "$OUT/clock-pbgi.log" &
sampler=$!
.gpu-bin/pbgi-gpu --bench --frames 3 --out /tmp/warm > /dev/null 2>&1
echo "SM clock after the warm-up run: $(clock)" > "$OUT/pbgi.txt"
.gpu-bin/pbgi-gpu --bench --out "$OUT" >> "$OUT/pbgi.txt" 2>&1 || echo "pbgi-gpu failed" >> "$OUT/pbgi.txt"
kill $sampler
tail -12 "$OUT/pbgi.txt"
tar czf "$RESULTS/results.tgz" -C /tmp/res .
# The second run: the surfels lit on the GPU every frame (the first, logs-2026-12-03h, lit them on the CPU at set-up).
