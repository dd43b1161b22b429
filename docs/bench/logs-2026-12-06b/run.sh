# Issue 28, stop 53: benchmarks on the H200 in one call of at most 540 s. Each argument is
# LABEL:SECONDS:PROGRAM [ARGS...] — PROGRAM one of the executables packed in .gpu-bin/bins.tar.xz
# (docs/bench/logs-2026-12-06/prep.sh, plus indirect-gpu-fused: this stop's one-dispatch
# DB + blur), run with --bench for at most SECONDS (less if the call's time runs out), its
# report under $OUT/reports/LABEL, its output in $OUT/LABEL.txt, the SM clock sampled every
# 200 ms into $OUT/clock.log. Results go straight under $OUT, so they come back if cut short.
source docs/bench/device-env.sh
export SUBDIV_BFT_DIR=$PWD/.gpu-data/bft
tar xJf .gpu-bin/bins.tar.xz -C .gpu-bin && chmod +x .gpu-bin/*
nvidia-smi --query-gpu=clocks.sm --format=csv,noheader,nounits -lms 200 > "$OUT/clock.log" &
sampler=$!
end=$(( $(date +%s) + 540 ))
for spec in "$@"; do
  label=${spec%%:*}; rest=${spec#*:}; limit=${rest%%:*}; cmd=${rest#*:}
  left=$(( end - $(date +%s) )); [ $left -lt $limit ] && limit=$left
  [ $limit -lt 20 ] && { echo "== $label not run: no time left" >> "$OUT/run.txt"; continue; }
  echo "== $label: $cmd (at most $limit s), SM clock $(clock)" >> "$OUT/run.txt"
  start=$(date +%s)
  timeout $limit .gpu-bin/$cmd --bench --out "$OUT/reports/$label" > "$OUT/$label.txt" 2>&1 \
    || echo "   failed or ran past $limit s" >> "$OUT/run.txt"
  echo "   took $(( $(date +%s) - start )) s" >> "$OUT/run.txt"
done
echo "SM clock after: $(clock)" >> "$OUT/run.txt"
kill $sampler
cat "$OUT/run.txt"
