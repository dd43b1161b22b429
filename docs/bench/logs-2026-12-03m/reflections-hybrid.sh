# Reflection maps and the hybrid CPU/GPU cut (again, with the lists' upload timed), on the
# device: `bash docs/bench/logs-2026-12-03m/reflections-hybrid.sh` with
# .gpu-bin/{reflections-gpu,hybrid-gpu} (stripped `cargo bench -p deferred-pipeline --bench
# reflections-gpu --bench hybrid-gpu --no-run` executables) and Sponza under
# .gpu-data/fixtures. A short discarded GPU run first raises the SM clock; results packed
# into $OUT/results.tgz.
RESULTS=$OUT; OUT=/tmp/res; mkdir -p $OUT
source docs/bench/device-env.sh
chmod +x .gpu-bin/*
nvidia-smi --query-gpu=clocks.sm --format=csv,noheader,nounits -lms 100 > "$OUT/clock.log" &
sampler=$!
.gpu-bin/reflections-gpu > /dev/null 2>&1
echo "SM clock after the warm-up run: $(clock)" > "$OUT/reflections.txt"
.gpu-bin/reflections-gpu --bench --out "$OUT" >> "$OUT/reflections.txt" 2>&1 || echo "reflections-gpu failed" >> "$OUT/reflections.txt"
echo "SM clock before: $(clock)" > "$OUT/hybrid.txt"
.gpu-bin/hybrid-gpu --bench --out "$OUT" >> "$OUT/hybrid.txt" 2>&1 || echo "hybrid-gpu failed" >> "$OUT/hybrid.txt"
kill $sampler
tail -8 "$OUT/reflections.txt"; tail -12 "$OUT/hybrid.txt"
tar czf "$RESULTS/results.tgz" -C /tmp/res .
