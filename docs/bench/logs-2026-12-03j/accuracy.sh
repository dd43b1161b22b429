# The accuracy benchmark with point-based GI's rows and frame times, on the device:
# `bash docs/bench/logs-2026-12-03j/accuracy.sh` with .gpu-bin/accuracy-gpu (a stripped
# `cargo bench -p deferred-pipeline --bench accuracy-gpu --no-run` executable) and the Cornell
# box and Sponza under .gpu-data/fixtures; the truths are path-traced on the device's CPUs.
# A short discarded GPU run first raises the SM clock; results packed into $OUT/results.tgz.
RESULTS=$OUT; OUT=/tmp/res; mkdir -p $OUT
source docs/bench/device-env.sh
chmod +x .gpu-bin/accuracy-gpu
nvidia-smi --query-gpu=clocks.sm --format=csv,noheader,nounits -lms 100 > "$OUT/clock-accuracy.log" &
sampler=$!
.gpu-bin/accuracy-gpu > /dev/null 2>&1
echo "SM clock after the warm-up run: $(clock)" > "$OUT/accuracy.txt"
.gpu-bin/accuracy-gpu --bench --spp 2048 --out "$OUT" >> "$OUT/accuracy.txt" 2>&1 || echo "accuracy-gpu failed" >> "$OUT/accuracy.txt"
kill $sampler
grep -E "PBGI|VPLs, ManyLoD|no visibility|rays  |wrote|failed" "$OUT/accuracy.txt" | tail -24
tar czf "$RESULTS/results.tgz" -C /tmp/res .
# The committed report's timing line said "1 frames" (the header's frame count was not updated when the frame times were added); the code timed 10 frames per row, and the line was corrected to say so.
