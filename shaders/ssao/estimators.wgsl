// #import ssao/common.wgsl
// The screen-space estimators (`ssao::cpu`, function for function): `full` (the k × k form),
// `pass_1` and `pass_2` (the separable approximation, Holländer 2013 §7.2.2). METHOD is
// `ssao::Method` in declaration order.

override METHOD: u32;
const FILTER: u32 = 0u;
const CRYTEK: u32 = 1u;
const HBAO: u32 = 3u;
const GTAO: u32 = 4u;
const HALF_PI: f32 = 1.5707963;

struct Sums {
    occluded: f32,
    total: f32,
};

// ξ(m) ∈ (−1, 1), odd in the window offset numbered m.
fn crytek_offset(m: i32) -> f32 {
    let f = fract(f32(abs(m)) * 0.618034);
    return select(f, -f, m < 0);
}

// o(p, q): the cosine of the direction to q when it blocks it within the radius, else 0.
fn occlusion(p: Surface, q: vec3<f32>) -> f32 {
    let v = q - p.position;
    let d2 = dot(v, v);
    if d2 <= 0.0 || d2 >= params.radius * params.radius {
        return 0.0;
    }
    return max(dot(p.normal, v) * inverseSqrt(d2), 0.0);
}

// Adds the sample at pixel q (window offset numbered m) to p's sums.
fn add_window_sample(p: Surface, q: vec2<i32>, m: i32, sums_in: Sums) -> Sums {
    var sums = sums_in;
    let r = params.radius;
    if METHOD == FILTER {
        sums.total += 1.0;
        let d = depth_at(q.x, q.y);
        if d > 0.0 {
            sums.occluded += occlusion(p, frame.eye.xyz + ray_at(q.x, q.y) * d);
        }
        return sums;
    }
    // Crytek and VO: q's view ray through the sphere around p (none outside the image).
    if !in_bounds(grid_pixel(q.x, q.y)) {
        return sums;
    }
    let lateral = length(ray_at(q.x, q.y) - p.ray) * p.depth;
    if lateral >= r {
        return sums;
    }
    let half_chord = sqrt(r * r - lateral * lateral);
    let b = depth_at(q.x, q.y);
    if METHOD == CRYTEK {
        let sample = p.depth + crytek_offset(m) * half_chord;
        sums.total += 1.0;
        if b > 0.0 && b < sample && sample - b < r {
            sums.occluded += 1.0;
        }
    } else {
        sums.total += 2.0 * half_chord;
        if b > 0.0 {
            sums.occluded += clamp(p.depth + half_chord - b, 0.0, 2.0 * half_chord);
        }
    }
    return sums;
}

// A window method's A from its sums (unclamped).
fn window_value(sums: Sums) -> f32 {
    if sums.total <= 0.0 {
        return 1.0;
    }
    let fraction = sums.occluded / sums.total;
    if METHOD == FILTER {
        return 1.0 - 2.0 * fraction;
    }
    return 2.0 * (1.0 - fraction);
}

// The highest sin(elevation) above the plane normal to `view` of the samples on one side of
// the line, starting from `lowest`.
fn horizon(p: Surface, view: vec3<f32>, x: i32, y: i32, u: vec2<f32>, side: i32, lowest: f32) -> f32 {
    var highest = lowest;
    let half = i32(params.size / 2u);
    for (var t = 1; t <= half; t++) {
        let q = step_along(x, y, u, side * t);
        let d = depth_at(q.x, q.y);
        if d > 0.0 {
            let delta = frame.eye.xyz + ray_at(q.x, q.y) * d - p.position;
            let d2 = dot(delta, delta);
            if d2 > 0.0 && d2 < params.radius * params.radius {
                highest = max(highest, dot(delta, view) * inverseSqrt(d2));
            }
        }
    }
    return highest;
}

fn normalize_or_zero(v: vec3<f32>) -> vec3<f32> {
    let l = length(v);
    return select(vec3<f32>(0.0), v / l, l > 0.0);
}

