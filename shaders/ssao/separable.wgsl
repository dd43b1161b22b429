// #import ssao/common.wgsl
// The separable approximation (Holländer 2013 §7.2.2; `ssao::cpu::separable`): pass 1 along
// each pixel's interleaved frame direction u, pass 2 over the perpendicular v on p's surface.

// Pass 1: mean occlusion along u (k − 1 samples).
@compute @workgroup_size(8, 8)
fn pass_1d(@builtin(global_invocation_id) id: vec3<u32>) {
    if !in_image(id) {
        return;
    }
    let x = i32(id.x);
    let y = i32(id.y);
    let here = surface_at(x, y);
    var sum = 0.0;
    if here.present {
        let u = frame_direction(x, y);
        let half = i32(params.size / 2u);
        for (var t = -half; t <= half; t++) {
            if t == 0 {
                continue;
            }
            let at = step_along(x, y, u, t);
            let q = surface_at(at.x, at.y);
            if q.present {
                sum += occlusion(here.position, here.normal, q.position);
            }
        }
    }
    first[pixel_index(id)] = sum / f32(params.size - 1u);
}

// Whether q lies on p's surface (depth within 5 %, normals within 25°).
fn same_surface(p: Surface, q: Surface) -> bool {
    return q.present && abs(q.depth - p.depth) <= 0.05 * p.depth && dot(p.normal, q.normal) >= 0.9;
}

// Pass 2: pass 1 averaged along v over p's surface; A = 1 − 2·mean.
@compute @workgroup_size(8, 8)
fn pass_2(@builtin(global_invocation_id) id: vec3<u32>) {
    if !in_image(id) {
        return;
    }
    let x = i32(id.x);
    let y = i32(id.y);
    let here = surface_at(x, y);
    if !here.present {
        accessibility_out[pixel_index(id)] = 1.0;
        return;
    }
    let d = frame_direction(x, y);
    let v = vec2<f32>(-d.y, d.x);
    let half = i32(params.size / 2u);
    var sum = 0.0;
    var count = 0.0;
    for (var t = -half; t <= half; t++) {
        let at = step_along(x, y, v, t);
        if same_surface(here, surface_at(at.x, at.y)) {
            sum += first[u32(at.y) * params.width + u32(at.x)];
            count += 1.0;
        }
    }
    accessibility_out[pixel_index(id)] = accessibility(sum / count);
}
