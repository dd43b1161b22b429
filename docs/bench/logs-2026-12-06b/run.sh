# Issue 28: benchmarks on the H200 in one call of at most 540 s. Each argument is
# LABEL:SECONDS:PROGRAM [ARGS...] — PROGRAM one of the executables packed in .gpu-bin/bins.tar.xz
# by prep.sh beside this script (the calls of 2026-12-06 carried those of
# ../logs-2026-12-06/prep.sh and indirect-gpu-fused, the first one-dispatch DB + blur), run with
# --bench for at most SECONDS (less if the call's time runs out): its report under
# reports/LABEL, its output in LABEL.txt, the SM clock sampled every 200 ms into clock.log, all
# packed into $OUT/results.tar after each program (a call returns only a few files, and what is
# packed comes back if the call is cut short).
source docs/bench/device-env.sh
export SUBDIV_BFT_DIR=$PWD/.gpu-data/bft
tar xJf .gpu-bin/bins.tar.xz -C .gpu-bin && chmod +x .gpu-bin/*
work=$(mktemp -d)
nvidia-smi --query-gpu=clocks.sm --format=csv,noheader,nounits -lms 200 > "$work/clock.log" &
sampler=$!
end=$(( $(date +%s) + 540 ))
for spec in "$@"; do
  label=${spec%%:*}; rest=${spec#*:}; limit=${rest%%:*}; cmd=${rest#*:}
  left=$(( end - $(date +%s) )); [ $left -lt $limit ] && limit=$left
  [ $limit -lt 20 ] && { echo "== $label not run: no time left" >> "$work/run.txt"; continue; }
  echo "== $label: $cmd (at most $limit s), SM clock $(clock)" >> "$work/run.txt"
  start=$(date +%s)
  timeout $limit .gpu-bin/$cmd --bench --out "$work/reports/$label" > "$work/$label.txt" 2>&1 \
    || echo "   failed or ran past $limit s" >> "$work/run.txt"
  echo "   took $(( $(date +%s) - start )) s" >> "$work/run.txt"
  tar cf "$OUT/results.tar" -C "$work" .
done
echo "SM clock after: $(clock)" >> "$work/run.txt"
kill $sampler
tar cf "$OUT/results.tar" -C "$work" .
cat "$work/run.txt"
