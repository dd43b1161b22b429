# Adds indirect-gpu (this commit: the workgroup-memory discontinuity buffer + blur) and
# indirect-gpu-1e1fc9b (three dispatches: DB, horizontal and vertical blur) to
# .gpu-bin/bins.tar.xz, for the same-run comparison docs/interleaved-sampling.md asks for. Run
# from the repository root, committed. On the device, beside the other specs of call.sh:
#   "ind-old:60:indirect-gpu-1e1fc9b --quick" "ind:60:indirect-gpu --quick"
#   "ind-1080:90:indirect-gpu --quick --vpls 256,1024"
# (--quick: 1024×768, 256 VPLs, 4×4 in both builds; the old build has no --vpls.)
set -euo pipefail
source docs/bench/executables.sh
bins=$(mktemp -d) old=$(mktemp -d)
tar xJf .gpu-bin/bins.tar.xz -C "$bins"
cargo bench -p deferred-pipeline --bench indirect-gpu --no-run --message-format=json 2>/dev/null \
  | executables | while read -r name exe; do cp "$exe" "$bins/$name"; done
git worktree add -q --detach "$old/tree" 1e1fc9b
(cd "$old/tree" && CARGO_TARGET_DIR=$old/target cargo bench -p deferred-pipeline \
  --bench indirect-gpu --no-run --message-format=json 2>/dev/null) \
  | executables | while read -r name exe; do cp "$exe" "$bins/$name-1e1fc9b"; done
git worktree remove --force "$old/tree" && rm -rf "$old"
strip "$bins"/indirect-gpu*
tar cJf .gpu-bin/bins.tar.xz -C "$bins" . && rm -r "$bins"
echo "indirect-gpu: $(git rev-parse HEAD); indirect-gpu-1e1fc9b" >> .gpu-bin/built-from
tar tJf .gpu-bin/bins.tar.xz; du -sh .gpu-bin
