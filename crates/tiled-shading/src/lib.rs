//! Light accumulation for deferred shading (Ishmukhametov 2013): every light at every pixel
//! (brute force), tile-based deferred shading with per-tile depth bounds (§2.4.1, after
//! Andersson 2009 and Lauritzen 2010), the same with normal-cone back-face culling of lights
//! (chapter 4, steps 1–7), tile lists with exponential depth-slice masks, clustered shading
//! (§2.5, after Olsson et al. 2012: per-cluster lists of the occupied clusters) — all finding
//! their lights through a light hierarchy ([`LightGroups`], [`LightSearch`]) — Forward+, the
//! light pre-pass and traditional deferred shading with light volumes (§4.1). CPU reference in
//! [`cpu`], one pass per method in [`gpu`].
//!
//! All methods produce the same two images — the diffuse and specular sums of
//! [`lighting::shade_light`] over the lights — because every light has a finite radius at
//! which its attenuation is exactly zero and every culling test is conservative: a light is
//! only dropped from a tile when it cannot reach any of its pixels (outside the tile's
//! depth-bounded frustum) or reaches them all from behind (normal cone).
//!
//! ```no_run
//! use tiled_shading::{Method, ShadingConfig};
//! let scene = scene::spheres_on_plane(4);
//! let camera = scene.camera_or_framed();
//! let gb = gbuffer::cpu::rasterize(&scene, &camera, 320, 240)?.gbuffer;
//! let frame = gbuffer::Frame::new(&camera, 320, 240);
//! let lights = scene::scatter_point_lights(scene.bounds(), 256, 7);
//! let config = ShadingConfig { method: Method::TiledCones, ..Default::default() };
//! let out = tiled_shading::cpu::shade(&gb, &frame, &camera, &tiled_shading::gpu_lights(&lights)?, &config, None)?;
//! println!("{} light evaluations", out.counts.iter().map(|&c| u64::from(c)).sum::<u64>());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod cpu;
pub mod gpu;
pub mod lighting;
pub mod rays;
pub mod shadows;

use std::fmt;
use std::str::FromStr;

use glam::{Vec3, Vec4Swizzles};
use scene::{Camera, Light};

/// This crate's WGSL (`shaders/tiled-shading/`, carried into the package by the `shaders` link).
pub static SHADERS: ::gpu::shader::Library = ::gpu::shader_library!(
    "tiled-shading",
    imports: [gbuffer::SHADERS, manylod::SHADERS],
    files: [
        "lighting.wgsl",
        "params.wgsl",
        "forward.wgsl",
        "light_prepass.wgsl",
        "rays.wgsl",
        "shadow_view.wgsl",
        "shadows.wgsl",
        "shadow_raster.wgsl",
        "tiled.wgsl",
        "clustered.wgsl",
        "slices.wgsl",
        "light_search.wgsl",
        "light_tree.wgsl",
        "pixels.wgsl",
        "sums.wgsl",
        "volumes.wgsl",
    ],
);

/// What this crate's kernels need of a device: wgpu's default limits suffice.
pub fn device_needs() -> ::gpu::DeviceNeeds {
    ::gpu::DeviceNeeds::default()
}

/// A light as the shaders see it (WGSL `Light` in `tiled-shading/lighting.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuLight {
    /// Position (point, spot, hemispherical).
    pub position: [f32; 3],
    /// Influence radius (point, spot, hemispherical).
    pub radius: f32,
    /// Colour × intensity.
    pub color: [f32; 3],
    /// 0 point, 1 spot, 2 directional, 3 hemispherical.
    pub kind: u32,
    /// Direction the light travels (spot, directional); the emitter's normal (hemispherical).
    pub direction: [f32; 3],
    /// Cosine of the outer cone angle (spot).
    pub cos_outer: f32,
    /// Cosine of the inner cone angle (spot).
    pub cos_inner: f32,
    /// First of the light's shadow views ([`shadows::ShadowPlan`]).
    pub shadow_first: u32,
    /// Number of its shadow views ([`shadows::NO_SHADOW`]: none, the light is unshadowed).
    pub shadow_count: u32,
    /// Padding to 64 bytes.
    pub _pad: u32,
}