// A along the line through pixel (x, y) in screen direction u (unclamped), and its weight in
// pass 2 (1, but GTAO's open arc).
fn line_value(p: Surface, x: i32, y: i32, u: vec2<f32>) -> vec2<f32> {
    let half = i32(params.size / 2u);
    if METHOD < HBAO {
        var sums = Sums(0.0, 0.0);
        for (var t = -half; t <= half; t++) {
            if t != 0 {
                sums = add_window_sample(p, step_along(x, y, u, t), t, sums);
            }
        }
        return vec2<f32>(window_value(sums), 1.0);
    }
    let view = normalize(frame.eye.xyz - p.position);
    let direction = (frame.inv_view * vec4<f32>(u.x, -u.y, 0.0, 0.0)).xyz;
    let ortho = direction - view * dot(direction, view);
    let axis = normalize_or_zero(cross(ortho, view));
    if METHOD == HBAO {
        var tangent = cross(axis, p.normal);
        if dot(tangent, ortho) < 0.0 {
            tangent = -tangent;
        }
        let sin_t = dot(normalize_or_zero(tangent), view);
        let forward = horizon(p, view, x, y, u, 1, sin_t);
        let backward = horizon(p, view, x, y, u, -1, -sin_t);
        return vec2<f32>(1.0 - 0.5 * ((forward - sin_t) + (backward + sin_t)), 1.0);
    }
    let projected = p.normal - axis * dot(p.normal, axis);
    let len = length(projected);
    if len <= 0.0 {
        return vec2<f32>(0.0);
    }
    let cos_n = clamp(dot(projected, view) / len, 0.0, 1.0);
    let gamma = select(acos(cos_n), -acos(cos_n), dot(ortho, projected) < 0.0);
    let forward = horizon(p, view, x, y, u, 1, cos(gamma + HALF_PI));
    let backward = horizon(p, view, x, y, u, -1, cos(gamma - HALF_PI));
    let h_forward = gamma + clamp(acos(clamp(forward, -1.0, 1.0)) - gamma, -HALF_PI, HALF_PI);
    let h_backward = gamma + clamp(-acos(clamp(backward, -1.0, 1.0)) - gamma, -HALF_PI, HALF_PI);
    // The open slice's arc is cos γ + γ·sin γ.
    let visible = arc(h_forward, gamma, cos_n) + arc(h_backward, gamma, cos_n);
    return len * vec2<f32>(visible, cos_n + gamma * sin(gamma));
}

// GTAO's cosine-weighted visible arc from the projected normal's angle γ to horizon h.
fn arc(h: f32, gamma: f32, cos_n: f32) -> f32 {
    return 0.25 * (cos_n + 2.0 * h * sin(gamma) - cos(2.0 * h - gamma));
}

// The k × k form: the window, or k lines π/k apart turned by the pixel's interleaved angle.
@compute @workgroup_size(16, 16)
fn full(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(local_invocation_index) local_index: u32,
) {
    load_tiles(group, local_index);
    if !in_grid(id) {
        return;
    }
    let x = i32(id.x);
    let y = i32(id.y);
    let p = surface_at(x, y);
    if !p.present {
        store(id, 1.0);
        return;
    }
    let k = i32(params.size);
    let half = k / 2;
    var value = 0.0;
    if METHOD >= HBAO {
        let first_line = pattern_index(x, y);
        let count = params.size * params.size;
        for (var i = 0u; i < params.size; i++) {
            value += line_value(p, x, y, directions[(first_line + i * params.size) % count]).x;
        }
        value /= f32(params.size);
    } else {
        var sums = Sums(0.0, 0.0);
        for (var dy = -half; dy <= half; dy++) {
            for (var dx = -half; dx <= half; dx++) {
                if dx != 0 || dy != 0 {
                    sums = add_window_sample(p, vec2<i32>(x + dx, y + dy), dx + k * dy, sums);
                }
            }
        }
        value = window_value(sums);
    }
    store(id, clamp(value, 0.0, 1.0));
}

// Pass 1 (untiled): the line along the pixel's direction u.
@compute @workgroup_size(16, 16)
fn pass_1(@builtin(global_invocation_id) id: vec3<u32>) {
    init_rays();
    if !in_grid(id) {
        return;
    }
    let p = surface_at(i32(id.x), i32(id.y));
    var value = vec2<f32>(1.0);
    if p.present {
        value = line_value(p, i32(id.x), i32(id.y), directions[pattern_index(i32(id.x), i32(id.y))]);
    }
    first[grid_index(id)] = value.x;
    first[params.width * params.height + grid_index(id)] = value.y;
}

// Whether q lies on p's surface (depth within 5 %, normals within 25°).
fn same_surface(p: Surface, q: Surface) -> bool {
    return q.present && abs(q.depth - p.depth) <= 0.05 * p.depth && dot(p.normal, q.normal) >= 0.9;
}

