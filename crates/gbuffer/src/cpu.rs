//! CPU reference G-buffer creation: the specification the GPU pass (`gbuffer.wgsl`) is
//! tested against.
//!
//! A sort-middle rasterizer parallel over screen tiles (rayon):
//! 1. vertex stage: world → clip (`vs_main`);
//! 2. clipping in homogeneous space against the near and far planes and a guard band
//!    (|x|, |y| ≤ 4w), fan-triangulated;
//! 3. setup: viewport transform, snapping to 1/256 pixel (8 sub-pixel bits, as GPUs do),
//!    integer edge functions; zero-area triangles are dropped; no face culling;
//! 4. binning into 32 × 32 pixel tiles, in submission order;
//! 5. per tile: coverage at pixel centres with the top-left fill rule, back faces of one-
//!    sided materials culled, perspective-correct attribute interpolation, screen-linear
//!    depth, depth test `Less`, then the fragment stage (`fs_main`): the material evaluated
//!    by [`scene::Material::evaluate`] with the texture coordinates' derivatives taken as
//!    `dpdxFine`/`dpdyFine` take them (differences across the 2 × 2 quad, from the
//!    triangle's interpolation extrapolated to the neighbour pixel), textures filtered through
//!    their mip chains with anisotropy; alpha-tested fragments discarded; octahedral normal,
//!    albedo, packed material, emission and occlusion (half floats).

use glam::{Vec2, Vec3, Vec4};
use rayon::prelude::*;
use scene::{Camera, Material, Scene, SceneTextures, SurfaceAttributes};

use crate::{
    Frame, GBuffer, GBufferError, Image, NO_MATERIAL, TextureOptions, normal::pack_octahedral,
    pack_material, to_half,
};

/// Side of a screen tile in pixels.
pub const TILE: u32 = 32;
/// Sub-pixel precision: positions snap to 1/`SUBPIXEL` pixel.
pub const SUBPIXEL: i64 = 256;
/// Guard band in units of w: triangles are clipped to |x|, |y| ≤ GUARD_BAND · w.
const GUARD_BAND: f32 = 4.0;

/// The G-buffer plus, per pixel, the index of the triangle that wrote it (triangles numbered
/// in submission order over all meshes; `u32::MAX` where none did). Tests use the ids to find
/// silhouette and triangle edges.
pub struct Rasterized {
    /// The G-buffer.
    pub gbuffer: GBuffer,
    /// Triangle id per pixel.
    pub triangle_id: Image<u32>,
}

/// The attributes `vs_main` passes on: normal (3), texture-coordinate sets 0 and 1 (2 + 2),
/// tangent (4), colour (4).
const ATTRIBUTES: usize = 15;

#[derive(Clone, Copy)]
struct ClipVertex {
    clip: Vec4,
    attributes: [f32; ATTRIBUTES],
}

impl ClipVertex {
    fn lerp(self, other: Self, t: f32) -> Self {
        Self {
            clip: self.clip.lerp(other.clip, t),
            attributes: std::array::from_fn(|k| {
                self.attributes[k] + (other.attributes[k] - self.attributes[k]) * t
            }),
        }
    }
}

/// Interpolated attributes at a point of a triangle.
struct Varyings {
    normal: Vec3,
    uv: [Vec2; 2],
    tangent: Vec4,
    color: Vec4,
}

impl Varyings {
    fn new(a: &[f32; ATTRIBUTES]) -> Self {
        Self {
            normal: Vec3::new(a[0], a[1], a[2]),
            uv: [Vec2::new(a[3], a[4]), Vec2::new(a[5], a[6])],
            tangent: Vec4::new(a[7], a[8], a[9], a[10]),
            color: Vec4::new(a[11], a[12], a[13], a[14]),
        }
    }
}

/// A triangle ready for scan conversion.
struct SetupTriangle {
    id: u32,
    material: u32,
    /// Snapped framebuffer positions in 1/SUBPIXEL pixels, y down.
    v: [[i64; 3]; 2],
    /// Unsnapped framebuffer positions (pixels), for attribute interpolation.
    screen: [Vec2; 3],
    /// 1 where the edge opposite vertex i is a top or left edge, else 0.
    top_left: [i64; 3],
    z: [f32; 3],
    inv_w: [f32; 3],
    attributes_over_w: [[f32; ATTRIBUTES]; 3],
    /// The triangle's geometric normal (not unit) on the side the camera sees.
    towards_camera: Vec3,
    /// Inclusive pixel bounds, clamped to the image.
    bounds: [u32; 4],
}

