# Prepares a checkout for the device calls of 2026-12-07 (issues 28, 29, 30): the Vulkan loader
# (.gl), the benchmark executables of HEAD stripped and packed in .gpu-bin/bins.tar.xz (those of
# ../logs-2026-12-06b/prep.sh plus peers-gpu), the fixtures (CesiumMan added) and the level-5
# basis-function tables under .gpu-data. Then on the device (carry .gl .gpu-bin .gpu-data):
#   bash docs/bench/logs-2026-12-06b/run.sh "LABEL:SECONDS:PROGRAM ARGS" ...
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
mkdir -p .gpu-bin && rm -f .gpu-bin/* && tar cJf .gpu-bin/bins.tar.xz -C "$bins" . && rm -r "$bins"
rm -rf .gpu-data && mkdir -p .gpu-data/fixtures/gltf .gpu-data/bft
cp -r ../shared/fixtures/{sponza,subdiv,stanford} .gpu-data/fixtures/
cp -r ../shared/fixtures/gltf/DamagedHelmet .gpu-data/fixtures/gltf/
mkdir -p .gpu-data/fixtures/animated && cp -r ../shared/fixtures/animated/CesiumMan .gpu-data/fixtures/animated/
cargo xtask bft --level 5 -o .gpu-data/bft/loop-l5-v18.bft
git rev-parse HEAD > .gpu-bin/built-from
du -sh .gpu-bin .gpu-data
