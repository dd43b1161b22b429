// The visibility buffer's words and the merge of one covered pixel, shared by the compute
// rasteriser (`visibility.wgsl`) and the hardware rasteriser's draw (`visibility_hardware.wgsl`).
//
// Per pixel 64 bits, (depth bits << 32) | id: the id in the low word, z/w's bits (a
// non-negative float, ordered as its bits) in the high one. Two ways to merge, chosen by
// specialising the three declarations below (`gbuffer::gpu::visibility::Atomics`):
// - wide: one 64-bit `atomicMin` of the packed word (SHADER_INT64_ATOMIC_MIN_MAX);
// - narrow (devices without 64-bit atomics): two passes over the same coverage with 32-bit
//   atomics on the two words — the depth pass takes the smallest depth, then the id pass the
//   smallest id among the fragments at exactly that depth. The same result, bit for bit (no
//   precision is given up), at twice the coverage work.
// A branch's conversions through `VisibilityValue` type-check in both variants; the other
// variant's branch is dead (a constant condition). The narrow variant has no 64-bit type at
// all: it runs on devices without 64-bit integers.

alias VisibilityWord = atomic<u64>;
alias VisibilityValue = u64;
const WIDE_ATOMICS: bool = true;
// Where the depth goes in a packed word (0 in the narrow variant, whose branch is dead).
const DEPTH_SHIFT: u32 = 32u;
// The narrow merge's second pass (ids at the depths the first one left).
const ID_PASS: bool = false;

@group(0) @binding(4) var<storage, read_write> visibility: array<VisibilityWord>;

fn merge(pixel: u32, z: f32, id: u32) {
    let depth = bitcast<u32>(z);
    if WIDE_ATOMICS {
        atomicMin(&visibility[pixel], (VisibilityValue(depth) << DEPTH_SHIFT) | VisibilityValue(id));
    } else if !ID_PASS {
        atomicMin(&visibility[2u * pixel + 1u], VisibilityValue(depth));
    } else if atomicLoad(&visibility[2u * pixel + 1u]) == VisibilityValue(depth) {
        atomicMin(&visibility[2u * pixel], VisibilityValue(id));
    }
}

// Word i to "nothing" (the largest depth and id).
fn clear_word(i: u32) {
    atomicStore(&visibility[i], ~VisibilityValue(0u));
}