/// Sutherland–Hodgman clipping against `dot(plane, clip) >= 0`.
fn clip_polygon(poly: Vec<ClipVertex>, plane: Vec4) -> Vec<ClipVertex> {
    let mut out = Vec::with_capacity(poly.len() + 2);
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        let (da, db) = (plane.dot(a.clip), plane.dot(b.clip));
        if da >= 0.0 {
            out.push(a);
        }
        if (da >= 0.0) != (db >= 0.0) {
            out.push(a.lerp(b, da / (da - db)));
        }
    }
    out
}

/// Edge function of a→b at p (fixed point); positive inside a positively oriented triangle.
fn edge(a: [i64; 2], b: [i64; 2], p: [i64; 2]) -> i64 {
    (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])
}

/// Top-left rule for a positively oriented triangle in y-down coordinates: left edges go
/// up (dy < 0), top edges are horizontal going right.
fn is_top_left(a: [i64; 2], b: [i64; 2]) -> bool {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    dy < 0 || (dy == 0 && dx > 0)
}

/// `geometric` is the world-space normal of the counter-clockwise winding (not unit); a
/// triangle whose back the camera sees is dropped where `cull_back`.
fn setup(
    verts: [ClipVertex; 3],
    (geometric, cull_back): (Vec3, bool),
    id: u32,
    material: u32,
    width: u32,
    height: u32,
) -> Option<SetupTriangle> {
    let (w, h) = (width as f32, height as f32);
    let mut fixed = [[0i64; 2]; 3];
    let mut screen = [Vec2::ZERO; 3];
    for ((f, s), v) in fixed.iter_mut().zip(&mut screen).zip(&verts) {
        let ndc = v.clip.truncate() / v.clip.w;
        *s = Vec2::new(ndc.x * (w * 0.5) + w * 0.5, -ndc.y * (h * 0.5) + h * 0.5);
        *f = [
            (s.x * SUBPIXEL as f32).round() as i64,
            (s.y * SUBPIXEL as f32).round() as i64,
        ];
    }
    let mut order = [0usize, 1, 2];
    let area = edge(fixed[0], fixed[1], fixed[2]);
    // Counter-clockwise on screen (y down: a negative area) is the winding's front.
    if area == 0 || (cull_back && area > 0) {
        return None;
    }
    if area < 0 {
        order = [0, 2, 1];
    }
    let v = order.map(|i| fixed[i]);
    let vs = order.map(|i| verts[i]);
    let top_left = [0, 1, 2].map(|i| i64::from(is_top_left(v[(i + 1) % 3], v[(i + 2) % 3])));
    let (min_x, max_x) = (v.iter().map(|p| p[0]).min()?, v.iter().map(|p| p[0]).max()?);
    let (min_y, max_y) = (v.iter().map(|p| p[1]).min()?, v.iter().map(|p| p[1]).max()?);
    let half = SUBPIXEL / 2;
    let x0 = (min_x - half + SUBPIXEL - 1).div_euclid(SUBPIXEL).max(0);
    let y0 = (min_y - half + SUBPIXEL - 1).div_euclid(SUBPIXEL).max(0);
    let x1 = (max_x - half)
        .div_euclid(SUBPIXEL)
        .min(i64::from(width) - 1);
    let y1 = (max_y - half)
        .div_euclid(SUBPIXEL)
        .min(i64::from(height) - 1);
    if x0 > x1 || y0 > y1 {
        return None;
    }
    let inv_w = vs.map(|v| 1.0 / v.clip.w);
    Some(SetupTriangle {
        id,
        material,
        v: [v.map(|p| p[0]), v.map(|p| p[1])],
        screen: order.map(|i| screen[i]),
        top_left,
        z: vs.map(|v| v.clip.z / v.clip.w),
        inv_w,
        attributes_over_w: [0, 1, 2].map(|i| vs[i].attributes.map(|a| a * inv_w[i])),
        // Counter-clockwise on screen (y down): the camera sees the winding's front.
        towards_camera: if area < 0 { geometric } else { -geometric },
        bounds: [x0 as u32, y0 as u32, x1 as u32, y1 as u32],
    })
}

