# Prepares a checkout for the single device call of issue 28's reports of record (next stop):
# the Vulkan loader (.gl), the five benchmark executables of HEAD stripped and packed in
# .gpu-bin/bins.tar.xz, the fixtures and the level-5 basis-function tables under .gpu-data.
# `bash docs/bench/logs-2026-12-06b/prep.sh`, then on the device (carry .gl .gpu-bin .gpu-data):
#   bash docs/bench/logs-2026-12-06b/run.sh "indirect:40:indirect-gpu --vpls 256,1024" \
#     "interleave:100:interleave-gpu" "subdiv:50:subdiv-gpu" "manylod:160:manylod-gpu" \
#     "ssaa:120:ssaa-gpu --quick" "visibility:120:visibility-gpu"
# (about 450 s of the 540; the call returns $OUT/results.tar with every report and log;
# visibility-gpu is issue 29's first measurement).
set -euo pipefail
bash ../shared/tools/device-prep.sh > /dev/null
bins=$(mktemp -d)
cargo bench -p deferred-pipeline --bench indirect-gpu --bench manylod-gpu --bench visibility-gpu \
  -p deferred-interleave --bench interleave-gpu -p deferred-subdiv-bft --bench subdiv-gpu \
  -p deferred-adaptive-ssaa --bench ssaa-gpu --no-run --message-format=json 2>/dev/null \
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
cargo xtask bft --level 5 -o .gpu-data/bft/loop-l5-v18.bft
du -sh .gpu-bin .gpu-data
