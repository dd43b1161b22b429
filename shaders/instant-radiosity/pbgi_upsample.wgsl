// Point-based GI's edge-aware upsampling (Holländer 2013 §3.6.1 and Fig. 3.25: PBGI on a grid of
// receivers "combined with bilateral upsampling"): every pixel takes the bilinear mean of the
// four nearest receivers' irradiance over those on its own surface — normals within ~25° and the
// receiver within 2 % of the pixel's depth of its tangent plane — or, where none is, over those
// that show any surface. Writes E/π, the indirect diffuse the composition multiplies by the
// albedo. Mirrors `instant_radiosity::pbgi::upsample`.
// #import instant-radiosity/pbgi_grid.wgsl

@group(0) @binding(4) var<storage, read> irradiance: array<vec4<f32>>;
@group(0) @binding(5) var indirect_out: texture_storage_2d<rgba16float, write>;

// `pbgi::SAME_NORMAL` and `pbgi::SAME_PLANE`.
const SAME_NORMAL: f32 = 0.9;
const SAME_PLANE: f32 = 0.02;

@compute @workgroup_size(8, 8)
fn upsample(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = vec2<u32>(frame.viewport.xy);
    if any(id.xy >= size) {
        return;
    }
    let depth = textureLoad(linear_depth, id.xy, 0).x;
    if depth <= 0.0 {
        textureStore(indirect_out, id.xy, vec4<f32>(0.0, 0.0, 0.0, 1.0));
        return;
    }
    let p = position_from_view_ray(frame, id.xy, depth);
    let n = normal_at(id.xy);
    let g = (vec2<f32>(id.xy) - f32(grid.stride / 2u)) / f32(grid.stride);
    let c0 = floor(g);
    let f = g - c0;
    var same = vec4<f32>(0.0);
    var any_surface = vec4<f32>(0.0);
    for (var k = 0u; k < 4u; k++) {
        let o = vec2<f32>(f32(k & 1u), f32(k >> 1u));
        let cell = clamp(c0 + o, vec2<f32>(0.0), vec2<f32>(f32(grid.columns - 1u), f32(grid.rows - 1u)));
        let c = vec2<u32>(cell);
        let w = mix(1.0 - f.x, f.x, o.x) * mix(1.0 - f.y, f.y, o.y);
        let rp = receiver_pixel(c, size);
        let rd = textureLoad(linear_depth, rp, 0).x;
        if rd <= 0.0 {
            continue;
        }
        let e = irradiance[c.y * grid.columns + c.x].rgb;
        let q = position_from_view_ray(frame, rp, rd);
        let on_surface = dot(n, normal_at(rp)) > SAME_NORMAL && abs(dot(n, q - p)) < SAME_PLANE * depth;
        any_surface += vec4<f32>(e * w, w);
        if on_surface {
            same += vec4<f32>(e * w, w);
        }
    }
    var e = vec3<f32>(0.0);
    if same.w > 1e-6 {
        e = same.rgb / same.w;
    } else if any_surface.w > 1e-6 {
        e = any_surface.rgb / any_surface.w;
    }
    textureStore(indirect_out, id.xy, vec4<f32>(e / PI, 1.0));
}