/// What the fragment stage reads besides the varyings.
struct Shading<'a> {
    materials: &'a [Material],
    textures: &'a SceneTextures,
    max_anisotropy: u32,
}

/// What a fragment writes: albedo, normal word, material word, emission and occlusion.
type Fragment = ([u8; 4], u32, u32, [f32; 4]);

/// Fragment stage (`fs_main`), or `None` where alpha discards the fragment at `pixel`.
fn fragment(
    shading: &Shading,
    material: u32,
    at: &SurfaceAttributes,
    pixel: (u32, u32),
) -> Option<Fragment> {
    let m = &shading.materials[material as usize];
    let s = m.evaluate(shading.textures, at, shading.max_anisotropy);
    if !m
        .alpha_mode
        .keeps(s.alpha, scene::dither_threshold(pixel.0, pixel.1))
    {
        return None;
    }
    let unorm = |c: f32| (c * 255.0).round() as u8;
    let albedo = [
        unorm(s.albedo.x),
        unorm(s.albedo.y),
        unorm(s.albedo.z),
        unorm(m.specular.clamp(0.0, 1.0)),
    ];
    let e = s.emission.min(Vec3::splat(HALF_MAX));
    Some((
        albedo,
        pack_octahedral(s.normal),
        pack_material(s.roughness, s.metallic, material),
        [e.x, e.y, e.z, s.occlusion].map(to_half),
    ))
}

/// The largest finite half float (emission is clamped to it).
const HALF_MAX: f32 = 65504.0;

struct Tile {
    x: u32,
    y: u32,
    w: u32,
    h: u32,
    depth: Vec<f32>,
    linear_depth: Vec<f32>,
    normal: Vec<u32>,
    albedo: Vec<[u8; 4]>,
    material: Vec<u32>,
    emission: Vec<[f32; 4]>,
    triangle: Vec<u32>,
}

fn raster_tile(tile: &mut Tile, triangles: &[SetupTriangle], bin: &[u32], shading: &Shading) {
    for &t in bin {
        let tri = &triangles[t as usize];
        let [bx0, by0, bx1, by1] = tri.bounds;
        let (x0, x1) = (bx0.max(tile.x), bx1.min(tile.x + tile.w - 1));
        let (y0, y1) = (by0.max(tile.y), by1.min(tile.y + tile.h - 1));
        let v = |i: usize| [tri.v[0][i], tri.v[1][i]];
        let s = &tri.screen;
        let edge_f =
            |a: Vec2, b: Vec2, p: Vec2| (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x);
        let area = edge_f(s[0], s[1], s[2]);
        // Barycentrics of a point (of the unsnapped positions).
        let bary = |c: Vec2| {
            [
                edge_f(s[1], s[2], c),
                edge_f(s[2], s[0], c),
                edge_f(s[0], s[1], c),
            ]
            .map(|e| e / area)
        };
        // Perspective-correct weights at a point — barycentrics and the view depth w —
        // and attribute k there (the plane equations extrapolate beyond the triangle,
        // as for the quad's helper pixels).
        let view_depth =
            |l: [f32; 3]| 1.0 / (l[0] * tri.inv_w[0] + l[1] * tri.inv_w[1] + l[2] * tri.inv_w[2]);
        let weights = |c: Vec2| {
            let l = bary(c);
            (l, view_depth(l))
        };
        let attribute = |(l, w): ([f32; 3], f32), k: usize| {
            (0..3)
                .map(|v| tri.attributes_over_w[v][k] * l[v])
                .sum::<f32>()
                * w
        };
        for py in y0..=y1 {
            for px in x0..=x1 {
                let p = [
                    i64::from(px) * SUBPIXEL + SUBPIXEL / 2,
                    i64::from(py) * SUBPIXEL + SUBPIXEL / 2,
                ];
                let e = [
                    edge(v(1), v(2), p),
                    edge(v(2), v(0), p),
                    edge(v(0), v(1), p),
                ];
                if (0..3).any(|i| e[i] + tri.top_left[i] <= 0) {
                    continue;
                }
                // Coverage is decided on snapped positions; attributes are interpolated with
                // barycentrics of the unsnapped positions, as the GPU's plane equations are.
                let c = Vec2::new(px as f32 + 0.5, py as f32 + 0.5);
                let l = bary(c);
                let z = l[0] * tri.z[0] + l[1] * tri.z[1] + l[2] * tri.z[2];
                let i = ((py - tile.y) * tile.w + (px - tile.x)) as usize;
                if !(0.0..=1.0).contains(&z) || z >= tile.depth[i] {
                    continue;
                }
                let w = view_depth(l);
                let here = Varyings::new(&std::array::from_fn(|k| attribute((l, w), k)));
                // `dpdxFine`/`dpdyFine`: the difference to the other pixel of the quad's row
                // or column, taken left to right and top to bottom; only the texture
                // coordinates (attributes 3..7) are needed there.
                let (step_x, step_y) = (
                    if px % 2 == 0 { 1.0 } else { -1.0 },
                    if py % 2 == 0 { 1.0 } else { -1.0 },
                );
                let across = |step: Vec2, sign: f32| -> [Vec2; 2] {
                    let at = weights(c + step);
                    let uv = |k| Vec2::new(attribute(at, k), attribute(at, k + 1));
                    let there = [uv(3), uv(5)];
                    [0, 1].map(|k| (there[k] - here.uv[k]) * sign)
                };
                // Shaded from the side of the plane the camera sees (`facing_normal`).
                let vertex_normal = here.normal.normalize_or(Vec3::Z);
                let facing = tri.towards_camera.normalize_or(Vec3::Z);
                let at = SurfaceAttributes {
                    uv: here.uv,
                    uv_dx: across(Vec2::new(step_x, 0.0), step_x),
                    uv_dy: across(Vec2::new(0.0, step_y), step_y),
                    normal: scene::facing_shading_normal(vertex_normal, facing),
                    back_face: vertex_normal.dot(facing) < 0.0,
                    tangent: here.tangent,
                    color: here.color,
                };
                let Some((albedo, n, m, emission)) = fragment(shading, tri.material, &at, (px, py))
                else {
                    continue;
                };
                tile.depth[i] = z;
                tile.linear_depth[i] = w;
                tile.normal[i] = n;
                tile.albedo[i] = albedo;
                tile.material[i] = m;
                tile.emission[i] = emission;
                tile.triangle[i] = tri.id;
            }
        }
    }
}

