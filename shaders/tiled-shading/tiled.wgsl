// #import tiled-shading/shadows.wgsl
// #import tiled-shading/pixels.wgsl
// #import tiled-shading/sums.wgsl
// #import tiled-shading/slices.wgsl
// #import tiled-shading/light_search.wgsl
// Light accumulation: brute force (`brute_force`, every light at every pixel) and tile-based
// deferred shading in one compute pass (`shade_tiles`, Ishmukhametov 2013 §2.4.1 after
// Andersson 2009): one workgroup per screen tile loads its G-buffer pixels, reduces their depth bounds
// (and normal cone, chapter 4 steps 2–3; and occupied depth slices, §2.5), then switches to
// lights: every invocation tests one light of a batch against the tile frustum and appends it
// to the tile's list in workgroup memory; whenever the list could overflow with the next batch,
// and after the last one, the invocations switch back to pixels and shade from the list.
// The lights are found as `light_search.wgsl` says: with LIGHT_TREE through the light
// hierarchy (rounds of THREADS groups tested against the tile frustum, then the lights of
// the groups that pass one by one), without it every light. The lists are the same.
// Forward+ (METHOD_FORWARD, §2.4.2) only builds the lists, for the depths from the near plane
// to the tile's farthest opaque surface (the far plane where a pixel shows no surface, so
// blended surfaces in front of the opaque ones find their lights too), marks the entries that
// also meet the opaque depth bounds (FORWARD_OPAQUE) and keeps them in `lists` for the
// forward pass (`forward.wgsl`).
// The light pre-pass's lighting pass (METHOD_PREPASS, §2.1 after Engel 2008) culls as tiled
// and writes the light buffer instead: diffuse light E/π summed in rgb, and in alpha the
// luminance of the summed specular light without its Fresnel factor (E·D·V, monochrome); its
// second geometry pass (`light_prepass.wgsl`) applies the materials. With `record_lists` the
// monochrome specular goes to the specular output too (for the CPU twin).
// Twin of `tiled_shading::cpu` (same names). `tiled_shading::gpu::specialisation` sets
// METHOD, TILE, WG, ROUND (= WG²) and LIGHT_TREE.

const METHOD: u32 = 1u;
const TILE: u32 = 16u;
// Invocations per tile side, min(TILE, 16); each shades PER_SIDE² pixels.
const WG: u32 = 16u;
const PER_SIDE: u32 = TILE / WG;
const PIXELS: u32 = PER_SIDE * PER_SIDE;
const THREADS: u32 = WG * WG;
const CAPACITY: u32 = 768u;

const METHOD_TILED: u32 = 1u;
const METHOD_CONES: u32 = 2u;
const METHOD_SLICES: u32 = 3u;
const METHOD_FORWARD: u32 = 4u;
const METHOD_PREPASS: u32 = 5u;
// Forward+ entry bits (`tiled_shading::cpu::FORWARD_OPAQUE`, `FORWARD_BLENDED`).
const FORWARD_OPAQUE: u32 = 1u;
const FORWARD_BLENDED: u32 = 2u;
const ALL_SLICES: u32 = 0xffffffffu;
const NORMAL_QUANTUM: f32 = 32768.0;
const COSINE_QUANTUM: f32 = 1048576.0;
const CONE_EPSILON: f32 = 1e-3;
// Lights per group of the light hierarchy (`tiled_shading::LIGHT_GROUP`).

// Per tile: the number of lights in its list (the light-count heatmap).
@group(0) @binding(9) var<storage, read_write> counts: array<u32>;
// Per tile: (light index, slice mask) × list_stride, when params.record_lists is 1.
@group(0) @binding(10) var<storage, read_write> lists: array<vec2<u32>>;

// Tree reductions over the invocations: (min depth bits, max depth bits, slice mask, _) and
// (quantized normal sum xyz, least quantized cosine) — four-way steps, no same-address atomics.
var<workgroup> reduce_u: array<vec4<u32>, THREADS>;
var<workgroup> reduce_i: array<vec4<i32>, THREADS>;
var<workgroup> list_count: atomic<u32>;
var<workgroup> list_size: u32;
var<workgroup> list_light: array<u32, CAPACITY>;
var<workgroup> list_mask: array<u32, CAPACITY>;
// Slices: the slice starts.
var<workgroup> slice_starts: array<f32, 33>;

