# Issue 28, the reports of record (H200): each benchmark named as NAME:SECONDS in the arguments
# (default: the indirect passes, split/gather, then the one-pass kernels with 32×8 and 64×4
# workgroups instead of 16×16 — interleave-gpu-g32x8/-g64x4, reports under variants/ — then
# Loop subdivision, ManyLoDs and adaptive SSAA), each for at most SECONDS and all of them in
# 540 s; executables, fixtures and tables prepared by prep.sh beside this script.
# `bash docs/bench/logs-2026-12-06/run2.sh [NAME:SECONDS ...]`; results straight under $OUT
# (they come back even if the call is cut short).
source docs/bench/device-env.sh
export SUBDIV_BFT_DIR=$PWD/.gpu-data/bft
tar xJf .gpu-bin/bins.tar.xz -C .gpu-bin && chmod +x .gpu-bin/*
nvidia-smi --query-gpu=clocks.sm --format=csv,noheader,nounits -lms 200 > "$OUT/clock.log" &
sampler=$!
end=$(( $(date +%s) + 540 ))
specs=("$@")
[ ${#specs[@]} -gt 0 ] || specs=(indirect-gpu:230 interleave-gpu:100 interleave-gpu-g32x8:70 interleave-gpu-g64x4:70 subdiv-gpu:120 manylod-gpu:200 ssaa-gpu:200)
for spec in "${specs[@]}"; do
  b=${spec%:*}; limit=${spec#*:}
  left=$(( end - $(date +%s) )); [ $left -lt $limit ] && limit=$left
  [ $limit -lt 20 ] && { echo "== $b not run: no time left" >> "$OUT/run.txt"; continue; }
  echo "== $b (at most $limit s), SM clock $(clock)" >> "$OUT/run.txt"
  start=$(date +%s)
  out="$OUT/reports"; case $b in *-gpu-g*) out="$OUT/variants/$b";; esac
  timeout $limit .gpu-bin/$b --bench --out "$out" > "$OUT/$b.txt" 2>&1 || echo "$b failed or ran past $limit s" >> "$OUT/run.txt"
  echo "   took $(( $(date +%s) - start )) s; $(grep -c . "$OUT/$b.txt") lines; $(grep -h 're-measured' "$OUT/$b.txt" | wc -l) re-measured" >> "$OUT/run.txt"
done
echo "SM clock after: $(clock)" >> "$OUT/run.txt"
kill $sampler
cat "$OUT/run.txt"; ls "$OUT/reports"
