//! CPU reference (rayon over tiles), mirroring `shaders/tiled-shading/tiled.wgsl` and
//! its `brute_force` entry point step for step: [`tile_bounds`] (depth bounds, normal cone, occupied
//! slices), [`tile_frustum`] (planes and the 8 corners), [`cull_light`] (sphere–frustum, [`light_cone`] and
//! [`faces_away`]: the normal-cone test of thesis chapter 4, cluster slices), [`shade`] (lists, then shading).

use gbuffer::{Frame, GBuffer, Image, normal::unpack_octahedral, position, unpack_material};
use glam::{IVec3, Vec3, Vec4, Vec4Swizzles};
use rayon::prelude::*;
use scene::Camera;

use crate::lighting::Surface;
use crate::shadows::{ShadowMaps, shade_shadowed};
use crate::{
    CLUSTER_SLICES, GpuLight, LIGHT_DIRECTIONAL, Method, ShadingConfig, ShadingError, Slicing,
};

/// Scale of the quantized normals summed for a tile's cone axis (exact integer sums, so the
/// axis does not depend on the order of summation; thesis §4.1 sums ×256 with atomics).
pub const NORMAL_QUANTUM: f32 = 32768.0;
/// Scale of the quantized cosines whose minimum gives the cone angle α (rounded down).
pub const COSINE_QUANTUM: f32 = 1_048_576.0;
/// Angle (radians) added to `π/2 + α + δ` before a light is rejected by the normal cone,
/// covering float rounding in α, δ and ω so the test stays conservative.
pub const CONE_EPSILON: f32 = 1e-3;
/// Relative widening of a cluster slice's depth interval (rounding of `ln` / `exp`).
pub const SLICE_EPSILON: f32 = 1e-5;
/// List entry mask of methods without slices.
pub const ALL_SLICES: u32 = u32::MAX;
/// A [`Method::ForwardPlus`] list entry's bit: the light meets the tile's opaque depth bounds
/// (the opaque surfaces are shaded from these entries).
pub const FORWARD_OPAQUE: u32 = 1;
/// A [`Method::ForwardPlus`] list entry's bit: the light meets the depths from the near plane to
/// the tile's far bound (every entry has it; blended surfaces are shaded from all).
pub const FORWARD_BLENDED: u32 = 2;

/// One G-buffer pixel as the light accumulation reads it.
#[derive(Clone, Copy, Debug)]
pub struct Sample {
    /// World position.
    pub position: Vec3,
    /// View depth (positive, along −Z of the view).
    pub depth: f32,
    /// World normal.
    pub normal: Vec3,
}

/// The G-buffer sample at `(x, y)` (position from the view ray and the linear depth, thesis
/// §3.6), `None` where no surface is.
pub fn sample(gb: &GBuffer, frame: &Frame, x: u32, y: u32) -> Option<Sample> {
    let depth = gb.linear_depth.get(x, y);
    if depth <= 0.0 {
        return None;
    }
    Some(Sample {
        position: position::from_view_ray(frame, x, y, depth),
        depth,
        normal: unpack_octahedral(gb.normal.get(x, y)),
    })
}

/// What a tile's pixels span (thesis §2.4.1 step 2 and chapter 4 steps 2–3).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TileBounds {
    /// Smallest view depth of the tile's surface pixels (`+∞` when it has none).
    pub min_depth: f32,
    /// Largest view depth (`−∞` when none).
    pub max_depth: f32,
    /// Sum of the quantized normals (×[`NORMAL_QUANTUM`], rounded).
    pub normal_sum: IVec3,
    /// Minimum over pixels of `⌊cos(axis, n)·Q⌋ − 1` (Q = [`COSINE_QUANTUM`]); `cos α` = this / Q.
    pub min_cosine: i32,
    /// Bit k set when a pixel lies in cluster slice k ([`Method::TiledSlices`],
    /// [`Method::Clustered`]).
    pub slices: u32,
    /// Per slice, the least and greatest view depth of the tile's pixels in it (`[+∞, −∞]`
    /// when none): the explicit depth bounds of [`Method::Clustered`]'s clusters.
    pub cluster_depths: [[f32; 2]; CLUSTER_SLICES as usize],
}

impl TileBounds {
    /// True when no pixel of the tile has a surface.
    pub fn is_empty(&self) -> bool {
        self.min_depth > self.max_depth
    }

