// #import interleave/texel.wgsl
// Two-pass block split and gather (Segovia 2006 §3.3, §3.4, Figure 2). Blocks of p×q pixels
// (p = a·n, q = b·m); inside a block, sub-block (i, j) of a×b texels holds sub-buffer (i, j).

// Sub-buffer texel (i, u, j, v) stored at intermediate texel t.
fn sub_texel_at(t: vec2<u32>) -> vec4<u32> {
    let p = a * n;
    let q = b * m;
    let l = t % vec2(p, q);
    return vec4(l.x / a, (t.x / p) * a + l.x % a, l.y / b, (t.y / q) * b + l.y % b);
}

// Intermediate texel of sub-buffer texel (u, v) of sub-buffer (i, j).
fn intermediate_of(i: u32, u: u32, j: u32, v: u32) -> vec2<u32> {
    return vec2((u / a) * a * n + i * a + u % a, (v / b) * b * m + j * b + v % b);
}

// Pass 1 of the split, block splitting: image → intermediate.
@compute @workgroup_size(16, 16)
fn split_block_splitting(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id.xy >= textureDimensions(destination)) {
        return;
    }
    let s = sub_texel_at(id.xy);
    textureStore(destination, id.xy, load_pixel(s.y * n + s.x, s.w * m + s.z));
}

// Pass 2 of the split, block translation: intermediate → split.
@compute @workgroup_size(16, 16)
fn split_block_translation(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= n * sub_width || id.y >= m * sub_height {
        return;
    }
    let t = intermediate_of(id.x / sub_width, id.x % sub_width, id.y / sub_height, id.y % sub_height);
    textureStore(destination, id.xy, textureLoad(source, t, 0));
}

// Pass 1 of the gather, block translation: split → intermediate.
@compute @workgroup_size(16, 16)
fn gather_block_translation(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id.xy >= textureDimensions(destination)) {
        return;
    }
    let s = sub_texel_at(id.xy);
    var t = Texel();
    if s.y < sub_width && s.w < sub_height {
        t = textureLoad(source, vec2(s.x * sub_width + s.y, s.z * sub_height + s.w), 0);
    }
    textureStore(destination, id.xy, t);
}

// Pass 2 of the gather, block gathering: intermediate → image.
@compute @workgroup_size(16, 16)
fn gather_block_gathering(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= width || id.y >= height {
        return;
    }
    let t = intermediate_of(id.x % n, id.x / n, id.y % m, id.y / m);
    textureStore(destination, id.xy, textureLoad(source, t, 0));
}
