// Point-based GI's receivers from the G-buffer (Holländer 2013 §3.6.1: "the visible pixels are
// backprojected into the scene"): the centre pixel of every cell of a grid over the frame, its
// position from the view depth, its normal, and its indirect-lighting view — a paraboloid of
// `tile`² texels over the normal's hemisphere, lifted by `ray_lift` (`manylod::View::gpu`).
// A cell whose pixel shows no surface gets a view at the eye looking up (its irradiance is not
// used). Mirrors `instant_radiosity::pbgi::grid_receivers` and `gather_views`.
// #import instant-radiosity/pbgi_grid.wgsl
// #import tiled-shading/rays.wgsl
// #import manylod/common.wgsl

@group(0) @binding(4) var<storage, read_write> views: array<View>;

@compute @workgroup_size(64)
fn receivers(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if i >= grid.columns * grid.rows {
        return;
    }
    let size = vec2<u32>(frame.viewport.xy);
    let pixel = receiver_pixel(vec2<u32>(i % grid.columns, i / grid.columns), size);
    let depth = textureLoad(linear_depth, pixel, 0).x;
    var p = frame.eye.xyz;
    var n = vec3<f32>(0.0, 1.0, 0.0);
    if depth > 0.0 {
        p = position_from_view_ray(frame, pixel, depth);
        n = normal_at(pixel);
    }
    let eye = p + n * ray_lift(p);
    let tb = paraboloid_frame(n);
    let t = tb[0];
    let b = tb[1];
    var v: View;
    v.planes[0] = vec4<f32>(n, -dot(n, eye));
    v.transform = mat4x4<f32>(
        vec4<f32>(t.x, b.x, n.x, 0.0),
        vec4<f32>(t.y, b.y, n.y, 0.0),
        vec4<f32>(t.z, b.z, n.z, 0.0),
        vec4<f32>(-dot(t, eye), -dot(b, eye), -dot(n, eye), 1.0),
    );
    v.eye = eye;
    v.kind = PARABOLOID;
    v.size = vec2<f32>(f32(grid.tile));
    v.pixels_per_radian = f32(grid.tile) * 0.5;
    v.rim = HALF_PI;
    views[i] = v;
}
