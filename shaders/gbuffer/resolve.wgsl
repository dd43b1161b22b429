// #import gbuffer/gbuffer.wgsl
// #import gbuffer/meshes.wgsl
// The visibility buffer resolved into the G-buffer layout (Burns & Hunt 2013): per pixel, the
// triangle its id names is fetched again, its attributes are interpolated at the pixel centre
// with perspective-correct barycentrics and their derivatives taken analytically at the
// neighbour of the 2 × 2 quad (as `dpdxFine`/`dpdyFine` and `gbuffer::cpu` take them), and
// the material is evaluated as `fs_main` evaluates it. One dispatch per material (its bind
// group is group 1, as in the G-buffer pass); `resolve_background` writes the cleared texels
// where no triangle is.

struct Resolve {
    // The material this dispatch resolves.
    material_index: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

// (depth bits << 32) | id per pixel, as two words: id, depth bits.
@group(0) @binding(2) var<storage, read> visibility: array<vec2<u32>>;
@group(0) @binding(3) var<uniform> resolve: Resolve;
@group(0) @binding(4) var<storage, read> positions: array<f32>;
// `gbuffer::gpu::GpuAttributes`: normal (3), uv0 (2), uv1 (2), tangent (4), colour (4).
@group(0) @binding(5) var<storage, read> attributes: array<f32>;
@group(0) @binding(6) var<storage, read> indices: array<u32>;
@group(0) @binding(7) var linear_depth_out: texture_storage_2d<r32float, write>;
@group(0) @binding(8) var normal_out: texture_storage_2d<r32uint, write>;
@group(0) @binding(9) var albedo_out: texture_storage_2d<rgba8unorm, write>;
@group(0) @binding(10) var material_out: texture_storage_2d<r32uint, write>;
@group(0) @binding(11) var emission_out: texture_storage_2d<rgba16float, write>;

const NO_TRIANGLE: u32 = 0xFFFFFFFFu;
const ATTRIBUTE_FLOATS: u32 = 15u;

fn world_position(v: u32) -> vec3<f32> {
    return vec3(positions[3u * v], positions[3u * v + 1u], positions[3u * v + 2u]);
}

fn vertex_attribute(v: u32, k: u32) -> f32 {
    return attributes[ATTRIBUTE_FLOATS * v + k];
}

// Perspective-correct barycentrics of the triangle with clip positions `clip` at the image
// point c (pixels, y down): the homogeneous 2D edge functions, valid whatever the signs of w.
fn barycentrics(clip: array<vec4<f32>, 3>, c: vec2<f32>) -> vec3<f32> {
    let size = frame.viewport.xy;
    let p = vec3(c.x / size.x * 2.0 - 1.0, 1.0 - c.y / size.y * 2.0, 1.0);
    let r0 = clip[0].xyw;
    let r1 = clip[1].xyw;
    let r2 = clip[2].xyw;
    let e = vec3(dot(cross(r1, r2), p), dot(cross(r2, r0), p), dot(cross(r0, r1), p));
    return e / (e.x + e.y + e.z);
}

// Attributes `first` to `first + 3` at barycentrics l.
fn interpolate(v: vec3<u32>, l: vec3<f32>, first: u32) -> vec4<f32> {
    var a = vec4(0.0);
    for (var k = 0u; k < 4u; k++) {
        a[k] = l.x * vertex_attribute(v.x, first + k) + l.y * vertex_attribute(v.y, first + k) + l.z * vertex_attribute(v.z, first + k);
    }
    return a;
}

fn store(p: vec2<u32>, out: GBufferOut) {
    textureStore(linear_depth_out, p, vec4(out.linear_depth, 0.0, 0.0, 0.0));
    textureStore(normal_out, p, vec4(out.normal, 0u, 0u, 0u));
    textureStore(albedo_out, p, out.albedo);
    textureStore(material_out, p, vec4(out.material, 0u, 0u, 0u));
    textureStore(emission_out, p, out.emission);
}

@compute @workgroup_size(8, 8)
fn resolve_material(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = vec2<u32>(frame.viewport.xy);
    if any(gid.xy >= size) {
        return;
    }
    let id = visibility[gid.y * size.x + gid.x].x;
    if id == NO_TRIANGLE {
        return;
    }
    let mesh = meshes[mesh_of(id)];
    if mesh.material != resolve.material_index {
        return;
    }
    let t = id - mesh.first_id;
    var v: vec3<u32>;
    var clip: array<vec4<f32>, 3>;
    var world: array<vec3<f32>, 3>;
    for (var k = 0u; k < 3u; k++) {
        v[k] = mesh.base_vertex + indices[mesh.first_index + 3u * t + k];
        world[k] = world_position(v[k]);
        clip[k] = frame.view_proj * vec4(world[k], 1.0);
    }
    let c = vec2<f32>(gid.xy) + 0.5;
    let l = barycentrics(clip, c);
    let view_depth = l.x * clip[0].w + l.y * clip[1].w + l.z * clip[2].w;
    // The derivatives over the texture footprint, towards the quad's other pixel.
    let footprint = max(frame.sampling.z, 1.0);
    let step = vec2(select(-1.0, 1.0, gid.x % 2u == 0u), select(-1.0, 1.0, gid.y % 2u == 0u));
    let uv = interpolate(v, l, 3u);
    let uv_dx = (interpolate(v, barycentrics(clip, c + vec2(step.x, 0.0)), 3u) - uv) * step.x * footprint;
    let uv_dy = (interpolate(v, barycentrics(clip, c + vec2(0.0, step.y)), 3u) - uv) * step.y * footprint;
    // Shaded from the side of the triangle's plane the camera sees.
    var geometric = cross(world[1] - world[0], world[2] - world[0]);
    if dot(geometric, frame.eye.xyz - world[0]) < 0.0 {
        geometric = -geometric;
    }
    let normal = vec3(
        l.x * vertex_attribute(v.x, 0u) + l.y * vertex_attribute(v.y, 0u) + l.z * vertex_attribute(v.z, 0u),
        l.x * vertex_attribute(v.x, 1u) + l.y * vertex_attribute(v.y, 1u) + l.z * vertex_attribute(v.z, 1u),
        l.x * vertex_attribute(v.x, 2u) + l.y * vertex_attribute(v.y, 2u) + l.z * vertex_attribute(v.z, 2u),
    );
    let facing = facing_geometric(normal, geometric);
    let at = SurfaceAttributes(uv, uv_dx, uv_dy, facing.normal, facing.back_face, interpolate(v, l, 7u), interpolate(v, l, 11u));
    store(gid.xy, gbuffer_texels(evaluate_material(at), view_depth));
}

@compute @workgroup_size(8, 8)
fn resolve_background(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = vec2<u32>(frame.viewport.xy);
    if any(gid.xy >= size) || visibility[gid.y * size.x + gid.x].x != NO_TRIANGLE {
        return;
    }
    var out: GBufferOut;
    out.linear_depth = 0.0;
    out.normal = 0u;
    out.albedo = vec4(0.0);
    out.material = NO_MATERIAL_WORD;
    out.emission = vec4(0.0);
    store(gid.xy, out);
}

const NO_MATERIAL_WORD: u32 = 0xFFFFFFFFu;

// The hardware depth target from the visibility buffer: a viewport-covering triangle whose
// fragments write the z/w of the visibility buffer's upper word (depth compare `Always`), and
// are discarded where no triangle is (the target stays cleared to 1).
@vertex
fn vs_depth_fullscreen(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let corner = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(corner * 2.0 - 1.0, 0.0, 1.0);
}

@fragment
fn fs_depth(@builtin(position) pixel: vec4<f32>) -> @builtin(frag_depth) f32 {
    let v = visibility[u32(pixel.y) * u32(frame.viewport.x) + u32(pixel.x)];
    if v.x == NO_TRIANGLE {
        discard;
    }
    return bitcast<f32>(v.y);
}