    /// The normal cone: unit axis and `cos α` (−1, i.e. α = π, when the normals cancel out).
    pub fn cone(&self) -> (Vec3, f32) {
        let sum = self.normal_sum.as_vec3();
        if sum.length_squared() < 1.0 {
            return (Vec3::Z, -1.0);
        }
        let cos = (self.min_cosine as f32 / COSINE_QUANTUM).clamp(-1.0, 1.0);
        (sum.normalize(), cos)
    }
}

/// Pixel coordinates of tile `(tx, ty)`: `x0..x1 × y0..y1`.
pub fn tile_pixels(tile_size: u32, width: u32, height: u32, tx: u32, ty: u32) -> [u32; 4] {
    let (x0, y0) = (tx * tile_size, ty * tile_size);
    [
        x0,
        (x0 + tile_size).min(width),
        y0,
        (y0 + tile_size).min(height),
    ]
}

fn quantize_normal(n: Vec3) -> IVec3 {
    (n * NORMAL_QUANTUM)
        .to_array()
        .map(|c| c.round_ties_even() as i32)
        .into()
}

/// Depth bounds, normal cone and occupied slices of the tile whose pixels are `samples`.
/// The cone axis is the normalised sum of the normals (step 2) and α the arccosine of the
/// least cosine between the axis and a normal (step 3), both by exact integer reductions.
pub fn tile_bounds(samples: &[Sample], slicing: &Slicing) -> TileBounds {
    let mut b = TileBounds {
        min_depth: f32::INFINITY,
        max_depth: f32::NEG_INFINITY,
        normal_sum: IVec3::ZERO,
        min_cosine: i32::MAX,
        slices: 0,
        cluster_depths: [[f32::INFINITY, f32::NEG_INFINITY]; CLUSTER_SLICES as usize],
    };
    for s in samples {
        b.min_depth = b.min_depth.min(s.depth);
        b.max_depth = b.max_depth.max(s.depth);
        b.normal_sum += quantize_normal(s.normal);
        let k = slicing.slice(s.depth);
        b.slices |= 1 << k;
        let bounds = &mut b.cluster_depths[k as usize];
        *bounds = [bounds[0].min(s.depth), bounds[1].max(s.depth)];
    }
    let axis = b.normal_sum.as_vec3().normalize_or_zero();
    for s in samples {
        let q = (axis.dot(s.normal) * COSINE_QUANTUM).floor() as i32 - 1;
        b.min_cosine = b.min_cosine.min(q);
    }
    b
}

/// A tile's frustum: inward planes (left, right, top, bottom, near, far) with unit normals,
/// `dot(n, p) + w ≥ 0` inside, built in view space and moved to world space (so lights are
/// tested where they are, without a transform per light), and the 8 corners in world space
/// (thesis chapter 4 step 4), at the tile's depth bounds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TileFrustum {
    /// World-space side planes, then near (`min_depth`) and far (`max_depth`).
    pub planes: [Vec4; 6],
    /// World-space corners (near four, then far four).
    pub corners: [Vec3; 8],
    /// The corners' centre, the origin of light cones.
    pub center: Vec3,
}

/// View-space slopes (x/depth, y/depth) of the tile's pixel edges: left, right, top, bottom.
fn edge_slopes(frame: &Frame, [x0, x1, y0, y1]: [u32; 4]) -> [f32; 4] {
    let ndc_x = |x: u32| x as f32 * frame.viewport.z * 2.0 - 1.0;
    let ndc_y = |y: u32| 1.0 - y as f32 * frame.viewport.w * 2.0;
    let (tx, ty) = (frame.tan_half_fov.x, frame.tan_half_fov.y);
    [
        ndc_x(x0) * tx,
        ndc_x(x1) * tx,
        ndc_y(y0) * ty,
        ndc_y(y1) * ty,
    ]
}

/// The view-space plane `n·p + w ≥ 0` in world space: `(Rᵀn̂)·p + n̂·t + w/|n|` for the view
/// transform `p ↦ R p + t` (`world_plane`).
fn world_plane(frame: &Frame, n: Vec3, w: f32) -> Vec4 {
    let unit = n / n.length();
    let normal = (frame.view.transpose() * unit.extend(0.0)).xyz();
    normal.extend(unit.dot(frame.view.w_axis.xyz()) + w / n.length())
}