/// `GpuLight::kind` of a directional light (no position, no radius: never culled).
pub const LIGHT_DIRECTIONAL: u32 = 2;

impl From<&Light> for GpuLight {
    fn from(light: &Light) -> Self {
        let (Light::Point {
            color, intensity, ..
        }
        | Light::Spot {
            color, intensity, ..
        }
        | Light::Hemispherical {
            color, intensity, ..
        }
        | Light::Directional {
            color, intensity, ..
        }) = *light;
        // (kind, position, radius, direction, (inner, outer) cone angles)
        let (kind, position, radius, direction, cone) = match *light {
            Light::Point {
                position, radius, ..
            } => (0, position, radius, Vec3::NEG_Y, None),
            Light::Spot {
                position,
                direction,
                radius,
                inner_angle,
                outer_angle,
                ..
            } => (
                1,
                position,
                radius,
                direction,
                Some((inner_angle, outer_angle)),
            ),
            Light::Hemispherical {
                position,
                direction,
                radius,
                ..
            } => (3, position, radius, direction, None),
            Light::Directional { direction, .. } => {
                (LIGHT_DIRECTIONAL, Vec3::ZERO, 1.0, direction, None)
            }
        };
        let (cos_outer, cos_inner) = cone.map_or((0.0, 1.0), |(inner, outer): (f32, f32)| {
            (outer.cos(), inner.cos().max(outer.cos() + 1e-4))
        });
        Self {
            position: position.to_array(),
            radius,
            color: (color * intensity).to_array(),
            kind,
            direction: direction.to_array(),
            cos_outer,
            cos_inner,
            shadow_first: 0,
            shadow_count: shadows::NO_SHADOW,
            _pad: 0,
        }
    }
}

/// How lights are assigned to pixels.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Method {
    /// Every light at every pixel (the light loop of thesis §1.3 step 3 as one compute pass):
    /// the reference.
    BruteForce,
    /// Traditional deferred shading (thesis §4.1, Hargreaves 2004): every light drawn as an
    /// instanced low-polygon volume (sphere, cone, or a full-screen triangle for directional
    /// lights), back faces only, depth-tested against the scene, each fragment shading one
    /// light and blended additively into the accumulation (the thesis's baseline).
    LightVolumes,
    /// Tile-based deferred shading (§2.4.1): per-tile depth bounds and a sphere–frustum test.
    #[default]
    Tiled,
    /// [`Method::Tiled`] plus normal-cone back-face culling of lights (chapter 4, steps 1–7).
    TiledCones,
    /// Tile lists with depth-slice masks (a one-pass approximation of §2.5's clusters): each
    /// tile's list holds the lights that meet its frustum, each with the mask of the tile's
    /// occupied exponential depth slices it overlaps; a pixel evaluates the entries whose mask
    /// holds its slice.
    TiledSlices,
    /// Clustered deferred shading (§2.5 after Olsson et al. 2012): every pixel's cluster key
    /// (its tile of the screen and exponential depth slice) comes from the depth buffer with
    /// each cluster's explicit bounds (the least and greatest depth of its pixels), the
    /// occupied clusters are compacted, each finds the lights meeting its tile's side planes
    /// and its bounds through the light hierarchy (a workgroup per cluster, lights of any
    /// number) and a pixel shades exactly its cluster's list ([`gpu::clustered`]). A
    /// cluster's lights are among its tile's [`Method::Tiled`] list.
    Clustered,
    /// Forward+ (tiled forward shading, §2.4.2 after Harada et al. 2012): the tiles' light
    /// lists are built from the depth pre-pass over the depths from the near plane to the
    /// tile's farthest opaque surface (the far plane where a pixel shows the background), kept
    /// in memory, and read by a forward pass that shades the scene's geometry — the opaque
    /// surfaces into the light accumulation, and alpha-blended surfaces over the composed
    /// frame ([`gpu::forward`]).
    ForwardPlus,
    /// The light pre-pass (deferred lighting, §2.1 after Engel 2008), a comparator: the
    /// lighting pass culls as [`Method::Tiled`] from the normals, depth and roughness only and
    /// writes a light buffer — diffuse light, and the luminance of the specular light without
    /// its Fresnel factor — and a second geometry pass applies the materials
    /// ([`gpu::light_prepass`]; monochrome specular: exact only for white lights on materials
    /// whose Fresnel factor does not vary).
    LightPrePass,
}