fn normalize_or_zero(v: vec3<f32>) -> vec3<f32> {
    let len2 = dot(v, v);
    if len2 > 0.0 {
        return v * inverseSqrt(len2);
    }
    return vec3<f32>(0.0);
}

// The tile's culling data, computed once by invocation 0 and read by all (broadcast reads
// keep it out of every invocation's registers): world-space inward planes left, right, top,
// bottom, near, far; the 8 corners and their centre; the normal cone (axis, cos α); the
// occupied slices.
var<workgroup> tile_planes: array<vec4<f32>, 6>;
var<workgroup> tile_corners: array<vec3<f32>, 8>;
var<workgroup> tile_center: vec3<f32>;
var<workgroup> tile_cone: vec4<f32>;
var<workgroup> tile_slices: u32;
// Forward+: the near and far planes at the opaque depth bounds, and whether there are any.
var<workgroup> opaque_planes: array<vec4<f32>, 2>;
var<workgroup> opaque_present: bool;
// Set when a light of the current batch may face away: α is then computed (once per tile).
var<workgroup> need_alpha: u32;

// `tile_frustum`: the tile's planes at its depth bounds and its 8 corners (chapter 4 step 4).
fn tile_frustum(rect: vec4<u32>, near: f32, far: f32) {
    let s = edge_slopes(rect);
    let sides = side_planes(s);
    for (var i = 0u; i < 4u; i++) {
        tile_planes[i] = sides[i];
    }
    tile_planes[4] = world_plane(vec3<f32>(0.0, 0.0, -1.0), -near);
    tile_planes[5] = world_plane(vec3<f32>(0.0, 0.0, 1.0), far);
    var center = vec3<f32>(0.0);
    for (var i = 0u; i < 8u; i++) {
        let z = select(far, near, i < 4u);
        let sx = select(s.y, s.x, (i & 1u) == 0u);
        let sy = select(s.w, s.z, (i & 2u) == 0u);
        let corner = (frame.inv_view * vec4<f32>(sx * z, sy * z, -z, 1.0)).xyz;
        tile_corners[i] = corner;
        center += corner;
    }
    tile_center = center / 8.0;
}

fn above(i: u32, c: vec3<f32>, radius: f32) -> bool {
    let plane = tile_planes[i];
    return dot(plane.xyz, c) + plane.w >= -radius;
}

// `light_cone` (steps 5–6): axis from the corners' centre to the light and cos δ;
// w ≤ 0 when δ ≥ π/2 (no useful bound).
fn light_cone(light: vec3<f32>) -> vec4<f32> {
    let axis = normalize_or_zero(light - tile_center);
    var min_cos = 1.0;
    for (var i = 0u; i < 8u; i++) {
        min_cos = min(min_cos, dot(axis, normalize_or_zero(light - tile_corners[i])));
    }
    if all(axis == vec3<f32>(0.0)) {
        return vec4<f32>(axis, 0.0);
    }
    return vec4<f32>(axis, min(min_cos, 1.0));
}

fn sine(c: f32) -> f32 {
    return sqrt(max(1.0 - c * c, 0.0));
}

// `faces_away` (step 7): ω > π/2 + θ with θ = α + δ + ε, on cosines: θ < π/2 and
// cos ω < −sin θ.
fn faces_away(light_axis: vec3<f32>, cos_delta: f32) -> bool {
    let cos_alpha = tile_cone.w;
    let cos_e = cos(CONE_EPSILON);
    let sin_e = sin(CONE_EPSILON);
    let sin_alpha = sine(cos_alpha);
    let sin_delta = sine(cos_delta);
    let cos_beta = cos_delta * cos_e - sin_delta * sin_e;
    let sin_beta = sin_delta * cos_e + cos_delta * sin_e;
    let cos_theta = cos_alpha * cos_beta - sin_alpha * sin_beta;
    let sin_theta = sin_alpha * cos_beta + cos_alpha * sin_beta;
    return cos_theta > 0.0 && sin_theta >= 0.0 && dot(light_axis, tile_cone.xyz) < -sin_theta;
}