/// The frustum of the tile with pixel rectangle `rect` between view depths `near` and `far`.
pub fn tile_frustum(frame: &Frame, rect: [u32; 4], near: f32, far: f32) -> TileFrustum {
    let [l, r, t, b] = edge_slopes(frame, rect);
    let planes = [
        world_plane(frame, Vec3::new(1.0, 0.0, l), 0.0),
        world_plane(frame, Vec3::new(-1.0, 0.0, -r), 0.0),
        world_plane(frame, Vec3::new(0.0, -1.0, -t), 0.0),
        world_plane(frame, Vec3::new(0.0, 1.0, b), 0.0),
        world_plane(frame, Vec3::NEG_Z, -near),
        world_plane(frame, Vec3::Z, far),
    ];
    let mut corners = [Vec3::ZERO; 8];
    for (i, c) in corners.iter_mut().enumerate() {
        let z = if i < 4 { near } else { far };
        let sx = if i & 1 == 0 { l } else { r };
        let sy = if i & 2 == 0 { t } else { b };
        *c = (frame.inv_view * Vec4::new(sx * z, sy * z, -z, 1.0)).xyz();
    }
    TileFrustum {
        planes,
        corners,
        center: corners.iter().copied().sum::<Vec3>() / 8.0,
    }
}

/// True when the sphere (centre `c`, radius `r`, in the planes' space) is not entirely outside
/// any of `planes` (the test of thesis §4.1, `Intersects`).
pub fn sphere_meets(planes: &[Vec4], c: Vec3, r: f32) -> bool {
    planes.iter().all(|p| p.xyz().dot(c) + p.w >= -r)
}

/// The light cone of thesis chapter 4 steps 5–6: the axis from the centre of the tile's 8
/// corners to the light (world position) and `cos δ`, δ the largest angle between the axis and
/// the directions from the corners to the light. `None` when δ ≥ π/2 (the light is inside or
/// beside the corners' hull): the cone bounds nothing useful and the light is kept.
pub fn light_cone(frustum: &TileFrustum, light: Vec3) -> Option<(Vec3, f32)> {
    let axis = (light - frustum.center).normalize_or_zero();
    let mut min_cos = 1.0f32;
    for c in &frustum.corners {
        min_cos = min_cos.min(axis.dot((light - *c).normalize_or_zero()));
    }
    (min_cos > 0.0 && axis != Vec3::ZERO).then_some((axis, min_cos.min(1.0)))
}

/// Step 7: the light faces the back of every surface of the tile when the angle ω between
/// the light cone's and the normal cone's axes exceeds `π/2 + θ`, θ = α + δ + [`CONE_EPSILON`].
/// Conservative: every pixel's normal is within α of the normal axis and its direction to the
/// light within δ of the light axis (all of the cone lies within 90° of its axis), so
/// `N·L < 0` at every pixel. Evaluated on cosines, without `acos`: when θ < π/2 the test is
/// `cos ω < cos(π/2 + θ) = −sin θ`, with `sin θ` and `cos θ` from the angle-sum formulas; when
/// θ ≥ π/2 no light can be rejected.
pub fn faces_away(
    (normal_axis, cos_alpha): (Vec3, f32),
    (light_axis, cos_delta): (Vec3, f32),
) -> bool {
    let sin = |c: f32| (1.0 - c * c).max(0.0).sqrt();
    let (cos_e, sin_e) = (CONE_EPSILON.cos(), CONE_EPSILON.sin());
    let (sin_alpha, sin_delta) = (sin(cos_alpha), sin(cos_delta));
    // β = δ + ε, θ = α + β.
    let cos_beta = cos_delta * cos_e - sin_delta * sin_e;
    let sin_beta = sin_delta * cos_e + cos_delta * sin_e;
    let cos_theta = cos_alpha * cos_beta - sin_alpha * sin_beta;
    let sin_theta = sin_alpha * cos_beta + cos_alpha * sin_beta;
    cos_theta > 0.0 && sin_theta >= 0.0 && light_axis.dot(normal_axis) < -sin_theta
}

/// True when `light` lies behind the plane through the centre of the tile's corners across
/// the normal axis. Only such a light can face away (ω > π/2): the others skip the light cone,
/// and the GPU computes α (its second reduction) only once some light of the tile needs it.
pub fn in_back_half_space(tile: &Tile, light: Vec3) -> bool {
    (light - tile.frustum.center).dot(tile.bounds.cone().0) < 0.0
}

