# Issue 28, the reports of record of 2026-12-06 (H200): the indirect passes and split/gather,
# then the one-pass kernels with 32×8 and 64×4 workgroups instead of 16×16
# (interleave-gpu-g32x8/-g64x4: this commit with one_pass.wgsl's workgroup size and its
# dispatch patched; reports under variants/), then Loop subdivision, ManyLoDs and adaptive
# SSAA with whatever time is left (330 s in all), each bench
# from one executable of this commit (`cargo xtask bench-bins`, stripped, packed in
# .gpu-bin/bins.tar.xz); fixtures and the level-5 basis-function tables under .gpu-data.
# `bash docs/bench/logs-2026-12-06/run2.sh`; results straight under $OUT (they come back even
# if the call is cut short).
source docs/bench/device-env.sh
export SUBDIV_BFT_DIR=$PWD/.gpu-data/bft
tar xJf .gpu-bin/bins.tar.xz -C .gpu-bin && chmod +x .gpu-bin/*
nvidia-smi --query-gpu=clocks.sm --format=csv,noheader,nounits -lms 200 > "$OUT/clock.log" &
sampler=$!
end=$(( $(date +%s) + 330 ))
for spec in indirect-gpu:200 interleave-gpu:90 interleave-gpu-g32x8:60 interleave-gpu-g64x4:60 subdiv-gpu:120 manylod-gpu:200 ssaa-gpu:200; do
  b=${spec%:*}; limit=${spec#*:}
  left=$(( end - $(date +%s) )); [ $left -lt $limit ] && limit=$left
  [ $limit -lt 20 ] && { echo "== $b not run: no time left" >> "$OUT/run.txt"; continue; }
  echo "== $b (at most $limit s), SM clock $(clock)" >> "$OUT/run.txt"
  start=$(date +%s)
  out="$OUT/reports"; case $b in *-g*) out="$OUT/variants/$b";; esac
  timeout $limit .gpu-bin/$b --bench --out "$out" > "$OUT/$b.txt" 2>&1 || echo "$b failed or ran past $limit s" >> "$OUT/run.txt"
  echo "   took $(( $(date +%s) - start )) s; $(grep -c . "$OUT/$b.txt") lines; $(grep -h 're-measured' "$OUT/$b.txt" | wc -l) re-measured" >> "$OUT/run.txt"
done
echo "SM clock after: $(clock)" >> "$OUT/run.txt"
kill $sampler
cat "$OUT/run.txt"; ls "$OUT/reports"
