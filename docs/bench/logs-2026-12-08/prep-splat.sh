# Adds manylod-gpu-loadmin to .gpu-bin/bins.tar.xz: the manylod bench with splat.wgsl testing
# the atlas word before its atomic-min (an atomicLoad, and atomicMin only where the disc is
# nearer) — the same atlas, fewer L2 atomics: does the splat wait on them? Run from the
# repository root, committed.
set -euo pipefail
source docs/bench/executables.sh
git diff --quiet HEAD -- shaders/manylod || { echo "commit shaders/manylod first"; exit 1; }
bins=$(mktemp -d)
tar xJf .gpu-bin/bins.tar.xz -C "$bins"
python3 - <<'PY'
p = 'shaders/manylod/splat.wgsl'
s = open(p).read()
old = "            if i >= 0 {\n                atomicMin(&atlas[i], d.word);"
assert old in s
s = s.replace(old, "            if i >= 0 && d.word < atomicLoad(&atlas[i]) {\n                atomicMin(&atlas[i], d.word);")
open(p, 'w').write(s)
PY
cargo bench -p deferred-pipeline --bench manylod-gpu --no-run --message-format=json 2>/dev/null \
  | executables | while read -r name exe; do cp "$exe" "$bins/$name-loadmin"; done
git checkout -- shaders/manylod/splat.wgsl
strip "$bins"/manylod-gpu-loadmin
tar cJf .gpu-bin/bins.tar.xz -C "$bins" . && rm -r "$bins"
echo "manylod-gpu-loadmin: $(git rev-parse HEAD) + atomicLoad before atomicMin" >> .gpu-bin/built-from
tar tJf .gpu-bin/bins.tar.xz