// Pass 2 (untiled): pass 1 averaged along v over p's surface (GTAO: weighted by the open
// arcs).
@compute @workgroup_size(16, 16)
fn pass_2(@builtin(global_invocation_id) id: vec3<u32>) {
    init_rays();
    if !in_grid(id) {
        return;
    }
    let x = i32(id.x);
    let y = i32(id.y);
    let p = surface_at(x, y);
    if !p.present {
        combined(id, 1.0);
        return;
    }
    let d = directions[pattern_index(x, y)];
    let v = vec2<f32>(-d.y, d.x);
    let half = i32(params.size / 2u);
    var sum = 0.0;
    var weights = 0.0;
    for (var t = -half; t <= half; t++) {
        let at = step_along(x, y, v, t);
        if same_surface(p, surface_at(at.x, at.y)) {
            sum += first[u32(at.y) * params.width + u32(at.x)];
            if METHOD == GTAO {
                weights += first[params.width * params.height + u32(at.y) * params.width + u32(at.x)];
            } else {
                weights += 1.0;
            }
        }
    }
    var a = 1.0;
    if weights > 0.0 {
        a = clamp(sum / weights, 0.0, 1.0);
    }
    combined(id, a);
}

// Pass 2's value: A, or with the smoothing to follow, first's last third.
fn combined(id: vec3<u32>, a: f32) {
    if params.smoothing == 1u {
        first[2u * params.width * params.height + grid_index(id)] = a;
    } else {
        store(id, a);
    }
}

// The feature-preserving smoothing (`cpu::smooth`): the mean of `first[source + …]` over the k
// grid points along `axis` on p's surface; 1 without a surface.
fn smoothed(id: vec3<u32>, axis: vec2<i32>, source: u32) -> f32 {
    let x = i32(id.x);
    let y = i32(id.y);
    let p = surface_at(x, y);
    if !p.present {
        return 1.0;
    }
    let half = i32(params.size / 2u);
    var sum = 0.0;
    var count = 0.0;
    for (var t = -half; t <= half; t++) {
        let q = vec2<i32>(x, y) + t * axis;
        if same_surface(p, surface_at(q.x, q.y)) {
            sum += first[source + u32(q.y) * params.width + u32(q.x)];
            count += 1.0;
        }
    }
    return sum / count;
}

// Smoothing along x: pass 2's values (first's last third) into first's first third.
@compute @workgroup_size(16, 16)
fn smooth_x(@builtin(global_invocation_id) id: vec3<u32>) {
    init_rays();
    if in_grid(id) {
        first[grid_index(id)] = smoothed(id, vec2<i32>(1, 0), 2u * params.width * params.height);
    }
}

// Smoothing along y: first's first third into A.
@compute @workgroup_size(16, 16)
fn smooth_y(@builtin(global_invocation_id) id: vec3<u32>) {
    init_rays();
    if in_grid(id) {
        store(id, smoothed(id, vec2<i32>(0, 1), 0u));
    }
}

// At half resolution: pixel (x, y)'s A from the estimates of the (up to) four nearest grid
// points on its surface, bilinearly weighted; with none on its surface, the nearest in depth;
// 1 without a surface.
@compute @workgroup_size(16, 16)
fn upsample(@builtin(global_invocation_id) id: vec3<u32>) {
    init_rays();
    if id.x >= params.image_width || id.y >= params.image_height {
        return;
    }
    let pixel = vec2<i32>(id.xy);
    let out = id.y * params.image_width + id.x;
    let p = pixel_surface(pixel);
    if !p.present {
        accessibility_out[out] = 1.0;
        return;
    }
    let base = pixel / 2;
    let f = vec2<f32>(pixel % 2) * 0.5;
    var sum = 0.0;
    var weights = 0.0;
    var nearest_gap = 3.4e38;
    var nearest = 1.0;
    for (var j = 0; j < 2; j++) {
        for (var i = 0; i < 2; i++) {
            let weight = select(f.x, 1.0 - f.x, i == 0) * select(f.y, 1.0 - f.y, j == 0);
            let g = base + vec2<i32>(i, j);
            let q = pixel_surface(g * 2);
            if weight > 0.0 && q.present {
                let value = coarse[u32(g.y) * params.width + u32(g.x)];
                if same_surface(p, q) {
                    sum += weight * value;
                    weights += weight;
                }
                let gap = abs(q.depth - p.depth);
                if gap < nearest_gap {
                    nearest_gap = gap;
                    nearest = value;
                }
            }
        }
    }
    accessibility_out[out] = select(nearest, sum / weights, weights > 0.0);
}