/// Everything a tile needs to cull lights: its bounds, its frustum and the cluster slicing.
#[derive(Clone, Copy, Debug)]
pub struct Tile {
    /// Depth bounds, normal cone, occupied slices.
    pub bounds: TileBounds,
    /// Frustum at the depth bounds.
    pub frustum: TileFrustum,
    /// [`Method::ForwardPlus`]: the frustum from the near plane to the tile's far bound
    /// ([`forward_far`]), where blended surfaces may lie.
    pub reach: TileFrustum,
    /// Cluster slicing of the view.
    pub slicing: Slicing,
}

/// The far bound of a [`Method::ForwardPlus`] tile: its largest opaque depth, or the far plane
/// where some pixel (`open`) or every pixel shows no surface.
pub fn forward_far(bounds: &TileBounds, open: bool, slicing: &Slicing) -> f32 {
    if open || bounds.is_empty() {
        slicing.start(CLUSTER_SLICES)
    } else {
        bounds.max_depth
    }
}

/// A [`Method::ForwardPlus`] entry for `light` (0: culled): [`FORWARD_BLENDED`] when it meets
/// [`Tile::reach`], with [`FORWARD_OPAQUE`] when it also meets the opaque depth bounds (a
/// directional light meets every frustum).
fn forward_entry(tile: &Tile, light: &GpuLight) -> u32 {
    let world = Vec3::from(light.position);
    let meets = |planes: &[Vec4]| {
        light.kind == LIGHT_DIRECTIONAL || sphere_meets(planes, world, light.radius)
    };
    if !meets(&tile.reach.planes) {
        return 0;
    }
    let opaque = !tile.bounds.is_empty() && meets(&tile.frustum.planes);
    FORWARD_BLENDED | if opaque { FORWARD_OPAQUE } else { 0 }
}

/// Whether `light` goes into the tile's list under `method`, and for which slices: 0 =
/// culled, [`ALL_SLICES`] = kept (tiled methods), else the mask of occupied clusters of the
/// tile it overlaps (tiled slices, clustered).
pub fn cull_light(method: Method, tile: &Tile, frame: &Frame, light: &GpuLight) -> u32 {
    if method == Method::ForwardPlus {
        // Its tiles list lights for blended surfaces even without opaque ones.
        return forward_entry(tile, light);
    }
    if tile.bounds.is_empty() {
        return 0;
    }
    let world = Vec3::from(light.position);
    if light.kind == LIGHT_DIRECTIONAL {
        // Light from one direction: a light cone of half-angle 0.
        let away = method == Method::TiledCones
            && faces_away(tile.bounds.cone(), (-Vec3::from(light.direction), 1.0));
        return match method {
            _ if away => 0,
            // It reaches every occupied cluster.
            Method::TiledSlices | Method::Clustered => tile.bounds.slices,
            _ => ALL_SLICES,
        };
    }
    let planes = &tile.frustum.planes;
    match method {
        // A light volume holds the light's whole influence: brute force's image.
        Method::BruteForce | Method::LightVolumes => ALL_SLICES,
        Method::Tiled | Method::LightPrePass => {
            if sphere_meets(planes, world, light.radius) {
                ALL_SLICES
            } else {
                0
            }
        }
        Method::TiledCones => {
            let keep = sphere_meets(planes, world, light.radius)
                && !(in_back_half_space(tile, world)
                    && light_cone(&tile.frustum, world)
                        .is_some_and(|cone| faces_away(tile.bounds.cone(), cone)));
            if keep { ALL_SLICES } else { 0 }
        }
        Method::ForwardPlus => forward_entry(tile, light),
        Method::Clustered => {
            // Explicit cluster bounds (Olsson et al. 2012 as §2.5 gives them): the tile's side
            // planes and the depths of the cluster's own pixels.
            if !sphere_meets(&planes[..4], world, light.radius) {
                return 0;
            }
            let depth = -frame.view.row(2).dot(world.extend(1.0));
            let (near, far) = (depth - light.radius, depth + light.radius);
            let mut mask = 0;
            for k in 0..CLUSTER_SLICES {
                let [z0, z1] = tile.bounds.cluster_depths[k as usize];
                if far >= z0 && near <= z1 {
                    mask |= 1 << k;
                }
            }
            mask
        }
        Method::TiledSlices => {
            // The slices' own depths within the tile's depth bounds.
            if !sphere_meets(planes, world, light.radius) {
                return 0;
            }
            let depth = -frame.view.row(2).dot(world.extend(1.0));
            let (near, far) = (depth - light.radius, depth + light.radius);
            let mut mask = 0;
            for k in 0..CLUSTER_SLICES {
                let (z0, z1) = (tile.slicing.start(k), tile.slicing.start(k + 1));
                if far >= z0 * (1.0 - SLICE_EPSILON) && near <= z1 * (1.0 + SLICE_EPSILON) {
                    mask |= 1 << k;
                }
            }
            mask & tile.bounds.slices
        }
    }
}

