# Transparency frames (the material gallery's blended sphere dithered, or drawn forward over
# tiled deferred shading, or by Forward+; the light pre-pass beside them) on the device:
# `bash docs/bench/logs-2026-12-04/transparency.sh` with .gpu-bin/tiled-gpu (stripped
# `cargo bench -p deferred-pipeline --bench tiled-gpu --no-run` executable). A short discarded
# run first raises the SM clock; results packed into $OUT/results.tgz.
RESULTS=$OUT; OUT=/tmp/res; mkdir -p $OUT
source docs/bench/device-env.sh
chmod +x .gpu-bin/*
.gpu-bin/tiled-gpu --bench --transparency --frames 2 --out /tmp/warm > /dev/null 2>&1
echo "SM clock after the warm-up run: $(clock)" > "$OUT/transparency.txt"
.gpu-bin/tiled-gpu --bench --transparency --out "$OUT" >> "$OUT/transparency.txt" 2>&1 || echo "tiled-gpu failed" >> "$OUT/transparency.txt"
echo "SM clock after: $(clock)" >> "$OUT/transparency.txt"
cat "$OUT/transparency.txt"
tar czf "$RESULTS/results.tgz" -C /tmp/res .
