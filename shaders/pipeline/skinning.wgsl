// Skinning and morphing (glTF 2.0 §3.7.3): each moved vertex from its rest attributes in object
// space — morph targets first (weights in target order), then the blend Σ wᵢ·Jᵢ of its joint
// matrices — written into the scene's vertex buffers, where the G-buffer and shadow passes read
// it. Twin of `scene::animation::Rig::deform`.

struct SkinVertex {
    position: vec3<f32>,
    // Destination vertex in the scene's buffers.
    vertex: u32,
    normal: vec3<f32>,
    // Index into `deformers`.
    deformer: u32,
    tangent: vec4<f32>,
    joints: vec4<u32>,
    weights: vec4<f32>,
};

struct Deformer {
    // Its first matrix in `joint_matrices`, and how many.
    first_joint: u32,
    joint_count: u32,
    // Its first displacement in `deltas` (three a vertex and target: position, normal,
    // tangent), and its morph-target count.
    first_delta: u32,
    targets: u32,
    // Its first weight in `morph_weights`.
    first_weight: u32,
    // Its first vertex in `vertices`.
    first_vertex: u32,
    // 1 when the mesh has tangents to move.
    tangents: u32,
    _pad: u32,
};

// Floats of one `gbuffer::gpu::GpuAttributes` and the offsets of its normal and tangent.
const ATTRIBUTE_FLOATS: u32 = 15u;
const NORMAL_AT: u32 = 0u;
const TANGENT_AT: u32 = 7u;
const WORKGROUP: u32 = 64u;

@group(0) @binding(0) var<storage, read> vertices: array<SkinVertex>;
@group(0) @binding(1) var<storage, read> deformers: array<Deformer>;
@group(0) @binding(2) var<storage, read> deltas: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> joint_matrices: array<mat4x4<f32>>;
@group(0) @binding(4) var<storage, read> morph_weights: array<f32>;
@group(0) @binding(5) var<storage, read_write> positions: array<f32>;
@group(0) @binding(6) var<storage, read_write> attributes: array<f32>;

fn safe_normalize(v: vec3<f32>, fallback: vec3<f32>) -> vec3<f32> {
    let l = length(v);
    if l > 0.0 && l < 3.0e38 {
        return v / l;
    }
    return fallback;
}

@compute @workgroup_size(WORKGROUP)
fn skin(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = gid.x + gid.y * groups.x * WORKGROUP;
    if i >= arrayLength(&vertices) {
        return;
    }
    let v = vertices[i];
    let d = deformers[v.deformer];
    // Morph targets (object space).
    var p = v.position;
    var n = v.normal;
    var t = v.tangent;
    let local = i - d.first_vertex;
    for (var k = 0u; k < d.targets; k++) {
        let w = morph_weights[d.first_weight + k];
        let at = d.first_delta + 3u * (local * d.targets + k);
        p += w * deltas[at].xyz;
        n += w * deltas[at + 1u].xyz;
        t += vec4<f32>(w * deltas[at + 2u].xyz, 0.0);
    }
    // The blended joint matrix (a joint index past the skin's end counts as none).
    var m = mat4x4<f32>(vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0));
    for (var j = 0u; j < 4u; j++) {
        if v.joints[j] < d.joint_count {
            m += joint_matrices[d.first_joint + v.joints[j]] * v.weights[j];
        }
    }
    let l = mat3x3<f32>(m[0].xyz, m[1].xyz, m[2].xyz);
    // Normals by the cofactor matrix (inverse transpose × determinant), outward under mirroring.
    let cofactor = mat3x3<f32>(cross(l[1], l[2]), cross(l[2], l[0]), cross(l[0], l[1]));
    let sign = select(1.0, -1.0, determinant(l) < 0.0);
    let position = (m * vec4<f32>(p, 1.0)).xyz;
    let normal = safe_normalize(sign * (cofactor * n), vec3<f32>(0.0, 1.0, 0.0));
    positions[3u * v.vertex] = position.x;
    positions[3u * v.vertex + 1u] = position.y;
    positions[3u * v.vertex + 2u] = position.z;
    let a = ATTRIBUTE_FLOATS * v.vertex;
    attributes[a + NORMAL_AT] = normal.x;
    attributes[a + NORMAL_AT + 1u] = normal.y;
    attributes[a + NORMAL_AT + 2u] = normal.z;
    if d.tangents != 0u {
        let tangent = safe_normalize(l * t.xyz, vec3<f32>(1.0, 0.0, 0.0));
        attributes[a + TANGENT_AT] = tangent.x;
        attributes[a + TANGENT_AT + 1u] = tangent.y;
        attributes[a + TANGENT_AT + 2u] = tangent.z;
        attributes[a + TANGENT_AT + 3u] = t.w * sign;
    }
}