/// The result of a light accumulation.
#[derive(Clone, Debug, PartialEq)]
pub struct Shaded {
    /// Σ diffuse `E/π` per pixel.
    pub diffuse: Image<Vec3>,
    /// Σ specular `E·D·V·F` per pixel.
    pub specular: Image<Vec3>,
    /// Tiles across and down.
    pub tiles: (u32, u32),
    /// Length of each tile's light list, row-major over tiles (brute force: every light for
    /// tiles with a surface) — the light-count heatmap.
    pub counts: Vec<u32>,
    /// Each tile's list: (light index, slice mask), in light order.
    pub lists: Vec<Vec<(u32, u32)>>,
}

/// Light accumulation with `config.method`: per tile, the bounds, the frustum and the list
/// of lights that pass [`cull_light`]; then per pixel the sums of [`shade_shadowed`] (with `shadows`, else unshadowed) over the
/// list (over the entries whose mask holds the pixel's slice).
pub fn shade(
    gb: &GBuffer,
    frame: &Frame,
    camera: &Camera,
    lights: &[GpuLight],
    config: &ShadingConfig,
    shadows: Option<&ShadowMaps>,
) -> Result<Shaded, ShadingError> {
    config.validate()?;
    let (w, h) = (gb.width(), gb.height());
    let (tiles_x, tiles_y) = config.tiles(w, h);
    let slicing = Slicing::new(camera);
    struct TileOut {
        list: Vec<(u32, u32)>,
        pixels: Vec<(u32, u32, Vec3, Vec3)>,
    }
    let out: Vec<TileOut> = (0..tiles_x * tiles_y)
        .into_par_iter()
        .map(|t| {
            let rect = tile_pixels(config.tile_size, w, h, t % tiles_x, t / tiles_x);
            let coords: Vec<(u32, u32)> = (rect[2]..rect[3])
                .flat_map(|y| (rect[0]..rect[1]).map(move |x| (x, y)))
                .collect();
            let samples: Vec<Option<Sample>> = coords
                .iter()
                .map(|&(x, y)| sample(gb, frame, x, y))
                .collect();
            let present: Vec<Sample> = samples.iter().flatten().copied().collect();
            let bounds = tile_bounds(&present, &slicing);
            let far = forward_far(&bounds, present.len() < coords.len(), &slicing);
            let tile = Tile {
                bounds,
                frustum: tile_frustum(frame, rect, bounds.min_depth, bounds.max_depth),
                reach: tile_frustum(frame, rect, slicing.near, far),
                slicing,
            };
            let list: Vec<(u32, u32)> = lights
                .iter()
                .enumerate()
                .map(|(i, l)| (i as u32, cull_light(config.method, &tile, frame, l)))
                .filter(|&(_, mask)| mask != 0)
                .collect();
            let pixels = coords
                .iter()
                .zip(&samples)
                .map(|(&(x, y), s)| {
                    let (d, sp) = s.map_or((Vec3::ZERO, Vec3::ZERO), |s| {
                        shade_pixel(
                            gb,
                            (frame, config.method),
                            (x, y),
                            &s,
                            (lights, shadows),
                            &list,
                            // Forward+ shades opaque surfaces from the FORWARD_OPAQUE entries.
                            if config.method == Method::ForwardPlus {
                                0
                            } else {
                                slicing.slice(s.depth)
                            },
                        )
                    });
                    (x, y, d, sp)
                })
                .collect();
            TileOut { list, pixels }
        })
        .collect();
    let mut diffuse = Image::filled(w, h, Vec3::ZERO);
    let mut specular = Image::filled(w, h, Vec3::ZERO);
    let mut lists = Vec::with_capacity(out.len());
    for tile in out {
        for (x, y, d, s) in tile.pixels {
            diffuse.set(x, y, d);
            specular.set(x, y, s);
        }
        lists.push(tile.list);
    }
    Ok(Shaded {
        diffuse,
        specular,
        tiles: (tiles_x, tiles_y),
        counts: lists.iter().map(|l| l.len() as u32).collect(),
        lists,
    })
}