impl Method {
    /// Every method, the reference first.
    pub const ALL: [Method; 8] = [
        Method::BruteForce,
        Method::Tiled,
        Method::TiledCones,
        Method::TiledSlices,
        Method::Clustered,
        Method::LightVolumes,
        Method::ForwardPlus,
        Method::LightPrePass,
    ];

    /// The command-line name (`brute`, `tiled`, `tiled-cones`, `tiled-slices`, `clustered`,
    /// `volumes`, `forward`, `light-prepass`).
    pub fn name(self) -> &'static str {
        match self {
            Method::BruteForce => "brute",
            Method::LightVolumes => "volumes",
            Method::Tiled => "tiled",
            Method::TiledCones => "tiled-cones",
            Method::TiledSlices => "tiled-slices",
            Method::Clustered => "clustered",
            Method::ForwardPlus => "forward",
            Method::LightPrePass => "light-prepass",
        }
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Method {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        Method::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| {
                format!(
                    "unknown shading method {s:?} (brute, tiled, tiled-cones, tiled-slices, clustered, volumes, forward, light-prepass)"
                )
            })
    }
}

/// Depth slices of [`Method::TiledSlices`] and [`Method::Clustered`]: a 32-bit mask holds a
/// tile's occupied slices.
pub const CLUSTER_SLICES: u32 = 32;

/// How a tile of the tiled methods finds the lights that meet it (the same lists either way).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum LightSearch {
    /// Through the light hierarchy ([`LightGroups`]): the groups first, then only the lights
    /// of the groups that meet the tile.
    #[default]
    Tree,
    /// Every light against every tile, as the thesis.
    Flat,
}

impl LightSearch {
    /// The command-line name (`tree`, `flat`).
    pub fn name(self) -> &'static str {
        match self {
            LightSearch::Tree => "tree",
            LightSearch::Flat => "flat",
        }
    }
}

impl fmt::Display for LightSearch {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for LightSearch {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        [LightSearch::Tree, LightSearch::Flat]
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| format!("unknown light search {s:?} (tree, flat)"))
    }
}

/// What the light accumulation does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadingConfig {
    /// Culling method.
    pub method: Method,
    /// Tile side in pixels: 8, 16 (default, as the thesis) or 32.
    pub tile_size: u32,
    /// How tiles (and clusters) find their lights.
    pub search: LightSearch,
}

impl Default for ShadingConfig {
    fn default() -> Self {
        Self {
            method: Method::Tiled,
            tile_size: 16,
            search: LightSearch::Tree,
        }
    }
}

impl ShadingConfig {
    /// Checks the tile size.
    pub fn validate(&self) -> Result<(), ShadingError> {
        if ![8, 16, 32].contains(&self.tile_size) {
            return Err(ShadingError::TileSize(self.tile_size));
        }
        Ok(())
    }

    /// Tiles across and down a `width × height` image (partial tiles at the right and bottom).
    pub fn tiles(&self, width: u32, height: u32) -> (u32, u32) {
        (
            width.div_ceil(self.tile_size),
            height.div_ceil(self.tile_size),
        )
    }
}

/// Exponential depth slicing of the view between the camera's near and far planes
/// (Olsson et al. 2012 as the thesis summarises it in §2.5): slice `k` spans view depths
/// `near · (far/near)^(k/S)` to `near · (far/near)^((k+1)/S)`, S = [`CLUSTER_SLICES`], so every
/// slice has the same ratio of depth extent to distance (self-similar clusters).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Slicing {
    /// Near plane distance.
    pub near: f32,
    /// `S / ln(far / near)`: slice index per unit of `ln(depth / near)`.
    pub scale: f32,
}

