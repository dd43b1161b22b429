# Prepares a checkout for the device calls of 2026-12-07 (issues 28, 29, 30): the Vulkan loader
# (.gl), the benchmark executables of HEAD stripped and packed in .gpu-bin/bins.tar.xz (those of
# ../logs-2026-12-06b/prep.sh plus peers-gpu), the fixtures (CesiumMan added) and the level-5
# basis-function tables under .gpu-data. Then on the device (carry .gl .gpu-bin .gpu-data):
#   ldconfig -p | grep -q libstdc++.so.6 || export LD_LIBRARY_PATH=$PWD/.gpu-bin/lib
#   bash docs/bench/logs-2026-12-06b/run.sh "visibility:170:visibility-gpu" \
#     "indirect:40:indirect-gpu --vpls 256,1024" "ssaa:100:ssaa-gpu --quick" \
#     "peers:100:peers-gpu --meshes spot,cesium-man,fandisk --levels 3,5 --cpu-runs 1 --python-level 0"
# Since call 3 also visibility-gpu-21dad3f (below); PACK="visibility-gpu visibility-gpu-21dad3f
# peers-gpu" packs only those. The first session of 2026-12-07 got no machine (every start failed). The second got an H100
# for five minutes after eight failed starts: call1/ (visibility, ssaa) and call2/ (peers — which
# stopped at fandisk level 5, see docs/peers.md —, indirect, then manylod and subdiv cut short
# by their time limits, stdout only).
set -euo pipefail
bash ../shared/tools/device-prep.sh > /dev/null
bins=$(mktemp -d)
cargo bench -p deferred-pipeline --bench indirect-gpu --bench manylod-gpu --bench visibility-gpu \
  -p deferred-interleave --bench interleave-gpu -p deferred-subdiv-bft --bench subdiv-gpu \
  -p deferred-adaptive-ssaa --bench ssaa-gpu -p deferred-peers --bench peers-gpu --no-run --message-format=json 2>/dev/null \
  | python3 -c "import sys, json
for l in sys.stdin:
    d = json.loads(l)
    if d.get('reason') == 'compiler-artifact' and d.get('executable'):
        print(d['target']['name'], d['executable'])" | while read -r name exe; do
  [ "$name" = bft ] || { cp "$exe" "$bins/$name"; strip "$bins/$name"; }
done
# The visibility bench once more with the rasteriser's shader of 21dad3f (setup_large with one
# invocation per deferred triangle), to measure 9ee63c3 against it in the same call.
git show 21dad3f:shaders/gbuffer/visibility.wgsl > shaders/gbuffer/visibility.wgsl
exe=$(cargo bench -p deferred-pipeline --bench visibility-gpu --no-run --message-format=json 2>/dev/null \
  | python3 -c "import sys, json
for l in sys.stdin:
    d = json.loads(l)
    if d.get('reason') == 'compiler-artifact' and d.get('executable'):
        print(d['executable'])")
git checkout -q shaders/gbuffer/visibility.wgsl
cp "$exe" "$bins/visibility-gpu-21dad3f" && strip "$bins/visibility-gpu-21dad3f"
# Only the programs named in $PACK (all by default): a call carries at most 64 MiB.
[ -z "${PACK:-}" ] || (cd "$bins" && for f in *; do [[ " $PACK " == *" $f "* ]] || rm "$f"; done)
mkdir -p .gpu-bin && rm -rf .gpu-bin/* && tar cJf .gpu-bin/bins.tar.xz -C "$bins" . && rm -r "$bins"
# peers-gpu links OpenSubdiv's C++ runtime; used on the device only where it has none.
mkdir -p .gpu-bin/lib && cp "$(g++ -print-file-name=libstdc++.so.6)" .gpu-bin/lib/
# The call carries at most 64 MiB with the working tree: no DamagedHelmet (ssaa-gpu --quick
# renders Sponza only) and the bunny alone of the Stanford models.
rm -rf .gpu-data && mkdir -p .gpu-data/fixtures/stanford .gpu-data/bft
cp -r ../shared/fixtures/{sponza,subdiv} .gpu-data/fixtures/
cp ../shared/fixtures/stanford/stanford-bunny.obj .gpu-data/fixtures/stanford/
mkdir -p .gpu-data/fixtures/animated && cp -r ../shared/fixtures/animated/CesiumMan .gpu-data/fixtures/animated/
cargo xtask bft --level 5 -o .gpu-data/bft/loop-l5-v18.bft
git rev-parse HEAD > .gpu-bin/built-from
du -sh .gpu-bin .gpu-data
