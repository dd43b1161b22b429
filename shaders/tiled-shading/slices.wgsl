// The geometry of tiles and depth slices shared by `tiled.wgsl` and `clustered.wgsl`:
// exponential depth slices (`tiled_shading::Slicing`) and a tile's side planes in world space
// (`tiled_shading::cpu::tile_frustum`).
// #import tiled-shading/pixels.wgsl

const SLICES: u32 = 32u;
const SLICE_EPSILON: f32 = 1e-5;

fn slice_of(depth: f32) -> u32 {
    let k = floor(log(max(depth / params.slice_near, 1.0)) * params.slice_scale);
    return min(u32(max(k, 0.0)), SLICES - 1u);
}

fn slice_start(k: u32) -> f32 {
    return params.slice_near * exp(f32(k) / params.slice_scale);
}

// The view depth of a world position.
fn view_depth(p: vec3<f32>) -> f32 {
    return -dot(vec4<f32>(frame.view[0].z, frame.view[1].z, frame.view[2].z, frame.view[3].z), vec4<f32>(p, 1.0));
}

// A view-space plane (normal n, offset w) in world space: n·(R p + t) + w = (Rᵀn)·p + n·t + w.
fn world_plane(n: vec3<f32>, w: f32) -> vec4<f32> {
    let unit = n / length(n);
    return vec4<f32>((vec4<f32>(unit, 0.0) * frame.view).xyz, dot(unit, frame.view[3].xyz) + w / length(n));
}

// View-space slopes (x/depth, y/depth) of the pixel rectangle `rect` (x0, x1, y0, y1)'s
// edges: left, right, top, bottom.
fn edge_slopes(rect: vec4<u32>) -> vec4<f32> {
    return vec4<f32>(
        (f32(rect.x) * frame.viewport.z * 2.0 - 1.0) * frame.tan_half_fov.x,
        (f32(rect.y) * frame.viewport.z * 2.0 - 1.0) * frame.tan_half_fov.x,
        (1.0 - f32(rect.z) * frame.viewport.w * 2.0) * frame.tan_half_fov.y,
        (1.0 - f32(rect.w) * frame.viewport.w * 2.0) * frame.tan_half_fov.y,
    );
}

// The inward side planes (left, right, top, bottom) through the edges of slopes `s`.
fn side_planes(s: vec4<f32>) -> array<vec4<f32>, 4> {
    return array<vec4<f32>, 4>(
        world_plane(vec3<f32>(1.0, 0.0, s.x), 0.0),
        world_plane(vec3<f32>(-1.0, 0.0, -s.y), 0.0),
        world_plane(vec3<f32>(0.0, -1.0, -s.z), 0.0),
        world_plane(vec3<f32>(0.0, 1.0, s.w), 0.0),
    );
}
