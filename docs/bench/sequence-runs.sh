# Sourced by the sequence scripts under docs/bench/logs-*: everything is written under /tmp/res
# and packed into $OUT/results.tgz by `pack` (at most 8 files come back from the device);
# `run NAME ARGS…` renders `deferred ARGS…` as a 1920x1080 sequence of 120 frames after 120
# warm-up frames, the SM clock sampled every 50 ms meanwhile (clock-NAME.log), and keeps its
# output (NAME.txt) and timings (NAME.csv).
RESULTS=$OUT; OUT=/tmp/res; mkdir -p $OUT
source docs/bench/device-env.sh
chmod +x .gpu-bin/deferred
run() {
  name=$1; shift
  nvidia-smi --query-gpu=clocks.sm --format=csv,noheader,nounits -lms 50 > "$OUT/clock-$name.log" &
  sampler=$!
  .gpu-bin/deferred "$@" --size 1920x1080 --frames 120 --warm-up 120 --frame-every 60 \
    --out /tmp/$name > "$OUT/$name.txt" 2>&1 || echo "$name failed" >> "$OUT/$name.txt"
  kill $sampler
  cp /tmp/$name/timings.csv "$OUT/$name.csv" || true
}
pack() { tar czf "$RESULTS/results.tgz" -C /tmp/res .; }
