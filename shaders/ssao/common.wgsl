// #import gbuffer/frame.wgsl
// #import gbuffer/normal_encoding.wgsl
// What the screen-space estimators share (`ssao::cpu`, function for function): parameters,
// the G-buffer's surfaces, the occlusion of one neighbour, the accessibility.

struct Params {
    width: u32,
    height: u32,
    // Kernel side k (odd).
    size: u32,
    radius: f32,
};

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> params: Params;
@group(0) @binding(2) var linear_depth_tex: texture_2d<f32>;
@group(0) @binding(3) var normal_tex: texture_2d<u32>;
// The per-pixel frame directions u of the k × k interleaving tile (`cpu::frame_directions`).
@group(0) @binding(4) var<storage, read> directions: array<vec2<f32>>;
// Pass 1's mean occlusion (separable), or unused.
@group(0) @binding(5) var<storage, read_write> first: array<f32>;
// The accessibility A per pixel.
@group(0) @binding(6) var<storage, read_write> accessibility_out: array<f32>;

struct Surface {
    position: vec3<f32>,
    normal: vec3<f32>,
    depth: f32,
    present: bool,
};

fn surface_at(x: i32, y: i32) -> Surface {
    var s: Surface;
    s.present = false;
    if x < 0 || y < 0 || x >= i32(params.width) || y >= i32(params.height) {
        return s;
    }
    let q = vec2<u32>(u32(x), u32(y));
    let depth = textureLoad(linear_depth_tex, q, 0).r;
    if depth <= 0.0 {
        return s;
    }
    s.present = true;
    s.depth = depth;
    s.position = position_from_view_ray(frame, q, depth);
    s.normal = decode_octahedral_snorm(unpack2x16snorm(textureLoad(normal_tex, q, 0).r));
    return s;
}

// o(p, q): the cosine of the direction to q when it blocks it within the radius, else 0.
fn occlusion(p: vec3<f32>, n: vec3<f32>, q: vec3<f32>) -> f32 {
    let v = q - p;
    let d = length(v);
    if d <= 0.0 || d >= params.radius {
        return 0.0;
    }
    return max(dot(n, v) / d, 0.0);
}

fn accessibility(mean_occlusion: f32) -> f32 {
    return clamp(1.0 - 2.0 * mean_occlusion, 0.0, 1.0);
}

// The pixel t steps along `direction` from (x, y), rounded half up.
fn step_along(x: i32, y: i32, direction: vec2<f32>, t: i32) -> vec2<i32> {
    let o = floor(direction * f32(t) + 0.5);
    return vec2<i32>(x + i32(o.x), y + i32(o.y));
}

// The direction u of pixel (x, y)'s local frame.
fn frame_direction(x: i32, y: i32) -> vec2<f32> {
    let k = i32(params.size);
    let index = ((x % k) + k) % k + k * (((y % k) + k) % k);
    return directions[index];
}

fn in_image(id: vec3<u32>) -> bool {
    return id.x < params.width && id.y < params.height;
}

fn pixel_index(id: vec3<u32>) -> u32 {
    return id.y * params.width + id.x;
}
