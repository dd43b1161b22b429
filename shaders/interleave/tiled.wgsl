// #import interleave/texel.wgsl
// Tiled one-pass split and gather: a workgroup owns a tile of a·n × b·m pixels, i.e. an a×b
// run of every sub-buffer. The side that touches the image walks the tile in row order, the
// side that touches the split texture walks each sub-buffer's run in row order, and the
// transposition between the two goes through workgroup memory.

const TILE_TEXELS: u32 = 512u;
const THREADS: u32 = 256u;
var<workgroup> tile: array<Texel, TILE_TEXELS>;

// Slot of tile pixel (lx, ly): sub-buffers one after the other, each run in row order.
fn tile_slot(lx: u32, ly: u32) -> u32 {
    return (((ly % m) * n + lx % n) * b + ly / m) * a + lx / n;
}

// Split texel of slot k of tile t, and whether it lies in the split texture.
fn slot_texel(t: vec2<u32>, k: u32) -> vec3<u32> {
    let s = k / (a * b);
    let r = k % (a * b);
    let u = t.x * a + r % a;
    let v = t.y * b + r / a;
    let inside = u < sub_width && v < sub_height;
    return vec3((s % n) * sub_width + u, (s / n) * sub_height + v, u32(inside));
}

@compute @workgroup_size(256)
fn split_tiled(@builtin(workgroup_id) t: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let tw = a * n;
    let count = tw * b * m;
    let origin = t.xy * vec2(tw, b * m);
    for (var k = li; k < count; k += THREADS) {
        let l = vec2(k % tw, k / tw);
        tile[tile_slot(l.x, l.y)] = load_pixel(origin.x + l.x, origin.y + l.y);
    }
    workgroupBarrier();
    for (var k = li; k < count; k += THREADS) {
        let s = slot_texel(t.xy, k);
        if s.z != 0u {
            textureStore(destination, s.xy, tile[k]);
        }
    }
}

@compute @workgroup_size(256)
fn gather_tiled(@builtin(workgroup_id) t: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let tw = a * n;
    let count = tw * b * m;
    for (var k = li; k < count; k += THREADS) {
        let s = slot_texel(t.xy, k);
        var texel = Texel();
        if s.z != 0u {
            texel = textureLoad(source, s.xy, 0);
        }
        tile[k] = texel;
    }
    workgroupBarrier();
    let origin = t.xy * vec2(tw, b * m);
    for (var k = li; k < count; k += THREADS) {
        let p = origin + vec2(k % tw, k / tw);
        if p.x < width && p.y < height {
            textureStore(destination, p, tile[tile_slot(k % tw, k / tw)]);
        }
    }
}
