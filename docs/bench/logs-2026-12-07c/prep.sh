# Prepares the next device call for what the fifth session of 2026-12-07 left unmeasured: the
# landed main step of subdiv-bft (four patches per workgroup at levels 1–3) beside f013d2d's in
# one call, the crate's GPU tests on the GPU, and the gbuffer one-dispatch tests (the kernel
# now kept across rebinds). Run from the repository root; then on the device (carry .gl
# .gpu-bin .gpu-data):
#   bash docs/bench/logs-2026-12-06b/run.sh "subdiv-new:65:subdiv-gpu" "subdiv-old:55:subdiv-gpu-f013d2d"
#   mkdir -p .gpu-bin/t && tar xJf .gpu-bin/tests.tar.xz -C .gpu-bin/t
#   export SUBDIV_BFT_DIR=$PWD/.gpu-data/bft DEFERRED_FIXTURES=$PWD/.gpu-data/fixtures
#   cd .gpu-bin/t && ./subdiv-gpu-test > $OUT/subdiv-gpu-test.txt 2>&1
#   ./gbuffer-gpu_vs_cpu --ignored one_dispatch > $OUT/gbuffer-one-dispatch.txt 2>&1
set -euo pipefail
source docs/bench/executables.sh
# The Vulkan loader (.gl), the fixtures the programs read and the level-5 tables (.gpu-data).
bash ../shared/tools/device-prep.sh > /dev/null
rm -rf .gpu-data && mkdir -p .gpu-data/fixtures/stanford .gpu-data/bft
cp -r ../shared/fixtures/{sponza,subdiv} .gpu-data/fixtures/
cp ../shared/fixtures/stanford/stanford-bunny.obj .gpu-data/fixtures/stanford/
cargo xtask bft --level 5 -o .gpu-data/bft/loop-l5-v18.bft
mkdir -p .gpu-bin && rm -rf .gpu-bin/*
bins=$(mktemp -d) tests=$(mktemp -d) old=$(mktemp -d)
cargo bench -p deferred-subdiv-bft --bench subdiv-gpu --no-run --message-format=json 2>/dev/null \
  | executables | while read -r name exe; do cp "$exe" "$bins/$name"; done
git worktree add -q --detach "$old/tree" f013d2d
(cd "$old/tree" && CARGO_TARGET_DIR=$old/target cargo bench -p deferred-subdiv-bft \
  --bench subdiv-gpu --no-run --message-format=json 2>/dev/null) \
  | executables | while read -r name exe; do cp "$exe" "$bins/$name-f013d2d"; done
git worktree remove --force "$old/tree" && rm -rf "$old"
cargo test --release -p deferred-subdiv-bft --test gpu --no-run --message-format=json 2>/dev/null \
  | executables | while read -r name exe; do cp "$exe" "$tests/subdiv-gpu-test"; done
cargo test --release -p deferred-gbuffer --test gpu_vs_cpu --no-run --message-format=json 2>/dev/null \
  | executables | while read -r name exe; do cp "$exe" "$tests/gbuffer-$name"; done
rm -f "$bins/bft" "$bins/bft-f013d2d"
strip "$bins"/* "$tests"/*
tar cJf .gpu-bin/bins.tar.xz -C "$bins" . && tar cJf .gpu-bin/tests.tar.xz -C "$tests" .
rm -r "$bins" "$tests"
git rev-parse HEAD > .gpu-bin/built-from
tar tJf .gpu-bin/bins.tar.xz; tar tJf .gpu-bin/tests.tar.xz; du -sh .gpu-bin .gpu-data
