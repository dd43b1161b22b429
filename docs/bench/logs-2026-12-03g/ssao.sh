# The ssao benchmark on the device: `bash docs/bench/logs-2026-12-03g/ssao.sh` with
# .gpu-bin/ssao-gpu (a stripped `cargo bench -p deferred-ssao --bench ssao-gpu --no-run`
# executable), the SM clock sampled every 100 ms meanwhile; results packed into
# $OUT/results.tgz.
RESULTS=$OUT; OUT=/tmp/res; mkdir -p $OUT
source docs/bench/device-env.sh
chmod +x .gpu-bin/ssao-gpu
nvidia-smi --query-gpu=clocks.sm --format=csv,noheader,nounits -lms 100 > "$OUT/clock-ssao.log" &
sampler=$!
.gpu-bin/ssao-gpu --bench --out "$OUT" > "$OUT/ssao.txt" 2>&1 || echo "ssao-gpu failed" >> "$OUT/ssao.txt"
kill $sampler
tail -5 "$OUT/ssao.txt"
tar czf "$RESULTS/results.tgz" -C /tmp/res .
# Afterwards the three sheets were re-encoded as 8-bit grey PNGs (R = G = B checked per pixel), a third of the size. Measured at commit a58102d (with the smoothing after pass 2).