// `cull_light`: 0 = culled, else the slice mask of the list entry.
// The normal-cone part of `cull_light` is `cone_rejects`, run after α is known.
fn cull_light(light: Light) -> u32 {
    if light.kind == LIGHT_DIRECTIONAL {
        if METHOD == METHOD_FORWARD {
            return FORWARD_BLENDED | select(0u, FORWARD_OPAQUE, opaque_present);
        }
        if METHOD == METHOD_SLICES {
            return tile_slices;
        }
        return ALL_SLICES;
    }
    let c = light.position;
    let r = light.radius;
    if !(above(0u, c, r) && above(1u, c, r) && above(2u, c, r) && above(3u, c, r)) {
        return 0u;
    }
    if !(above(4u, c, r) && above(5u, c, r)) {
        return 0u;
    }
    if METHOD == METHOD_SLICES {
        let depth = view_depth(c);
        let near = depth - r;
        let far = depth + r;
        var mask = 0u;
        for (var k = 0u; k < SLICES; k++) {
            if far >= slice_starts[k] * (1.0 - SLICE_EPSILON) && near <= slice_starts[k + 1u] * (1.0 + SLICE_EPSILON) {
                mask |= 1u << k;
            }
        }
        return mask & tile_slices;
    }
    if METHOD == METHOD_FORWARD {
        let near = opaque_planes[0];
        let far = opaque_planes[1];
        let opaque = opaque_present && dot(near.xyz, c) + near.w >= -r && dot(far.xyz, c) + far.w >= -r;
        return FORWARD_BLENDED | select(0u, FORWARD_OPAQUE, opaque);
    }
    return ALL_SLICES;
}

// `in_back_half_space`: only a light behind the plane through the corners' centre across the
// normal axis can face away (ω > π/2); the others skip the light cone (and need no α).
fn in_back_half_space(light: Light) -> bool {
    if light.kind == LIGHT_DIRECTIONAL {
        return dot(-light.direction, tile_cone.xyz) < 0.0;
    }
    return dot(light.position - tile_center, tile_cone.xyz) < 0.0;
}

// Steps 5–7 for a light that passed the frustum test and lies in the back half-space.
fn cone_rejects(light: Light) -> bool {
    if light.kind == LIGHT_DIRECTIONAL {
        return faces_away(-light.direction, 1.0);
    }
    let cone = light_cone(light.position);
    return cone.w > 0.0 && faces_away(cone.xyz, cone.w);
}

// Brute force (`Method::BruteForce`): every light at every pixel, 8 × 8 invocations per
// workgroup — the thesis's traditional light accumulation (§1.3 step 3) as one compute pass.
@compute @workgroup_size(8, 8)
fn brute_force(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(linear_depth_texture);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    let s = load_sample(id.xy, size);
    var sum = Accumulated(vec3<f32>(0.0), vec3<f32>(0.0));
    if s.present {
        let p = lit_pixel(s, id.xy);
        for (var i = 0u; i < params.light_count; i++) {
            sum = add_light(sum, lights[i], p);
        }
    }
    store_sums(id.xy, sum);
}

// Shades the tile's pixels from the list's `n` entries (and records them, for tests), then
// empties the list; returns the entries of the tile so far.
fn flush(
    n: u32,
    total: u32,
    tile_index: u32,
    index: u32,
    samples: ptr<function, array<Sample, PIXELS>>,
    pixels: ptr<function, array<vec2<u32>, PIXELS>>,
    diffuse: ptr<function, array<vec3<f32>, PIXELS>>,
    specular: ptr<function, array<vec3<f32>, PIXELS>>,
) -> u32 {
    if params.record_lists != 0u {
        for (var j = index; j < n && total + j < params.list_stride; j += THREADS) {
            lists[tile_index * params.list_stride + total + j] = vec2<u32>(list_light[j], list_mask[j]);
        }
    }
    for (var p = 0u; p < PIXELS; p++) {
        if METHOD != METHOD_FORWARD && (*samples)[p].present {
            var pixel = lit_pixel((*samples)[p], (*pixels)[p]);
            if METHOD == METHOD_PREPASS {
                // Only the roughness of the material: F = 1 (a white metal).
                pixel.m = SurfaceMaterial(vec3<f32>(1.0), pixel.m.roughness, 1.0, 1.0);
            }
            let slice = slice_of(pixel.s.depth);
            var sum = Accumulated((*diffuse)[p], (*specular)[p]);
            for (var j = 0u; j < n; j++) {
                if ((list_mask[j] >> slice) & 1u) == 1u {
                    sum = add_light(sum, lights[list_light[j]], pixel);
                }
            }
            (*diffuse)[p] = sum.diffuse;
            (*specular)[p] = sum.specular;
        }
    }
    workgroupBarrier();
    if index == 0u {
        atomicStore(&list_count, 0u);
    }
    workgroupBarrier();
    return total + n;
}