/// The (diffuse, specular) sums at one pixel over the list entries that cover its slice; for
/// the light pre-pass the light buffer's diffuse light and, grey, its monochrome specular
/// light (the luminance of the specular sum with F = 1).
fn shade_pixel(
    gb: &GBuffer,
    (frame, method): (&Frame, Method),
    (x, y): (u32, u32),
    s: &Sample,
    (lights, shadows): (&[GpuLight], Option<&ShadowMaps>),
    list: &[(u32, u32)],
    slice: u32,
) -> (Vec3, Vec3) {
    let v = (frame.eye.truncate() - s.position).normalize();
    let (albedo, specular) = gbuffer::unpack_albedo(gb.albedo.get(x, y));
    let (roughness, metallic, _) = unpack_material(gb.material.get(x, y));
    let prepass = method == Method::LightPrePass;
    let surface = Surface {
        p: s.position,
        n: s.normal,
        v,
        // The light pre-pass has only the roughness: F = 1, a white metal.
        albedo: if prepass { Vec3::ONE } else { albedo },
        roughness,
        metallic: if prepass { 1.0 } else { metallic },
        specular: if prepass { 1.0 } else { specular },
    };
    let (d, sp) = list.iter().filter(|(_, mask)| mask >> slice & 1 == 1).fold(
        (Vec3::ZERO, Vec3::ZERO),
        |(d, sp), &(i, _)| {
            let (dl, sl) = shade_shadowed(&lights[i as usize], &surface, shadows);
            (d + dl, sp + sl)
        },
    );
    if prepass {
        (d, Vec3::splat(scene::luminance(sp)))
    } else {
        (d, sp)
    }
}

/// The light pre-pass's second geometry pass from the G-buffer (the twin of
/// `light_prepass.wgsl`, which reads the rasterised material instead): given `light`, the
/// lighting pass's light buffer ([`shade`] with [`Method::LightPrePass`]: diffuse light, grey
/// monochrome specular), the diffuse light as it is and the monochrome specular times the
/// Fresnel factor at N·V, tinted by the diffuse light's chromaticity.
pub fn apply_light_prepass(gb: &GBuffer, frame: &Frame, light: &Shaded) -> Shaded {
    let (w, h) = (gb.width(), gb.height());
    let specular: Vec<Vec3> = (0..w * h)
        .into_par_iter()
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let Some(s) = sample(gb, frame, x, y) else {
                return Vec3::ZERO;
            };
            let n_dot_v = s
                .normal
                .dot((frame.eye.truncate() - s.position).normalize())
                .clamp(0.0, 1.0);
            let fw = (1.0 - n_dot_v).powi(5);
            let (albedo, factor) = gbuffer::unpack_albedo(gb.albedo.get(x, y));
            let (_, metallic, _) = unpack_material(gb.material.get(x, y));
            let dielectric = Vec3::splat(factor * (0.04 + 0.96 * fw));
            let f = dielectric.lerp(albedo + (Vec3::ONE - albedo) * fw, metallic);
            let diffuse = light.diffuse.get(x, y);
            let lum = scene::luminance(diffuse);
            let chroma = if lum > 0.0 { diffuse / lum } else { Vec3::ONE };
            f * light.specular.get(x, y).x * chroma
        })
        .collect();
    Shaded {
        specular: Image::from_vec(w, h, specular).expect("w × h pixels"),
        ..light.clone()
    }
}

/// Per pixel, how many lights contribute (non-zero attenuation and `N·L > 0`): what an ideal
/// per-pixel culling would evaluate, for heatmaps beside the per-tile list lengths.
pub fn contributing_lights(gb: &GBuffer, frame: &Frame, lights: &[GpuLight]) -> Image<u32> {
    let (w, h) = (gb.width(), gb.height());
    let pixels: Vec<u32> = (0..w * h)
        .into_par_iter()
        .map(|i| {
            sample(gb, frame, i % w, i / w).map_or(0, |s| {
                lights
                    .iter()
                    .filter(|l| {
                        let (dir, att) = crate::lighting::light_incidence(l, s.position);
                        att > 0.0 && dir.dot(s.normal) > 0.0
                    })
                    .count() as u32
            })
        })
        .collect();
    Image::from_vec(w, h, pixels).expect("w × h pixels")
}
