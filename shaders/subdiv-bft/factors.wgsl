// View-dependent tessellation factors for adaptive subdivision (Holländer 2013 §2.2.3,
// "Adaptive Refinement"): one thread per M¹ edge, f = log2(projected length / target pixels)
// clamped to [0, log2 s_max]; edges entirely behind the eye get 0, edges crossing the eye plane
// the maximum. Mirrors `subdiv_bft::adaptive::screen_factors`.

struct FactorParams {
    view_proj: mat4x4<f32>,
    // Viewport size in pixels.
    viewport: vec2<f32>,
    target_pixels: f32,
    // log2 s_max.
    max_factor: f32,
    edge_count: u32,
};

@group(0) @binding(0) var<uniform> params: FactorParams;
@group(0) @binding(1) var<storage, read> p1: array<vec4<f32>>;
// End vertices of each M¹ edge.
@group(0) @binding(2) var<storage, read> ends: array<vec2<u32>>;
@group(0) @binding(3) var<storage, read_write> factors: array<f32>;

@compute @workgroup_size(64)
fn edge_factors(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    let e = id.x + id.y * groups.x * 64u;
    if e >= params.edge_count {
        return;
    }
    let a = params.view_proj * vec4<f32>(p1[ends[e].x].xyz, 1.0);
    let b = params.view_proj * vec4<f32>(p1[ends[e].y].xyz, 1.0);
    var f = params.max_factor;
    if a.w <= 0.0 && b.w <= 0.0 {
        f = 0.0;
    } else if a.w > 0.0 && b.w > 0.0 {
        let d = (a.xy / a.w - b.xy / b.w) * (0.5 * params.viewport);
        f = clamp(log2(length(d) / params.target_pixels), 0.0, params.max_factor);
    }
    factors[e] = f;
}
