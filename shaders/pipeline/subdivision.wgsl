// Subdivision per frame (`pipeline::subdivision`): the control mesh's vertices, as the skinning
// left them in the scene's vertex buffers, gathered into M⁰ of `subdiv_bft`'s evaluation
// (`gather`: one render vertex per welded vertex), and the evaluated limit surface written
// back into the scene's vertex buffers where the refined mesh is drawn (`scatter`: positions
// and normals; texture coordinates were evaluated through the same stencils at set-up).

struct Params {
    // Vertices to gather (welded M⁰ vertices) or to scatter (refined vertices).
    count: u32,
    // The mesh's first vertex in the scene's buffers (control or refined).
    base: u32,
    _pad0: u32,
    _pad1: u32,
};

// Floats of one `gbuffer::gpu::GpuAttributes` and the offset of its normal.
const ATTRIBUTE_FLOATS: u32 = 15u;
const NORMAL_AT: u32 = 0u;
const WORKGROUP: u32 = 64u;

@group(0) @binding(0) var<uniform> params: Params;
// gather: the render vertex of each welded vertex; M⁰ (xyz, 1).
@group(0) @binding(1) var<storage, read> welded_from: array<u32>;
@group(0) @binding(2) var<storage, read_write> m0: array<vec4<f32>>;
// scatter: the evaluated positions (xyz, 1) and normals (xyz, 0).
@group(0) @binding(3) var<storage, read> fine_positions: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> fine_normals: array<vec4<f32>>;
// The scene's vertex buffers.
@group(0) @binding(5) var<storage, read_write> positions: array<f32>;
@group(0) @binding(6) var<storage, read_write> attributes: array<f32>;

fn index(gid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return gid.x + gid.y * groups.x * WORKGROUP;
}

@compute @workgroup_size(WORKGROUP)
fn gather(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = index(gid, groups);
    if i >= params.count {
        return;
    }
    let v = 3u * (params.base + welded_from[i]);
    m0[i] = vec4<f32>(positions[v], positions[v + 1u], positions[v + 2u], 1.0);
}

@compute @workgroup_size(WORKGROUP)
fn scatter(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = index(gid, groups);
    if i >= params.count {
        return;
    }
    let v = params.base + i;
    let p = fine_positions[i].xyz;
    positions[3u * v] = p.x;
    positions[3u * v + 1u] = p.y;
    positions[3u * v + 2u] = p.z;
    let n = fine_normals[i].xyz;
    let a = ATTRIBUTE_FLOATS * v;
    attributes[a + NORMAL_AT] = n.x;
    attributes[a + NORMAL_AT + 1u] = n.y;
    attributes[a + NORMAL_AT + 2u] = n.z;
}