impl Slicing {
    /// The slicing for `camera`'s near and far planes.
    pub fn new(camera: &Camera) -> Self {
        let near = camera.near.max(1e-6);
        let ratio = (camera.far / near).max(1.0 + 1e-6);
        Self {
            near,
            scale: CLUSTER_SLICES as f32 / ratio.ln(),
        }
    }

    /// The slice of a view depth (clamped to `0..S`).
    pub fn slice(&self, depth: f32) -> u32 {
        let k = ((depth / self.near).max(1.0).ln() * self.scale).floor();
        (k.max(0.0) as u32).min(CLUSTER_SLICES - 1)
    }

    /// View depth at which slice `k` begins (`k = S` gives the far plane).
    pub fn start(&self, k: u32) -> f32 {
        self.near * (k as f32 / self.scale).exp()
    }
}

/// Lights per group of [`LightGroups`].
pub const LIGHT_GROUP: usize = 32;

/// The light hierarchy of the tiled methods' [`LightSearch::Tree`] (after Olsson et al. 2012's
/// light BVH, one level): the lights in Morton order of their centres, cut into groups of [`LIGHT_GROUP`],
/// each under a sphere holding its lights' spheres. A tile tests the groups first and only the
/// lights of the groups that meet it. Directional lights come first, under a sphere of radius
/// `f32::MAX` (they meet every tile).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LightGroups {
    /// Light indices in Morton order.
    pub order: Vec<u32>,
    /// Per group of [`LIGHT_GROUP`] consecutive entries of `order`: centre xyz, radius.
    pub spheres: Vec<[f32; 4]>,
}

/// Bits of the Morton code that order the lights of [`LightGroups`]: a counting sort over
/// 2¹⁵ buckets (32 cells per axis), as the GPU build does it each frame.
pub const LIGHT_BUCKET_BITS: u32 = 15;

