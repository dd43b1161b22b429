# Prepares the device call of 2026-12-07 (fourth session): after
#   PACK="visibility-gpu visibility-gpu-21dad3f peers-gpu" bash docs/bench/logs-2026-12-07/prep.sh
# (the Vulkan loader, fixtures, level-5 tables, and those programs) this replaces visibility-gpu
# by HEAD's (the one-dispatch resolve timed beside the classified one) and adds the gbuffer
# test program `gpu_vs_cpu` (its one-dispatch tests need binding arrays, which llvmpipe lacks:
# run on the device with `--ignored one_dispatch`). Call 4 carried the pipeline's `visibility`
# and `subdivision` test programs too (`cargo test --release -p deferred-pipeline --test
# visibility --test subdivision --no-run`, stripped, packed as .gpu-bin/tests.tar.xz).
set -euo pipefail
source docs/bench/executables.sh
bins=$(mktemp -d)
tar xJf .gpu-bin/bins.tar.xz -C "$bins"
cargo bench -p deferred-pipeline --bench visibility-gpu --no-run --message-format=json 2>/dev/null \
  | executables | while read -r name exe; do cp "$exe" "$bins/$name"; strip "$bins/$name"; done
cargo test --release -p deferred-gbuffer --test gpu_vs_cpu --no-run --message-format=json 2>/dev/null \
  | executables | while read -r name exe; do cp "$exe" "$bins/$name"; strip "$bins/$name"; done
tar cJf .gpu-bin/bins.tar.xz -C "$bins" . && rm -r "$bins"
git rev-parse HEAD > .gpu-bin/built-from
tar tJf .gpu-bin/bins.tar.xz; du -sh .gpu-bin .gpu-data
