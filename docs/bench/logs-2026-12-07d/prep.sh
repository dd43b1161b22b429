# Prepares the device call of the sixth session of 2026-12-07: the chunked adaptive main step
# (f043643) at three chunk sizes beside b1e174e (one workgroup per patch) and f013d2d, and the
# adaptive-SSAA bench with the tiled resolve (0350e63), in one call. Run after ../logs-2026-12-07c/prep.sh (its bins: subdiv-gpu of b1e174e,
# subdiv-gpu-f013d2d; its tests), from the repository root at f043643 or later, committed.
# Adds subdiv-gpu-c64 / -c128 / -c256 (ADAPTIVE_CHUNK = (64, 128), (128, 256), (256, 512)),
# ssaa-gpu and the two crates' adaptive test binaries. On the device (carry .gl .gpu-bin
# .gpu-data):
#   bash docs/bench/logs-2026-12-06b/run.sh "c128:60:subdiv-gpu-c128" "c64:60:subdiv-gpu-c64" \
#     "ssaa:90:ssaa-gpu --quick" "b1e174e:60:subdiv-gpu" "f013d2d:55:subdiv-gpu-f013d2d" \
#     "c256:60:subdiv-gpu-c256"
# then, with docs/bench/device-env.sh sourced, SUBDIV_BFT_DIR=$PWD/.gpu-data/bft and CI=1, each
# test binary of .gpu-bin/tests.tar.xz (gbuffer-gpu_vs_cpu with --ignored one_dispatch).
set -euo pipefail
source docs/bench/executables.sh
git diff --quiet HEAD -- crates/subdiv-bft || { echo "commit crates/subdiv-bft first"; exit 1; }
bins=$(mktemp -d) tests=$(mktemp -d)
tar xJf .gpu-bin/bins.tar.xz -C "$bins" && tar xJf .gpu-bin/tests.tar.xz -C "$tests"
mod=crates/subdiv-bft/src/gpu/mod.rs
for chunk in "64, 128" "128, 256" "256, 512"; do
  sed -i "s/^const ADAPTIVE_CHUNK: (u32, u32) = (.*);/const ADAPTIVE_CHUNK: (u32, u32) = ($chunk);/" $mod
  grep -q "($chunk);" $mod
  cargo bench -p deferred-subdiv-bft --bench subdiv-gpu --no-run --message-format=json 2>/dev/null \
    | executables | while read -r name exe; do cp "$exe" "$bins/$name-c${chunk%%,*}"; done
done
git checkout -- $mod
cargo bench -p deferred-adaptive-ssaa --bench ssaa-gpu --no-run --message-format=json 2>/dev/null \
  | executables | while read -r name exe; do cp "$exe" "$bins/$name"; done
cargo test --release -p deferred-adaptive-ssaa --test adaptive --no-run --message-format=json \
  2>/dev/null | executables | while read -r name exe; do cp "$exe" "$tests/ssaa-adaptive-test"; done
cargo test --release -p deferred-subdiv-bft --test adaptive --no-run --message-format=json 2>/dev/null \
  | executables | while read -r name exe; do cp "$exe" "$tests/subdiv-adaptive-test"; done
rm -f "$bins"/bft-c*
strip "$bins"/* "$tests"/*
tar cJf .gpu-bin/bins.tar.xz -C "$bins" . && tar cJf .gpu-bin/tests.tar.xz -C "$tests" .
rm -r "$bins" "$tests"
git rev-parse HEAD >> .gpu-bin/built-from
tar tJf .gpu-bin/bins.tar.xz; tar tJf .gpu-bin/tests.tar.xz; du -sh .gpu-bin .gpu-data
