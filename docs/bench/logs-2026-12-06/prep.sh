# Prepares a fresh checkout for run2.sh / run3.sh: the Vulkan loader (.gl), the benchmark
# executables of HEAD plus the two one-pass workgroup-shape variants, stripped and packed in
# .gpu-bin/bins.tar.xz, and the fixtures and level-5 basis-function tables under .gpu-data
# (about 55 MB with the repository; the device call carries at most 64 MiB).
# `bash docs/bench/logs-2026-12-06/prep.sh` from the repository root.
set -euo pipefail
bash ../shared/tools/device-prep.sh > /dev/null
bins=$(mktemp -d)
built() { # cargo bench --no-run arguments → "name path" per executable
  cargo bench "$@" --no-run --message-format=json 2>/dev/null | python3 -c "import sys, json
for l in sys.stdin:
    d = json.loads(l)
    if d.get('reason') == 'compiler-artifact' and d.get('executable'):
        print(d['target']['name'], d['executable'])"
}
built -p deferred-pipeline --bench indirect-gpu --bench manylod-gpu \
  -p deferred-interleave --bench interleave-gpu -p deferred-subdiv-bft --bench subdiv-gpu \
  -p deferred-adaptive-ssaa --bench ssaa-gpu | while read -r name exe; do
  [ "$name" = bft ] || { cp "$exe" "$bins/$name"; strip "$bins/$name"; }
done
for shape in 32x8 64x4; do
  wx=${shape%x*}; wy=${shape#*x}
  sed -i "s/@workgroup_size(16, 16)/@workgroup_size($wx, $wy)/g" shaders/interleave/one_pass.wgsl
  python3 - "$wx" "$wy" <<'PY'
import sys
p = 'crates/interleave/src/gpu/split.rs'
s = open(p).read()
old = '''            (_, _, [(name, p)]) => pass(
                device,
                name,
                p,
                &[res(&from_view), res(&to_view)],
                groups(to_size, 16),
            ),'''
assert old in s
new = old.replace('groups(to_size, 16)', f'(to_size.0.div_ceil({sys.argv[1]}), to_size.1.div_ceil({sys.argv[2]}))')
open(p, 'w').write(s.replace(old, new))
PY
  built -p deferred-interleave --bench interleave-gpu | while read -r name exe; do
    cp "$exe" "$bins/interleave-gpu-g$shape"; strip "$bins/interleave-gpu-g$shape"
  done
  git checkout -- shaders/interleave/one_pass.wgsl crates/interleave/src/gpu/split.rs
done
mkdir -p .gpu-bin && rm -f .gpu-bin/* && tar cJf .gpu-bin/bins.tar.xz -C "$bins" . && rm -r "$bins"
rm -rf .gpu-data && mkdir -p .gpu-data/fixtures/gltf .gpu-data/bft
cp -r ../shared/fixtures/{sponza,subdiv,stanford} .gpu-data/fixtures/
cp -r ../shared/fixtures/gltf/DamagedHelmet .gpu-data/fixtures/gltf/
cargo xtask bft --level 5 -o .gpu-data/bft/loop-l5-v18.bft
du -sh .gpu-bin .gpu-data