impl LightGroups {
    /// Sorts `lights` by the top [`LIGHT_BUCKET_BITS`] of the Morton code of their centres
    /// (10 bits per axis over the lights' bounds), by index within a bucket, and bounds each
    /// group. The GPU build (`light_tree.wgsl`) sorts the same buckets in no set order within
    /// each.
    pub fn new(lights: &[GpuLight]) -> Self {
        let positional = |l: &GpuLight| l.kind != LIGHT_DIRECTIONAL;
        let (lo, hi) = lights.iter().filter(|l| positional(l)).fold(
            (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
            |(lo, hi), l| {
                let p = Vec3::from(l.position);
                (lo.min(p), hi.max(p))
            },
        );
        let scale = Vec3::splat(1023.0) / (hi - lo).max(Vec3::splat(f32::MIN_POSITIVE));
        let morton = |l: &GpuLight| -> u32 {
            if !positional(l) {
                return 0;
            }
            let q = ((Vec3::from(l.position) - lo) * scale)
                .clamp(Vec3::ZERO, Vec3::splat(1023.0))
                .as_uvec3();
            // Spread 10 bits to every third bit.
            let spread = |mut v: u32| {
                v = (v | (v << 16)) & 0x0300_00ff;
                v = (v | (v << 8)) & 0x0300_f00f;
                v = (v | (v << 4)) & 0x030c_30c3;
                (v | (v << 2)) & 0x0924_9249
            };
            let code = spread(q.x) | (spread(q.y) << 1) | (spread(q.z) << 2);
            1 + (code >> (30 - LIGHT_BUCKET_BITS))
        };
        let mut keyed: Vec<(u32, u32)> = lights
            .iter()
            .enumerate()
            .map(|(i, l)| (morton(l), i as u32))
            .collect();
        keyed.sort_unstable();
        let order: Vec<u32> = keyed.into_iter().map(|(_, i)| i).collect();
        let spheres = order
            .chunks(LIGHT_GROUP)
            .map(|group| {
                let members = group.iter().map(|&i| &lights[i as usize]);
                if members.clone().any(|l| !positional(l)) {
                    return [0.0, 0.0, 0.0, f32::MAX];
                }
                let (lo, hi) = members.clone().fold(
                    (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
                    |(lo, hi), l| {
                        let (p, r) = (Vec3::from(l.position), Vec3::splat(l.radius));
                        (lo.min(p - r), hi.max(p + r))
                    },
                );
                let centre = (lo + hi) * 0.5;
                let radius = members
                    .map(|l| centre.distance(Vec3::from(l.position)) + l.radius)
                    .fold(0.0, f32::max);
                // Rounding: grown by a relative 1e-5 so it holds every member after it.
                centre
                    .extend(radius * (1.0 + 1e-5) + centre.abs().max_element() * 1e-6)
                    .to_array()
            })
            .collect();
        Self { order, spheres }
    }

    /// The hierarchy as the shader reads it (`tiled.wgsl`'s `light_tree`, 16-byte entries):
    /// the spheres' bits, then the order, zero-padded to whole entries.
    pub fn words(&self) -> Vec<u32> {
        let mut words: Vec<u32> = self.spheres.iter().flatten().map(|f| f.to_bits()).collect();
        words.extend(&self.order);
        words.resize(words.len().next_multiple_of(4), 0);
        words
    }
}

/// Errors of light accumulation.
#[derive(Debug, thiserror::Error)]
pub enum ShadingError {
    /// Tile sides other than 8, 16, 32.
    #[error("tile size must be 8, 16 or 32 pixels, got {0}")]
    TileSize(u32),
    /// A light has non-finite or negative parameters or a non-positive radius.
    #[error("light {index}: {problem}")]
    InvalidLight {
        /// Index in the light list.
        index: usize,
        /// What is wrong, with the values.
        problem: String,
    },
    /// More lights than the buffer made at creation holds.
    #[error("{count} lights do not fit the light buffer made for {capacity}")]
    TooManyLights {
        /// Lights given.
        count: usize,
        /// Lights the buffer holds.
        capacity: usize,
    },
    /// A geometry-pass method (Forward+, the light pre-pass) given what it cannot take: the
    /// forward pass without Forward+ lists, supersampling.
    #[error("{0}")]
    Incompatible(String),
    /// Bad shadow-map settings, or more shadow views than the device holds.
    #[error("shadow maps: {0}")]
    InvalidShadows(String),
    /// A scene the ray traversal cannot take ([`rays::RayBvh`]).
    #[error("rays: {0}")]
    Rays(String),
    /// A GPU resource could not be created or read.
    #[error(transparent)]
    Gpu(#[from] ::gpu::GpuError),
}

/// Converts lights to their shader form, rejecting NaN/infinite values, negative colours and
/// non-positive radii (the error says which, with the value).
pub fn gpu_lights(lights: &[Light]) -> Result<Vec<GpuLight>, ShadingError> {
    lights
        .iter()
        .enumerate()
        .map(|(index, light)| {
            let g = GpuLight::from(light);
            let kind = match light {
                Light::Point { .. } => "point light",
                Light::Spot { .. } => "spot light",
                Light::Hemispherical { .. } => "hemispherical light",
                Light::Directional { .. } => "directional light",
            };
            let problem = if !g.position.iter().all(|v| v.is_finite()) {
                format!("position {:?} is not finite", g.position)
            } else if !g.direction.iter().all(|v| v.is_finite()) {
                format!("direction {:?} is not finite", g.direction)
            } else if !(g.radius.is_finite() && g.radius > 0.0) {
                format!("radius {} must be positive and finite", g.radius)
            } else if !g.color.iter().all(|&c| c.is_finite() && c >= 0.0) {
                format!(
                    "colour × intensity {:?} must be finite and non-negative",
                    g.color
                )
            } else if !(g.cos_inner.is_finite() && g.cos_outer.is_finite()) {
                "cone angles are not finite".to_string()
            } else {
                return Ok(g);
            };
            Err(ShadingError::InvalidLight {
                index,
                problem: format!("{kind}: {problem}"),
            })
        })
        .collect()
}

/// CPU view-frustum culling of lights (thesis §4.1): the indices of the lights whose
/// influence sphere meets the camera's view frustum (six planes; directional lights always).
/// Only these need to be sent to the light accumulation.
pub fn frustum_cull(camera: &Camera, aspect: f32, lights: &[GpuLight]) -> Vec<u32> {
    let m = camera.view_projection(aspect);
    let (r0, r1, r2, r3) = (m.row(0), m.row(1), m.row(2), m.row(3));
    // Clip-space planes (wgpu depth 0..1): left, right, bottom, top, near, far.
    let planes = [r3 + r0, r3 - r0, r3 + r1, r3 - r1, r2, r3 - r2]
        .map(|p| p / p.xyz().length().max(f32::MIN_POSITIVE));
    lights
        .iter()
        .enumerate()
        .filter(|(_, l)| {
            l.kind == LIGHT_DIRECTIONAL
                || planes
                    .iter()
                    .all(|p| p.xyz().dot(Vec3::from(l.position)) + p.w >= -l.radius)
        })
        .map(|(i, _)| i as u32)
        .collect()
}

/// Colour of `t` ∈ \[0, 1\] on the heatmap ramp black → blue → green → yellow → red → white.
pub fn heat_color(t: f32) -> [f32; 4] {
    const RAMP: [[f32; 3]; 6] = [
        [0.0, 0.0, 0.0],
        [0.0, 0.1, 0.9],
        [0.0, 0.8, 0.2],
        [1.0, 0.9, 0.0],
        [1.0, 0.1, 0.0],
        [1.0, 1.0, 1.0],
    ];
    let x = t.clamp(0.0, 1.0) * (RAMP.len() - 1) as f32;
    let i = (x.floor() as usize).min(RAMP.len() - 2);
    let f = x - i as f32;
    let c = |k: usize| RAMP[i][k] + (RAMP[i + 1][k] - RAMP[i][k]) * f;
    [c(0), c(1), c(2), 1.0]
}

/// The light-count heatmap of a `width × height` frame (like the thesis's figures in §4.2):
/// each tile filled with [`heat_color`] of its count / `max` (black: no lights, white: `max`
/// or more), with a one-pixel darker grid between tiles.
pub fn heatmap(
    counts: &[u32],
    config: &ShadingConfig,
    width: u32,
    height: u32,
    max: u32,
) -> gbuffer::Image<[f32; 4]> {
    let (tiles_x, _) = config.tiles(width, height);
    let t = config.tile_size;
    let pixels = (0..width * height)
        .map(|i| {
            let (x, y) = (i % width, i / width);
            let count = counts
                .get(((y / t) * tiles_x + x / t) as usize)
                .copied()
                .unwrap_or(0);
            let c = heat_color(count as f32 / max.max(1) as f32);
            let edge = if x % t == 0 || y % t == 0 { 0.7 } else { 1.0 };
            [c[0] * edge, c[1] * edge, c[2] * edge, 1.0]
        })
        .collect();
    gbuffer::Image::from_vec(width, height, pixels).expect("w × h pixels")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gpu_light_matches_wgsl_layout() {
        assert_eq!(size_of::<GpuLight>(), 64);
        assert_eq!(std::mem::offset_of!(GpuLight, color), 16);
        assert_eq!(std::mem::offset_of!(GpuLight, direction), 32);
        assert_eq!(std::mem::offset_of!(GpuLight, cos_inner), 48);
    }

    #[test]
    fn invalid_lights_are_rejected() {
        for (position, radius) in [
            (Vec3::NAN, 1.0),
            (Vec3::ZERO, 0.0),
            (Vec3::ZERO, f32::INFINITY),
        ] {
            let bad = Light::Point {
                position,
                color: Vec3::ONE,
                intensity: 1.0,
                radius,
            };
            assert!(matches!(
                gpu_lights(&[bad]),
                Err(ShadingError::InvalidLight { index: 0, .. })
            ));
        }
    }

    #[test]
    fn light_groups_hold_their_lights_in_morton_order() {
        let mut lights = gpu_lights(&scene::scatter_point_lights(
            scene::Aabb {
                min: Vec3::splat(-5.0),
                max: Vec3::splat(5.0),
            },
            1000,
            3,
        ))
        .expect("lights");
        lights[500].kind = LIGHT_DIRECTIONAL;
        let groups = LightGroups::new(&lights);
        let mut sorted = groups.order.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..1000).collect::<Vec<u32>>());
        assert_eq!(groups.spheres.len(), 1000usize.div_ceil(LIGHT_GROUP));
        assert_eq!(groups.order[0], 500, "directional lights first");
        assert_eq!(groups.spheres[0][3], f32::MAX);
        for (g, sphere) in groups.spheres.iter().enumerate().skip(1) {
            let (c, r) = (Vec3::new(sphere[0], sphere[1], sphere[2]), sphere[3]);
            for &i in &groups.order[g * LIGHT_GROUP..((g + 1) * LIGHT_GROUP).min(1000)] {
                let l = &lights[i as usize];
                assert!(c.distance(Vec3::from(l.position)) + l.radius <= r);
            }
        }
        // Morton order keeps groups local: their spheres are far smaller than those of groups
        // in the lights' own (random) order.
        let radius = |group: &[GpuLight]| {
            let (lo, hi) = group.iter().fold(
                (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
                |(lo, hi), l| {
                    (
                        lo.min(Vec3::from(l.position)),
                        hi.max(Vec3::from(l.position)),
                    )
                },
            );
            let c = (lo + hi) * 0.5;
            group
                .iter()
                .map(|l| c.distance(Vec3::from(l.position)) + l.radius)
                .fold(0.0, f32::max)
        };
        let unsorted: f32 = lights[..992].chunks(LIGHT_GROUP).map(radius).sum::<f32>() / 31.0;
        let sorted = groups.spheres[1..].iter().map(|s| s[3]).sum::<f32>() / 31.0;
        assert!(
            sorted < 0.6 * unsorted,
            "mean radius {sorted} vs {unsorted} unsorted"
        );
    }

    #[test]
    fn methods_parse_by_name() {
        for m in Method::ALL {
            assert_eq!(m.name().parse::<Method>(), Ok(m));
        }
        assert!("tiles".parse::<Method>().is_err());
    }

    #[test]
    fn slices_are_exponential_and_cover_near_to_far() {
        let mut camera = Camera::look_at(Vec3::ZERO, Vec3::NEG_Z);
        (camera.near, camera.far) = (0.5, 500.0);
        let s = Slicing::new(&camera);
        assert!((s.start(0) - 0.5).abs() < 1e-6);
        assert!((s.start(CLUSTER_SLICES) - 500.0).abs() < 1e-2);
        let ratio = s.start(1) / s.start(0);
        for k in 0..CLUSTER_SLICES {
            assert!((s.start(k + 1) / s.start(k) - ratio).abs() < 1e-4);
            let mid = (s.start(k) * s.start(k + 1)).sqrt();
            assert_eq!(s.slice(mid), k);
        }
        assert_eq!(s.slice(0.01), 0);
        assert_eq!(s.slice(1e6), CLUSTER_SLICES - 1);
    }

    #[test]
    fn frustum_culling_keeps_lights_that_reach_the_view() {
        let mut camera = Camera::look_at(Vec3::ZERO, Vec3::NEG_Z);
        (camera.near, camera.far) = (0.1, 100.0);
        let light = |x: f32, z: f32, r: f32| GpuLight {
            position: [x, 0.0, z],
            radius: r,
            ..bytemuck::Zeroable::zeroed()
        };
        let lights = [
            light(0.0, -10.0, 1.0),   // in view
            light(0.0, 10.0, 1.0),    // behind the eye
            light(0.0, 1.0, 1.5),     // behind, but its sphere crosses the near plane
            light(50.0, -10.0, 1.0),  // far to the right
            light(0.0, -200.0, 50.0), // beyond the far plane
        ];
        assert_eq!(frustum_cull(&camera, 1.0, &lights), vec![0, 2]);
    }
}
