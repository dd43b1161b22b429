// Image size, interleave pattern n×m and sub-buffer size ceil(width/n) × ceil(height/m)
// (Segovia 2006 §3.2), set per pipeline as override constants.
override width: u32 = 1u;
override height: u32 = 1u;
override n: u32 = 1u;
override m: u32 = 1u;
override sub_width: u32 = 1u;
override sub_height: u32 = 1u;

// Whether texel t lies in the split layout (n·sub_width × m·sub_height texels).
fn in_split_layout(t: vec2<u32>) -> bool {
    return t.x < n * sub_width && t.y < m * sub_height;
}

// The subset j·n + i of split texel t, in sub-buffer (i, j).
fn split_subset(t: vec2<u32>) -> u32 {
    return (t.y / sub_height) * n + t.x / sub_width;
}

// The image pixel of split texel t: texel (u, v) of sub-buffer (i, j) is pixel
// (u·n + i, v·m + j) (§3.2); padding texels map outside the image.
fn split_pixel(t: vec2<u32>) -> vec2<u32> {
    let sub = vec2(sub_width, sub_height);
    return (t % sub) * vec2(n, m) + t / sub;
}
