// #import interleave/texel.wgsl
// One-pass split and gather by index arithmetic (Segovia 2006 §3.2, §3.4).

@compute @workgroup_size(16, 16)
fn split_one_pass(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= n * sub_width || id.y >= m * sub_height {
        return;
    }
    let i = id.x / sub_width;
    let u = id.x % sub_width;
    let j = id.y / sub_height;
    let v = id.y % sub_height;
    textureStore(destination, id.xy, load_pixel(u * n + i, v * m + j));
}

@compute @workgroup_size(16, 16)
fn gather_one_pass(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= width || id.y >= height {
        return;
    }
    let s = vec2((id.x % n) * sub_width + id.x / n, (id.y % m) * sub_height + id.y / m);
    textureStore(destination, id.xy, textureLoad(source, s, 0));
}
