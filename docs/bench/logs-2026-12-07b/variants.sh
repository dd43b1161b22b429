# Controlled variants of visibility-gpu for issue 29 (where the resolve's materials stage spends
# its time), built after ../logs-2026-12-07/prep.sh and added to .gpu-bin/bins.tar.xz:
#   visibility-gpu-notex  every texture read as white (`read_slot` samples nothing): the
#                         materials stage without texture sampling (the hardware rows change too)
#   visibility-gpu-one    every covered tile resolved by one dispatch with the first material's
#                         textures (no per-material dispatches): what one dispatch over all
#                         materials would cost (the picture is wrong; agreement drops)
# Neither is a candidate: they bound the cost of texture sampling and of one dispatch per
# material. Usage: PACK="…" bash ../logs-2026-12-07/prep.sh && bash variants.sh
set -euo pipefail
build() {
  cargo bench -p deferred-pipeline --bench visibility-gpu --no-run --message-format=json 2>/dev/null \
    | python3 -c "import sys, json
for l in sys.stdin:
    d = json.loads(l)
    if d.get('reason') == 'compiler-artifact' and d.get('executable'):
        print(d['executable'])"
}
bins=$(mktemp -d)
tar xJf .gpu-bin/bins.tar.xz -C "$bins"
restore() { git checkout -q shaders/gbuffer crates/gbuffer/src/gpu/visibility.rs; }
trap restore EXIT
sed -i 's/if slot.offset.w == 0.0 {/if true {/' shaders/gbuffer/material.wgsl
grep -q 'if true {' shaders/gbuffer/material.wgsl
cp "$(build)" "$bins/visibility-gpu-notex" && strip "$bins/visibility-gpu-notex"
restore
sed -i 's/return meshes\[mesh_of(id)\].slot;/return 0u;/; s/if mesh.slot != resolve.slot {/if false {/' shaders/gbuffer/resolve.wgsl
grep -q 'return 0u;' shaders/gbuffer/resolve.wgsl && grep -q 'if false {' shaders/gbuffer/resolve.wgsl
sed -i 's/for (slot, &m) in visibility.materials.iter().enumerate() {/for (slot, \&m) in visibility.materials.iter().enumerate().take(1) {/' crates/gbuffer/src/gpu/visibility.rs
grep -q 'enumerate().take(1)' crates/gbuffer/src/gpu/visibility.rs
cp "$(build)" "$bins/visibility-gpu-one" && strip "$bins/visibility-gpu-one"
restore
tar cJf .gpu-bin/bins.tar.xz -C "$bins" . && rm -r "$bins"
tar tJf .gpu-bin/bins.tar.xz; du -sh .gpu-bin .gpu-data