/// Rasterizes `scene` seen by `camera` into a `width × height` G-buffer (textures filtered
/// with the default [`TextureOptions`]).
pub fn rasterize(
    scene: &Scene,
    camera: &Camera,
    width: u32,
    height: u32,
) -> Result<Rasterized, GBufferError> {
    rasterize_with(scene, camera, (width, height), &TextureOptions::default())
}

/// [`rasterize`] at `(width, height)` with textures filtered as `options` say.
pub fn rasterize_with(
    scene: &Scene,
    camera: &Camera,
    (width, height): (u32, u32),
    options: &TextureOptions,
) -> Result<Rasterized, GBufferError> {
    options.validate()?;
    crate::validate_size(width, height)?;
    crate::validate_camera(camera)?;
    crate::validate_scene(scene)?;
    let frame = Frame::new(camera, width, height);

    // Vertex stage and primitive assembly, numbered in submission order.
    let mut first_id = Vec::with_capacity(scene.meshes.len());
    let mut next = 0u32;
    for m in &scene.meshes {
        first_id.push(next);
        next += m.triangle_count() as u32;
    }
    let planes = [
        Vec4::new(0.0, 0.0, 1.0, 0.0),         // z >= 0 (near)
        Vec4::new(0.0, 0.0, -1.0, 1.0),        // z <= w (far)
        Vec4::new(1.0, 0.0, 0.0, GUARD_BAND),  // x >= -g w
        Vec4::new(-1.0, 0.0, 0.0, GUARD_BAND), // x <= g w
        Vec4::new(0.0, 1.0, 0.0, GUARD_BAND),  // y >= -g w
        Vec4::new(0.0, -1.0, 0.0, GUARD_BAND), // y <= g w
    ];
    let triangles: Vec<SetupTriangle> = scene
        .meshes
        .par_iter()
        .zip(first_id.par_iter())
        .flat_map_iter(|(mesh, &first)| {
            let clip: Vec<Vec4> = mesh
                .positions
                .iter()
                .map(|p| frame.view_proj * p.extend(1.0))
                .collect();
            mesh.indices
                .chunks_exact(3)
                .enumerate()
                .flat_map(move |(t, idx)| {
                    let vert = |i: u32| {
                        let i = i as usize;
                        let n = mesh.normals[i];
                        let uv0 = mesh.uvs[i];
                        let uv1 = mesh.uvs1.get(i).copied().unwrap_or(Vec2::ZERO);
                        let t = mesh.tangents.get(i).copied().unwrap_or(Vec4::ZERO);
                        let c = mesh.colors.get(i).copied().unwrap_or(Vec4::ONE);
                        ClipVertex {
                            clip: clip[i],
                            attributes: [
                                n.x, n.y, n.z, uv0.x, uv0.y, uv1.x, uv1.y, t.x, t.y, t.z, t.w, c.x,
                                c.y, c.z, c.w,
                            ],
                        }
                    };
                    let mut poly = vec![vert(idx[0]), vert(idx[1]), vert(idx[2])];
                    let inside = |v: &ClipVertex| planes.iter().all(|p| p.dot(v.clip) >= 0.0);
                    if !poly.iter().all(inside) {
                        for p in planes {
                            poly = clip_polygon(poly, p);
                            if poly.len() < 3 {
                                break;
                            }
                        }
                    }
                    let id = first + t as u32;
                    let [p0, p1, p2] = [0, 1, 2].map(|k| mesh.positions[idx[k] as usize]);
                    let geometric = (p1 - p0).cross(p2 - p0);
                    let cull_back = !scene.materials[mesh.material as usize].double_sided;
                    (1..poly.len().saturating_sub(1))
                        .filter_map(|k| {
                            setup(
                                [poly[0], poly[k], poly[k + 1]],
                                (geometric, cull_back),
                                id,
                                mesh.material,
                                width,
                                height,
                            )
                        })
                        .collect::<Vec<_>>()
                })
        })
        .collect();

    // Binning.
    let (tiles_x, tiles_y) = (width.div_ceil(TILE), height.div_ceil(TILE));
    let mut bins = vec![Vec::<u32>::new(); (tiles_x * tiles_y) as usize];
    for (i, t) in triangles.iter().enumerate() {
        let [x0, y0, x1, y1] = t.bounds;
        for ty in y0 / TILE..=y1 / TILE {
            for tx in x0 / TILE..=x1 / TILE {
                bins[(ty * tiles_x + tx) as usize].push(i as u32);
            }
        }
    }

    let textures = SceneTextures::new(scene, true);
    let shading = Shading {
        materials: &scene.materials,
        textures: &textures,
        max_anisotropy: options.max_anisotropy,
    };

    let tiles: Vec<Tile> = bins
        .par_iter()
        .enumerate()
        .map(|(i, bin)| {
            let (x, y) = ((i as u32 % tiles_x) * TILE, (i as u32 / tiles_x) * TILE);
            let (w, h) = (TILE.min(width - x), TILE.min(height - y));
            let n = (w * h) as usize;
            let mut tile = Tile {
                x,
                y,
                w,
                h,
                depth: vec![1.0; n],
                linear_depth: vec![0.0; n],
                normal: vec![0; n],
                albedo: vec![[0; 4]; n],
                material: vec![NO_MATERIAL; n],
                emission: vec![[0.0; 4]; n],
                triangle: vec![u32::MAX; n],
            };
            raster_tile(&mut tile, &triangles, bin, &shading);
            tile
        })
        .collect();

    let mut gbuffer = GBuffer::cleared(width, height);
    let mut triangle_id = Image::filled(width, height, u32::MAX);
    for t in &tiles {
        for ly in 0..t.h {
            for lx in 0..t.w {
                let (i, x, y) = ((ly * t.w + lx) as usize, t.x + lx, t.y + ly);
                gbuffer.depth.set(x, y, t.depth[i]);
                gbuffer.linear_depth.set(x, y, t.linear_depth[i]);
                gbuffer.normal.set(x, y, t.normal[i]);
                gbuffer.albedo.set(x, y, t.albedo[i]);
                gbuffer.material.set(x, y, t.material[i]);
                gbuffer.emission.set(x, y, t.emission[i]);
                triangle_id.set(x, y, t.triangle[i]);
            }
        }
    }
    Ok(Rasterized {
        gbuffer,
        triangle_id,
    })
}
