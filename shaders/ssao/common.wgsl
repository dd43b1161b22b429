// #import gbuffer/frame.wgsl
// #import gbuffer/normal_encoding.wgsl
// What the screen-space estimators share (`ssao::cpu`, function for function): parameters,
// bindings and the G-buffer's surfaces on the estimator's grid.

struct Params {
    // The estimator's grid: the image, or at half resolution the pixels (2x, 2y).
    width: u32,
    height: u32,
    // Kernel side k (odd).
    size: u32,
    radius: f32,
    // The image.
    image_width: u32,
    image_height: u32,
    // Grid point (x, y) is pixel (x, y) · scale (1, or 2 at half resolution).
    scale: u32,
    // 1: separable, with the smoothing after pass 2.
    smoothing: u32,
};

@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<uniform> params: Params;
@group(0) @binding(2) var linear_depth_tex: texture_2d<f32>;
@group(0) @binding(3) var normal_tex: texture_2d<u32>;
// The per-pixel frame directions u of the k × k interleaving tile (`cpu::frame_directions`).
@group(0) @binding(4) var<storage, read> directions: array<vec2<f32>>;
// Separable: pass 1's line values (later the smoothing's x pass), their weights in pass 2, and
// pass 2's values — 3 × grid points; else unused.
@group(0) @binding(5) var<storage, read_write> first: array<f32>;
// The accessibility A per pixel.
@group(0) @binding(6) var<storage, read_write> accessibility_out: array<f32>;
// At half resolution: A per grid point, which `upsample` spreads to the pixels; else unused.
@group(0) @binding(7) var<storage, read_write> coarse: array<f32>;

// Workgroup tiles for the k × k kernels (a speed-up; the results are the untiled ones): a
// 16 × 16 workgroup first loads the linear depth of its grid points and an apron of
// APRON = k/2 points into workgroup memory, and the samples read them there. The array holds
// APRON up to 10 (k ≤ 21); wider kernels read textures. The separable passes read textures:
// the H200 measured them faster without the array, which takes its room from the L1 cache
// (`ssao::gpu` compiles them with TILE_CAPACITY = 1).
override TILED: bool = false;
override APRON: i32 = 10;
const TILE: i32 = 16;
override TILE_SIDE: i32 = TILE + 2 * APRON;
override TILE_ENTRIES: u32 = u32(TILE_SIDE * TILE_SIDE);
const TILE_CAPACITY: u32 = 1296u;
var<workgroup> depth_tile: array<f32, TILE_CAPACITY>;
// The grid point of the tile's entry 0.
var<private> tile_origin: vec2<i32>;
// The view ray of pixel (x, y) is ray_origin + x·ray_dx + y·ray_dy (the frame's rays are
// affine in the pixel; `cpu` computes them alike).
var<private> ray_origin: vec3<f32>;
var<private> ray_dx: vec3<f32>;
var<private> ray_dy: vec3<f32>;

fn init_rays() {
    ray_origin = view_ray(frame, vec2<u32>(0u, 0u));
    ray_dx = view_ray(frame, vec2<u32>(1u, 0u)) - ray_origin;
    ray_dy = view_ray(frame, vec2<u32>(0u, 1u)) - ray_origin;
}

fn pixel_ray(pixel: vec2<i32>) -> vec3<f32> {
    let p = vec2<f32>(pixel);
    return ray_origin + p.x * ray_dx + p.y * ray_dy;
}

fn in_bounds(pixel: vec2<i32>) -> bool {
    return all(pixel >= vec2<i32>(0)) && pixel.x < i32(params.image_width) && pixel.y < i32(params.image_height);
}

fn grid_pixel(x: i32, y: i32) -> vec2<i32> {
    return vec2<i32>(x, y) * i32(params.scale);
}

// The linear depth at a pixel from the texture; 0 outside the image or where nothing was drawn.
fn pixel_depth(pixel: vec2<i32>) -> f32 {
    if !in_bounds(pixel) {
        return 0.0;
    }
    return max(textureLoad(linear_depth_tex, vec2<u32>(pixel), 0).r, 0.0);
}

fn pixel_normal(pixel: vec2<i32>) -> vec3<f32> {
    return decode_octahedral_snorm(unpack2x16snorm(textureLoad(normal_tex, vec2<u32>(pixel), 0).r));
}

fn tile_entry(x: i32, y: i32) -> u32 {
    let o = vec2<i32>(x, y) - tile_origin;
    return u32(o.y * TILE_SIDE + o.x);
}

// Sets up the rays and fills the tiles of workgroup `group` (every invocation calls it, before
// any return).
fn load_tiles(group: vec3<u32>, local_index: u32) {
    init_rays();
    if !TILED {
        return;
    }
    tile_origin = vec2<i32>(group.xy) * TILE - APRON;
    for (var i = local_index; i < TILE_ENTRIES; i += u32(TILE * TILE)) {
        let q = tile_origin + vec2<i32>(i32(i) % TILE_SIDE, i32(i) / TILE_SIDE);
        let pixel = grid_pixel(q.x, q.y);
        depth_tile[i] = pixel_depth(pixel);
    }
    workgroupBarrier();
}

struct Surface {
    position: vec3<f32>,
    normal: vec3<f32>,
    depth: f32,
    // The view ray at unit view depth.
    ray: vec3<f32>,
    present: bool,
};

// The linear depth at grid point (x, y); 0 outside the grid or where nothing was drawn.
fn depth_at(x: i32, y: i32) -> f32 {
    if TILED {
        return depth_tile[tile_entry(x, y)];
    }
    return pixel_depth(grid_pixel(x, y));
}

fn ray_at(x: i32, y: i32) -> vec3<f32> {
    return pixel_ray(grid_pixel(x, y));
}

// The surface at a pixel whose linear depth is `depth` (0: none).
fn surface_of(pixel: vec2<i32>, depth: f32) -> Surface {
    var s: Surface;
    s.depth = depth;
    s.present = depth > 0.0;
    if s.present {
        s.ray = pixel_ray(pixel);
        s.position = frame.eye.xyz + s.ray * depth;
        s.normal = pixel_normal(pixel);
    }
    return s;
}

// The surface at a pixel, from the textures.
fn pixel_surface(pixel: vec2<i32>) -> Surface {
    return surface_of(pixel, pixel_depth(pixel));
}

// The surface at grid point (x, y) (its depth from the tile when tiled).
fn surface_at(x: i32, y: i32) -> Surface {
    return surface_of(grid_pixel(x, y), depth_at(x, y));
}

// The pixel t steps along `direction` from (x, y), rounded half up.
fn step_along(x: i32, y: i32, direction: vec2<f32>, t: i32) -> vec2<i32> {
    let o = floor(direction * f32(t) + 0.5);
    return vec2<i32>(x + i32(o.x), y + i32(o.y));
}

// Grid point (x, y)'s entry of the k × k interleaving tile.
fn pattern_index(x: i32, y: i32) -> u32 {
    let k = i32(params.size);
    return u32(((x % k) + k) % k + k * (((y % k) + k) % k));
}

fn in_grid(id: vec3<u32>) -> bool {
    return id.x < params.width && id.y < params.height;
}

fn grid_index(id: vec3<u32>) -> u32 {
    return id.y * params.width + id.x;
}

// Stores the A of grid point `id`: the pixel's, or at half resolution the grid point's.
fn store(id: vec3<u32>, a: f32) {
    if params.scale == 1u {
        accessibility_out[grid_index(id)] = a;
    } else {
        coarse[grid_index(id)] = a;
    }
}
