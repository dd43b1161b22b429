# Issue 28, first device call: the split/gather kernels with four tiled-variant tile sizes
# (interleave-gpu-t<texels>[w], built from main with TILE_TEXELS and the aimed tile patched:
# t512 = 32×16 pixels (main), t1024 = 32×32, t1024w = 64×16, t2048 = 64×32), then the indirect
# passes of c17307c (indirect-gpu) and with the cheaper BRDF, the VPL skip and the paired blur
# (indirect-gpu-new), one after the other. `bash docs/bench/logs-2026-12-06/run1.sh` with those executables in .gpu-bin and
# Sponza under .gpu-data/fixtures; results in $OUT/results.tgz.
RESULTS=$OUT; OUT=/tmp/res; mkdir -p $OUT
source docs/bench/device-env.sh
tar xJf .gpu-bin/bins.tar.xz -C .gpu-bin && chmod +x .gpu-bin/*
nvidia-smi --query-gpu=clocks.sm --format=csv,noheader,nounits -lms 200 > "$OUT/clock.log" &
sampler=$!
for v in t512 t1024 t1024w t2048; do
  mkdir -p "$OUT/$v"
  echo "== $v, SM clock $(clock)" >> "$OUT/run.txt"
  timeout 60 .gpu-bin/interleave-gpu-$v --bench --out "$OUT/$v" > "$OUT/$v/log.txt" 2>&1 || echo "$v failed or ran past 60 s" >> "$OUT/run.txt"
  grep -E "3840x2160 (4x4|8x8|8x6|2x2) (tiled|one-pass)|copy 3840|re-measured" "$OUT/$v/log.txt" >> "$OUT/run.txt"
done
for v in indirect-gpu indirect-gpu-new; do
  mkdir -p "$OUT/$v"
  echo "== $v, SM clock $(clock)" >> "$OUT/run.txt"
  timeout 145 .gpu-bin/$v --bench --out "$OUT/$v" > "$OUT/$v/log.txt" 2>&1 || echo "$v failed or ran past 145 s" >> "$OUT/run.txt"
  grep -E "1920x1080  1024 VPLs 4x4|re-measured" "$OUT/$v/log.txt" >> "$OUT/run.txt"
done
echo "SM clock after: $(clock)" >> "$OUT/run.txt"
kill $sampler
cat "$OUT/run.txt"
tar czf "$RESULTS/results.tgz" -C /tmp/res .
