// #import ssao/common.wgsl
// Eq. 7.1 (Holländer 2013 §7.2.1): every neighbour of the k × k window
// (`ssao::cpu::kernel_2d`).

@compute @workgroup_size(8, 8)
fn kernel_2d(@builtin(global_invocation_id) id: vec3<u32>) {
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
    let half = i32(params.size / 2u);
    var sum = 0.0;
    for (var dy = -half; dy <= half; dy++) {
        for (var dx = -half; dx <= half; dx++) {
            if dx == 0 && dy == 0 {
                continue;
            }
            let q = surface_at(x + dx, y + dy);
            if q.present {
                sum += occlusion(here.position, here.normal, q.position);
            }
        }
    }
    let samples = f32(params.size * params.size - 1u);
    accessibility_out[pixel_index(id)] = accessibility(sum / samples);
}
