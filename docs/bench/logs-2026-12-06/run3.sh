# Issue 28, a focused call for what the device budget left allows (110 s): the indirect passes at
# 1920×1080 with 256 and 1024 VPLs (`indirect-gpu --vpls 256,1024`: the per-pass table of this
# commit's stage), then split/gather with the one-pass kernels' 16×16 workgroups (main) and
# 32×8 / 64×4 ones (interleave-gpu-g32x8/-g64x4: one_pass.wgsl's workgroup size and its
# dispatch patched). `bash docs/bench/logs-2026-12-06/run3.sh` with the executables packed in
# .gpu-bin/bins.tar.xz and Sponza under .gpu-data (prep.sh); results straight under $OUT.
source docs/bench/device-env.sh
tar xJf .gpu-bin/bins.tar.xz -C .gpu-bin && chmod +x .gpu-bin/*
nvidia-smi --query-gpu=clocks.sm --format=csv,noheader,nounits -lms 200 > "$OUT/clock.log" &
sampler=$!
end=$(( $(date +%s) + 110 ))
for spec in "indirect-gpu --vpls 256,1024:100" interleave-gpu:70 interleave-gpu-g32x8:55 interleave-gpu-g64x4:55; do
  cmd=${spec%:*}; limit=${spec#*:}; b=${cmd%% *}
  left=$(( end - $(date +%s) )); [ $left -lt $limit ] && limit=$left
  [ $limit -lt 20 ] && { echo "== $b not run: no time left" >> "$OUT/run.txt"; continue; }
  echo "== $cmd (at most $limit s), SM clock $(clock)" >> "$OUT/run.txt"
  start=$(date +%s)
  timeout $limit .gpu-bin/$cmd --bench --out "$OUT/reports/$b" > "$OUT/$b.txt" 2>&1 || echo "$b failed or ran past $limit s" >> "$OUT/run.txt"
  echo "   took $(( $(date +%s) - start )) s" >> "$OUT/run.txt"
  grep -E "^1920x1080 +1024 VPLs 4x4|^3840x2160 (4x4|8x8) (tiled|one-pass)|^copy 3840|re-measured" "$OUT/$b.txt" >> "$OUT/run.txt"
done
echo "SM clock after: $(clock)" >> "$OUT/run.txt"
kill $sampler
cat "$OUT/run.txt"