@compute @workgroup_size(WG, WG)
fn shade_tiles(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(local_invocation_id) local: vec3<u32>,
    @builtin(local_invocation_index) index: u32,
) {
    let size = textureDimensions(linear_depth_texture);
    if index == 0u {
        atomicStore(&list_count, 0u);
    }

    // Pixels: depth bounds (positive view depths order like their bits), normal sum, slices.
    var samples: array<Sample, PIXELS>;
    var pixels: array<vec2<u32>, PIXELS>;
    var bounds = vec4<u32>(0x7f800000u, 0u, 0u, 0u);
    var normals = vec4<i32>(0);
    for (var i = 0u; i < PIXELS; i++) {
        pixels[i] = group.xy * TILE + local.xy + WG * vec2<u32>(i % PER_SIDE, i / PER_SIDE);
        samples[i] = load_sample(pixels[i], size);
        if samples[i].present {
            let bits = bitcast<u32>(samples[i].depth);
            bounds = vec4<u32>(min(bounds.x, bits), max(bounds.y, bits), bounds.z, 0u);
            if METHOD == METHOD_CONES {
                normals += vec4<i32>(vec3<i32>(round(samples[i].normal * NORMAL_QUANTUM)), 0);
            }
            if METHOD == METHOD_SLICES {
                bounds.z |= 1u << slice_of(samples[i].depth);
            }
        } else if METHOD == METHOD_FORWARD && all(pixels[i] < size) {
            // A pixel without a surface: blended surfaces there may lie at any depth.
            bounds.z = 1u;
        }
    }
    reduce_u[index] = bounds;
    reduce_i[index] = normals;
    workgroupBarrier();
    // Four-way steps (THREADS is 64 or 256, a power of 4): half the barriers of halving.
    for (var stride = THREADS / 4u; stride > 0u; stride >>= 2u) {
        if index < stride {
            var a = reduce_u[index];
            for (var k = 1u; k < 4u; k++) {
                let b = reduce_u[index + k * stride];
                a = vec4<u32>(min(a.x, b.x), max(a.y, b.y), a.z | b.z, 0u);
            }
            reduce_u[index] = a;
            if METHOD == METHOD_CONES {
                reduce_i[index] += reduce_i[index + stride] + reduce_i[index + 2u * stride]
                    + reduce_i[index + 3u * stride];
            }
        }
        workgroupBarrier();
    }
    let tile_bounds = workgroupUniformLoad(&reduce_u[0]);
    let sum = vec3<f32>(reduce_i[0].xyz);
    let axis = normalize_or_zero(sum);
    let opaque = tile_bounds.x <= tile_bounds.y;
    // A Forward+ tile without opaque surfaces may still show blended ones.
    let empty = !opaque && METHOD != METHOD_FORWARD;
    let origin = group.xy * TILE;
    if index == 0u {
        let rect = vec4<u32>(origin.x, min(origin.x + TILE, size.x), origin.y, min(origin.y + TILE, size.y));
        var near = bitcast<f32>(tile_bounds.x);
        var far = bitcast<f32>(tile_bounds.y);
        if METHOD == METHOD_FORWARD {
            opaque_present = opaque;
            if opaque {
                opaque_planes[0] = world_plane(vec3<f32>(0.0, 0.0, -1.0), -near);
                opaque_planes[1] = world_plane(vec3<f32>(0.0, 0.0, 1.0), far);
            }
            near = params.slice_near;
            far = select(far, slice_start(SLICES), !opaque || tile_bounds.z != 0u);
        }
        tile_frustum(rect, near, far);
        // cos α = −1 until step 3 runs (lazily, below).
        tile_cone = vec4<f32>(axis, -1.0);
        tile_slices = tile_bounds.z;
        need_alpha = 0u;
    }
    if METHOD == METHOD_SLICES && index <= SLICES {
        slice_starts[index] = slice_start(index);
    }
    workgroupBarrier();
    let tile_index = group.y * params.tiles_x + group.x;

    var diffuse: array<vec3<f32>, PIXELS>;
    var specular: array<vec3<f32>, PIXELS>;
    var total = 0u;
    if !empty {
        // Candidates in batches of THREADS: every light, or (LIGHT_TREE) the lights of the
        // groups that meet the tile frustum, found a round of THREADS groups at a time. The
        // pixels are shaded whenever the next batch could overflow the list, and at the end.
        var alpha_ready = false;
        for (var r = 0u; r < search_rounds(); r++) {
            var candidates = params.light_count;
            if LIGHT_TREE {
                let g = begin_round(r, index);
                if g != NO_LIGHT {
                    let sphere = group_sphere(g);
                    let c = sphere.xyz;
                    let radius = sphere.w;
                    if above(0u, c, radius) && above(1u, c, radius) && above(2u, c, radius)
                        && above(3u, c, radius) && above(4u, c, radius) && above(5u, c, radius) {
                        pass_group(g);
                    }
                }
                candidates = end_round(index);
            }
            let batches = (candidates + THREADS - 1u) / THREADS;
            for (var b = 0u; b < batches; b++) {
                let i = candidate_light(b * THREADS + index);
                let valid = i != NO_LIGHT;
                var mask = 0u;
                var pending = false;
                if valid {
                    mask = cull_light(lights[i]);
                    if METHOD == METHOD_CONES && mask != 0u && in_back_half_space(lights[i]) {
                        pending = true;
                        need_alpha = 1u;
                    }
                }
                if METHOD == METHOD_CONES {
                    // Step 3, the cone angle α from the least cosine between the axis and a
                    // normal (a second reduction), only once some light may face away.
                    if !alpha_ready && workgroupUniformLoad(&need_alpha) != 0u {
                        var least = 0x7fffffff;
                        for (var p = 0u; p < PIXELS; p++) {
                            if samples[p].present {
                                least = min(least, i32(floor(dot(axis, samples[p].normal) * COSINE_QUANTUM)) - 1);
                            }
                        }
                        reduce_i[index].w = least;
                        workgroupBarrier();
                        for (var stride = THREADS / 4u; stride > 0u; stride >>= 2u) {
                            if index < stride {
                                reduce_i[index].w = min(
                                    min(reduce_i[index].w, reduce_i[index + stride].w),
                                    min(reduce_i[index + 2u * stride].w, reduce_i[index + 3u * stride].w),
                                );
                            }
                            workgroupBarrier();
                        }
                        if index == 0u && dot(sum, sum) >= 1.0 {
                            tile_cone.w = clamp(f32(reduce_i[0].w) / COSINE_QUANTUM, -1.0, 1.0);
                        }
                        workgroupBarrier();
                        alpha_ready = true;
                    }
                    if pending && cone_rejects(lights[i]) {
                        mask = 0u;
                    }
                }
                if mask != 0u {
                    let slot = atomicAdd(&list_count, 1u);
                    list_light[slot] = i;
                    list_mask[slot] = mask;
                }
                workgroupBarrier();
                if index == 0u {
                    list_size = atomicLoad(&list_count);
                }
                let n = workgroupUniformLoad(&list_size);
                if n + THREADS > CAPACITY {
                    total = flush(n, total, tile_index, index, &samples, &pixels, &diffuse, &specular);
                }
            }
        }
        if index == 0u {
            list_size = atomicLoad(&list_count);
        }
        total = flush(workgroupUniformLoad(&list_size), total, tile_index, index, &samples, &pixels, &diffuse, &specular);
    }
    for (var p = 0u; p < PIXELS; p++) {
        if METHOD == METHOD_PREPASS && pixels[p].x < size.x && pixels[p].y < size.y {
            let mono = luminance(specular[p]);
            textureStore(diffuse_out, pixels[p], vec4<f32>(diffuse[p], mono));
            if params.record_lists != 0u {
                textureStore(specular_out, pixels[p], vec4<f32>(vec3<f32>(mono), 0.0));
            }
        } else if METHOD != METHOD_FORWARD && pixels[p].x < size.x && pixels[p].y < size.y {
            store_sums(pixels[p], Accumulated(diffuse[p], specular[p]));
        }
    }
    if index == 0u {
        counts[tile_index] = total;
    }
}
