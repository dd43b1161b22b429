// #import gbuffer/gbuffer.wgsl
// #import gbuffer/meshes.wgsl
// #import gbuffer/visibility_word.wgsl
// The visibility buffer's meshes drawn by the hardware rasteriser: alpha-tested ones (masked,
// or blended and dithered), whose coverage depends on the material's alpha, a texture lookup
// with derivatives the compute rasteriser does not take, and meshes of large triangles the
// caller routes here (`VisibilityPass::bind_split`; their alpha test keeps every fragment).
// Each fragment the G-buffer pass would keep
// (`surface_fragment`'s alpha test) merges its z/w and triangle id into the visibility buffer
// as the compute rasteriser merges them (`visibility_word.wgsl`: in the narrow variant the
// draw runs twice, once per pass). Vertices are pulled from the scene's
// buffers, so the fragment knows its triangle: mesh m is drawn as instance m over its index
// slots (`draw(first_index..first_index + index_count, m..m + 1)`).

@group(0) @binding(2) var<storage, read> positions: array<f32>;
// `gbuffer::gpu::GpuAttributes`: normal (3), uv0 (2), uv1 (2), tangent (4), colour (4).
@group(0) @binding(3) var<storage, read> attributes: array<f32>;
@group(0) @binding(5) var<storage, read> indices: array<u32>;

const ATTRIBUTE_FLOATS: u32 = 15u;

struct AlphaVertex {
    // Invariant: the same clip position as the G-buffer pass's `vs_main`.
    @builtin(position) @invariant clip: vec4<f32>,
    // Texture-coordinate sets 0 (xy) and 1 (zw).
    @location(0) uv: vec4<f32>,
    @location(1) color: vec4<f32>,
    @location(2) @interpolate(flat) id: u32,
}

@vertex
fn vs_hardware(@builtin(vertex_index) slot: u32, @builtin(instance_index) m: u32) -> AlphaVertex {
    let mesh = meshes[m];
    let v = mesh.base_vertex + indices[slot];
    let a = ATTRIBUTE_FLOATS * v;
    var out: AlphaVertex;
    out.clip = frame.view_proj * vec4(positions[3u * v], positions[3u * v + 1u], positions[3u * v + 2u], 1.0);
    out.uv = vec4(attributes[a + 3u], attributes[a + 4u], attributes[a + 5u], attributes[a + 6u]);
    out.color = vec4(attributes[a + 11u], attributes[a + 12u], attributes[a + 13u], attributes[a + 14u]);
    out.id = mesh.first_id + (slot - mesh.first_index) / 3u;
    return out;
}

@fragment
fn fs_hardware(in: AlphaVertex) {
    // `evaluate_fragment`'s coordinates and derivatives; the alpha reads nothing else.
    let footprint = max(frame.sampling.z, 1.0);
    let at = SurfaceAttributes(in.uv, dpdxFine(in.uv) * footprint, dpdyFine(in.uv) * footprint, vec3(0.0, 0.0, 1.0), false, vec4(0.0), in.color);
    if !alpha_keeps(material_alpha(at), dither_threshold(vec2<u32>(in.clip.xy))) {
        discard;
    }
    let pixel = vec2<u32>(in.clip.xy);
    merge(pixel.y * u32(frame.viewport.x) + pixel.x, in.clip.z, in.id);
}
