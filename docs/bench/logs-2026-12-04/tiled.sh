# The light accumulation with traditional deferred shading (light volumes), Forward+ and the light pre-pass beside brute force,
# tiled, tiled + cones and clustered, on the device: `bash docs/bench/logs-2026-12-04/tiled.sh`
# with .gpu-bin/tiled-gpu (stripped `cargo bench -p deferred-pipeline --bench tiled-gpu
# --no-run` executable) and Sponza under .gpu-data/fixtures. A short discarded run first
# raises the SM clock; results packed into $OUT/results.tgz.
RESULTS=$OUT; OUT=/tmp/res; mkdir -p $OUT
source docs/bench/device-env.sh
chmod +x .gpu-bin/*
nvidia-smi --query-gpu=clocks.sm --format=csv,noheader,nounits -lms 100 > "$OUT/clock.log" &
sampler=$!
.gpu-bin/tiled-gpu --bench --quick > /dev/null 2>&1
echo "SM clock after the warm-up run: $(clock)" > "$OUT/tiled.txt"
timeout 520 .gpu-bin/tiled-gpu --bench --out "$OUT" >> "$OUT/tiled.txt" 2>&1 || echo "tiled-gpu failed or ran past 520 s" >> "$OUT/tiled.txt"
echo "SM clock after: $(clock)" >> "$OUT/tiled.txt"
kill $sampler
tail -40 "$OUT/tiled.txt"
tar czf "$RESULTS/results.tgz" -C /tmp/res .
