// How a workgroup finds the lights that meet its tile or cluster, shared by `tiled.wgsl` and
// `clustered.wgsl`. With LIGHT_TREE (`LightSearch::Tree`, after Olsson et al. 2012's light
// BVH) through the light hierarchy — the lights in Morton order in groups of GROUP under
// bounding spheres (`tiled_shading::LightGroups`): in each round ROUND groups are tested, one
// per invocation, and the lights of the groups that pass become the round's candidates.
// Without it (`LightSearch::Flat`, the thesis) one round whose candidates are all lights. The
// importer's loop:
//   for r in 0..search_rounds():
//     candidates = params.light_count
//     if LIGHT_TREE: g = begin_round(r, index); if g != NO_LIGHT && meets(group_sphere(g)):
//                    pass_group(g); candidates = end_round(index)
//     then candidate_light(i) for i in 0..candidates (NO_LIGHT past the last).
// #import tiled-shading/pixels.wgsl

const LIGHT_TREE: bool = true;
const GROUP: u32 = 32u;
// Groups tested per round: the workgroup's invocation count (at least that many invocations).
const ROUND: u32 = 64u;
const NO_LIGHT: u32 = 0xffffffffu;

// `LightGroups::words`: each group's bounding sphere (centre, radius as float bits), then the
// light indices in Morton order, four per entry.
@group(0) @binding(11) var<storage, read> light_tree: array<vec4<u32>>;

// The groups of the current round that passed.
var<workgroup> passed_count: atomic<u32>;
var<workgroup> passed_size: u32;
var<workgroup> passed_groups: array<u32, ROUND>;

fn search_rounds() -> u32 {
    if LIGHT_TREE {
        return (params.group_count + ROUND - 1u) / ROUND;
    }
    return 1u;
}

// Starts round `r`: the group invocation `index` tests, or NO_LIGHT.
fn begin_round(r: u32, index: u32) -> u32 {
    if index == 0u {
        atomicStore(&passed_count, 0u);
    }
    workgroupBarrier();
    let g = r * ROUND + index;
    return select(NO_LIGHT, g, index < ROUND && g < params.group_count);
}

fn group_sphere(g: u32) -> vec4<f32> {
    return bitcast<vec4<f32>>(light_tree[g]);
}

fn pass_group(g: u32) {
    passed_groups[atomicAdd(&passed_count, 1u)] = g;
}

// Ends the round's group tests: the number of candidates (workgroup-uniform).
fn end_round(index: u32) -> u32 {
    workgroupBarrier();
    if index == 0u {
        passed_size = atomicLoad(&passed_count);
    }
    return workgroupUniformLoad(&passed_size) * GROUP;
}

// The light of candidate `i` of this round, or NO_LIGHT.
fn candidate_light(i: u32) -> u32 {
    if !LIGHT_TREE {
        return select(NO_LIGHT, i, i < params.light_count);
    }
    let k = passed_groups[min(i / GROUP, ROUND - 1u)] * GROUP + i % GROUP;
    let valid = i / GROUP < passed_size && k < params.light_count;
    let o = min(k, params.light_count - 1u);
    return select(NO_LIGHT, light_tree[params.group_count + o / 4u][o % 4u], valid);
}
