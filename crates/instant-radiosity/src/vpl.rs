//! Virtual point lights by instant radiosity (Keller 1997, as used by Segovia 2006 §6 and
//! summarised in Holländer 2013 §3.4): photons are shot from the primary lights through the
//! scene BVH and a hemispherical VPL is placed at each first hit, carrying the photon's flux ×
//! the surface albedo (one bounce, §6.2).
//!
//! The VPLs come in `subsets` equally sized groups, one per interleaved sub-buffer (§4.3).
//! Each group is the prefix of its own Halton sequence shifted by a seeded Cranley–Patterson
//! rotation, so every group is a stratified, representative sample of the light paths and
//! their union is the VPL set of the non-interleaved reference. A group shoots photons until
//! it has placed its VPLs; a photon that misses the scene or carries no flux (beyond a
//! light's radius, outside a spot cone) places none but still counts: each VPL's flux is
//! `Φ_light / (p_light · photons) / subsets · albedo`, so the union estimates the reflected
//! flux and one group, scaled by `subsets`, estimates it too.
//!
//! ```
//! use instant_radiosity::vpl::{VplConfig, generate};
//! let scene = scene::cornell_box();
//! let bvh = scene::Bvh::build(&scene);
//! let config = VplConfig { count: 256, subsets: 16, seed: 7, emissive: false, bounces: 1 };
//! let set = generate(&scene, &bvh, &scene.lights, &config)?;
//! assert_eq!(set.vpls.len(), 256);
//! assert_eq!(set.per_subset, 16);
//! # Ok::<(), instant_radiosity::vpl::VplError>(())
//! ```

use std::f32::consts::PI;

use glam::Vec3;
use rayon::prelude::*;
use scene::{Aabb, Bvh, Light, Scene};
use scene::{SceneTextures, SurfaceAttributes};

/// Fewest and most VPLs a set may hold.
pub const VPL_RANGE: std::ops::RangeInclusive<usize> = 16..=16384;

/// A hemispherical virtual point light: radiant intensity `flux / π · cos θ` around `normal`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vpl {
    /// Position on the surface.
    pub position: Vec3,
    /// Unit surface normal, facing the side the photon came from.
    pub normal: Vec3,
    /// Reflected flux (photon flux × albedo), linear RGB.
    pub flux: Vec3,
}

/// A VPL as the shaders see it (WGSL `Vpl` in `instant-radiosity/vpl.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuVpl {
    /// Position.
    pub position: [f32; 3],
    /// Padding.
    pub _pad0: f32,
    /// Unit normal.
    pub normal: [f32; 3],
    /// Padding.
    pub _pad1: f32,
    /// Flux.
    pub flux: [f32; 3],
    /// Padding.
    pub _pad2: f32,
}

impl From<&Vpl> for GpuVpl {
    fn from(v: &Vpl) -> Self {
        Self {
            position: v.position.to_array(),
            _pad0: 0.0,
            normal: v.normal.to_array(),
            _pad1: 0.0,
            flux: v.flux.to_array(),
            _pad2: 0.0,
        }
    }
}

/// What to generate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VplConfig {
    /// Total number of VPLs, in [`VPL_RANGE`] and a multiple of `subsets`
    /// (see [`per_subset`] to round a request).
    pub count: usize,
    /// Number of equally sized subsets (the sub-buffer count n·m; 1 for no interleaving).
    pub subsets: u32,
    /// Seed of the Cranley–Patterson rotations: the same seed gives the same VPLs.
    pub seed: u64,
    /// Also shoot photons from the scene's emissive triangles (Lambertian area lights). Leave
    /// it off when `lights` already stand for them (see [`area_lights`]'s stand-ins, or a
    /// point light placed under a lamp).
    pub emissive: bool,
    /// VPLs per photon path at most: 1 places them where photons first land (one bounce of
    /// indirect light); more continue each photon's Lambertian reflection by Russian roulette
    /// and place one at every later hit (Keller 1997: multi-bounce instant radiosity).
    pub bounces: u32,
}

/// Generated VPLs, subset-major: subset `s` is `vpls[s·per_subset .. (s+1)·per_subset]`.
#[derive(Clone, Debug, PartialEq)]
pub struct VplSet {
    /// The VPLs.
    pub vpls: Vec<Vpl>,
    /// Number of subsets.
    pub subsets: u32,
    /// VPLs per subset.
    pub per_subset: u32,
    /// Photons shot per subset (hits and misses).
    pub photons: Vec<u64>,
}

impl VplSet {
    /// The VPLs of subset `s`.
    pub fn subset(&self, s: u32) -> &[Vpl] {
        let k = self.per_subset as usize;
        &self.vpls[s as usize * k..(s as usize + 1) * k]
    }

    /// The VPLs in the layout of the shaders.
    pub fn gpu(&self) -> Vec<GpuVpl> {
        self.vpls.iter().map(GpuVpl::from).collect()
    }
}

/// Errors of VPL generation.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum VplError {
    /// The count is outside [`VPL_RANGE`] or not a multiple of the subset count.
    #[error(
        "{count} VPLs cannot be split into {subsets} equal subsets: use a multiple of {subsets} between {} and {}",
        VPL_RANGE.start(),
        VPL_RANGE.end()
    )]
    Count {
        /// Requested total.
        count: usize,
        /// Subsets.
        subsets: u32,
    },
    /// Neither the light list nor the scene's emissive materials emit anything.
    #[error("no primary light emits any flux: add a light or an emissive material")]
    NoEmitter,
    /// Too few photons hit the scene with non-zero flux.
    #[error(
        "only {placed} of {wanted} VPLs placed after {photons} photons: the lights barely reach the scene"
    )]
    TooFewHits {
        /// VPLs placed in the worst subset.
        placed: usize,
        /// VPLs wanted per subset.
        wanted: usize,
        /// Photons shot in that subset.
        photons: u64,
    },
    /// A light has non-finite or negative parameters.
    #[error("light {0}: {1}")]
    InvalidLight(usize, String),
}

/// VPLs per subset for a requested total: `round(count / subsets)`, at least 1, so the set
/// holds `per_subset · subsets` VPLs (the paper's 480 VPLs in 8×6 sub-buffers give 10 each).
pub fn per_subset(count: usize, subsets: u32) -> u32 {
    let s = subsets.max(1) as usize;
    ((count + s / 2) / s).max(1) as u32
}

/// Photons shot per subset before giving up: `ATTEMPTS × per_subset`.
const ATTEMPTS: u64 = 256;

/// Radical inverse of `i` in `base` (the Halton sequence's coordinate).
pub fn radical_inverse(mut i: u64, base: u64) -> f32 {
    let inv = 1.0 / base as f64;
    let (mut result, mut f) = (0.0f64, inv);
    while i > 0 {
        result += (i % base) as f64 * f;
        i /= base;
        f *= inv;
    }
    result as f32
}

const HALTON_BASES: [u64; 5] = [2, 3, 5, 7, 11];

/// Point `i` of the 5-D Halton sequence shifted by `rotation` (modulo 1).
fn halton(i: u64, rotation: &[f32; 5]) -> [f32; 5] {
    std::array::from_fn(|d| {
        let x = radical_inverse(i, HALTON_BASES[d]) + rotation[d];
        let x = x - x.floor();
        if x >= 1.0 { 0.0 } else { x }
    })
}

/// The seeded Cranley–Patterson rotation of subset `s` (SplitMix64 of seed and subset).
fn rotation(seed: u64, s: u32) -> [f32; 5] {
    let mut state = seed ^ (u64::from(s) + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    std::array::from_fn(|_| {
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    })
}

/// Direction around `n` with `cos θ` and azimuth `2π·u`.
fn around(n: Vec3, cos_theta: f32, u: f32) -> Vec3 {
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    let (t, b) = scene::orthonormal_basis(n);
    let phi = 2.0 * PI * u;
    (t * phi.cos() + b * phi.sin()) * sin_theta + n * cos_theta
}

/// Cosine-weighted direction around `n` (pdf cos θ / π).
fn cosine_direction(n: Vec3, u: f32, v: f32) -> Vec3 {
    around(n, (1.0 - u).sqrt(), v)
}

/// The distance window of point, spot and hemispherical lights, `saturate(1 − (d/r)⁴)²`
/// (`pipeline::cpu::distance_attenuation` without the `1/d²`, which the photon density
/// carries).
fn window(d: f32, radius: f32) -> f32 {
    let x2 = (d / radius) * (d / radius);
    let w = (1.0 - x2 * x2).clamp(0.0, 1.0);
    w * w
}

/// A primary light as a photon source.
enum Emitter {
    Light(Light),
    /// One emissive triangle: a Lambertian area light of radiance `radiance`.
    Triangle {
        v: [Vec3; 3],
        normal: Vec3,
        area: f32,
        radiance: Vec3,
    },
}

/// One photon: ray, its flux when it hits at distance `d` (`weight(d)`), before the albedo.
#[derive(Clone, Copy)]
struct Photon {
    origin: Vec3,
    direction: Vec3,
    t_max: f32,
    flux: Vec3,
    /// Radius of the distance window (infinite for directional and area lights).
    radius: f32,
}

impl Emitter {
    /// Total emitted flux (RGB) of the emitter as a photon source. A directional light's is
    /// its irradiance times the disc that covers `bounds`.
    fn flux(&self, bounds: &Aabb) -> Vec3 {
        match *self {
            Emitter::Light(Light::Point {
                color, intensity, ..
            }) => color * intensity * 4.0 * PI,
            Emitter::Light(Light::Spot {
                color,
                intensity,
                outer_angle,
                ..
            }) => color * intensity * 2.0 * PI * (1.0 - outer_angle.cos()),
            Emitter::Light(Light::Hemispherical {
                color, intensity, ..
            }) => color * intensity * PI,
            Emitter::Light(Light::Directional {
                color, intensity, ..
            }) => {
                let r = 0.5 * bounds.diagonal();
                color * intensity * PI * r * r
            }
            Emitter::Triangle { area, radiance, .. } => radiance * PI * area,
        }
    }

    /// The photon of sample `u` carrying `flux` (this emitter's share of the photon budget).
    fn photon(&self, u: &[f32; 5], flux: Vec3, bounds: &Aabb) -> Photon {
        let diag = bounds.diagonal();
        match *self {
            Emitter::Light(Light::Point {
                position, radius, ..
            }) => {
                let z = 1.0 - 2.0 * u[1];
                Photon {
                    origin: position,
                    direction: around(Vec3::Z, z, u[2]),
                    t_max: radius,
                    flux,
                    radius,
                }
            }
            Emitter::Light(Light::Spot {
                position,
                direction,
                radius,
                inner_angle,
                outer_angle,
                ..
            }) => {
                let (cos_outer, cos_inner) = (outer_angle.cos(), inner_angle.cos());
                let cos_theta = 1.0 - u[1] * (1.0 - cos_outer);
                let t =
                    ((cos_theta - cos_outer) / (cos_inner - cos_outer).max(1e-4)).clamp(0.0, 1.0);
                Photon {
                    origin: position,
                    direction: around(direction, cos_theta, u[2]),
                    t_max: radius,
                    flux: flux * (t * t * (3.0 - 2.0 * t)),
                    radius,
                }
            }
            Emitter::Light(Light::Hemispherical {
                position,
                direction,
                radius,
                ..
            }) => Photon {
                origin: position,
                direction: cosine_direction(direction, u[1], u[2]),
                t_max: radius,
                flux,
                radius,
            },
            Emitter::Light(Light::Directional { direction, .. }) => {
                let r = 0.5 * diag;
                let (t, b) = scene::orthonormal_basis(direction);
                let disc =
                    (u[1].sqrt() * r) * (t * (2.0 * PI * u[2]).cos() + b * (2.0 * PI * u[2]).sin());
                Photon {
                    origin: bounds.center() - direction * (2.0 * r) + disc,
                    direction,
                    t_max: 4.0 * r,
                    flux,
                    radius: f32::INFINITY,
                }
            }
            Emitter::Triangle { v, normal, .. } => {
                let (a, b) = if u[3] + u[4] > 1.0 {
                    (1.0 - u[3], 1.0 - u[4])
                } else {
                    (u[3], u[4])
                };
                let p = v[0] + (v[1] - v[0]) * a + (v[2] - v[0]) * b;
                Photon {
                    origin: p + normal * (1e-4 * diag),
                    direction: cosine_direction(normal, u[1], u[2]),
                    t_max: 2.0 * diag,
                    flux,
                    radius: f32::INFINITY,
                }
            }
        }
    }
}

/// The meshes whose material is a light ([`scene::Material::is_light`]: uniform emission).
fn emissive_meshes(scene: &Scene) -> impl Iterator<Item = (&scene::Mesh, &scene::Material)> {
    scene.meshes.iter().filter_map(|mesh| {
        let material = scene.materials.get(mesh.material as usize)?;
        material.is_light().then_some((mesh, material))
    })
}

/// The emissive triangles of `scene` (materials with non-zero emissive radiance) as
/// Lambertian area lights emitting on the side their winding faces.
fn area_emitters(scene: &Scene) -> Vec<Emitter> {
    let mut out = Vec::new();
    for (mesh, material) in emissive_meshes(scene) {
        for t in mesh.indices.chunks_exact(3) {
            let v = [t[0], t[1], t[2]].map(|i| mesh.positions[i as usize]);
            let cross = (v[1] - v[0]).cross(v[2] - v[0]);
            let area = 0.5 * cross.length();
            if area > 0.0 && area.is_finite() {
                out.push(Emitter::Triangle {
                    v,
                    normal: cross.normalize(),
                    area,
                    radiance: material.emissive,
                });
            }
        }
    }
    out
}

/// Hemispherical point lights standing in for the scene's emissive meshes in direct shading
/// (photons are then shot from the triangles themselves with [`VplConfig::emissive`]):
/// `samples` per mesh, each with intensity `radiance × area / samples` (a small Lambertian
/// emitter's intensity along its normal), reaching eight scene diagonals. One sample sits
/// at the mesh's area-weighted centroid along its mean normal; more are stratified over its
/// area (the triangles by their share of the area, a Halton coordinate within each) along
/// their triangle's normal, so shadowed they draw the area light's penumbrae.
pub fn area_lights(scene: &Scene, samples: u32) -> Vec<Light> {
    area_lights_frame(scene, samples, 0)
}

/// [`area_lights`] for frame `frame` of a progressive render (Segovia 2006 §6.3: new light
/// samples each frame): sample `i` keeps its stratum of the area, and within it both of its
/// coordinates (along the stratum, and across its triangle: base-2 radical inverse of `i`)
/// shift by the frame's point of the 2-D Halton sequence in bases 3 and 5 (a Cranley–Patterson
/// rotation), so over the frames every stratum is covered uniformly and the mean converges to
/// the area light. (Continuing one base-2 sequence across frames for the second coordinate
/// would not: its first digits are those of `i`, so each stratum would only ever see one band
/// of it.) Frame 0 is [`area_lights`]; a single sample stays at the centroid in every frame.
pub fn area_lights_frame(scene: &Scene, samples: u32, frame: u32) -> Vec<Light> {
    // The distance window `(1 − (d/r)⁴)²` the lights share is ≥ 0.9995 within the scene at
    // 8 diagonals (an emitter has none), and the shadow views' near plane is r / 1000. The
    // lift off the surface moves a grazing receiver's cos θ by lift / height, so it is tiny.
    let diagonal = scene.bounds().diagonal().max(1e-3);
    let radius = 8.0 * diagonal;
    let lift = 1e-5 * diagonal;
    let mut lights = Vec::new();
    for (mesh, material) in emissive_meshes(scene) {
        let triangles: Vec<([Vec3; 3], Vec3, f32)> = mesh
            .indices
            .chunks_exact(3)
            .map(|t| {
                let v = [t[0], t[1], t[2]].map(|i| mesh.positions[i as usize]);
                let cross = (v[1] - v[0]).cross(v[2] - v[0]);
                (v, cross, 0.5 * cross.length())
            })
            .filter(|(_, _, a)| *a > 0.0 && a.is_finite())
            .collect();
        let area: f32 = triangles.iter().map(|t| t.2).sum();
        let normal: Vec3 = triangles.iter().map(|t| t.1 * 0.5).sum();
        let (Some(mean_normal), true) = (normal.try_normalize(), area > 0.0) else {
            continue;
        };
        let radiance = material.emissive.max_element();
        let light = |position: Vec3, direction: Vec3, share: f32| Light::Hemispherical {
            position: position + direction * lift,
            direction,
            color: material.emissive / radiance,
            intensity: radiance * share,
            radius,
        };
        if samples <= 1 {
            let centroid: Vec3 = triangles
                .iter()
                .map(|(v, _, a)| (v[0] + v[1] + v[2]) / 3.0 * *a)
                .sum();
            lights.push(light(centroid / area, mean_normal, area));
            continue;
        }
        let mut start = 0.0;
        let mut t = 0;
        let shift = (0.5 + radical_inverse(u64::from(frame), 3)).fract();
        for i in 0..samples {
            // Stratified position along the cumulative area, then within its triangle.
            let u = (i as f32 + shift) / samples as f32 * area;
            while t + 1 < triangles.len() && start + triangles[t].2 < u {
                start += triangles[t].2;
                t += 1;
            }
            let (v, cross, a) = triangles[t];
            let r1 = ((u - start) / a).clamp(0.0, 1.0).sqrt();
            let r2 =
                (radical_inverse(u64::from(i), 2) + radical_inverse(u64::from(frame), 5)).fract();
            let p = v[0] * (1.0 - r1) + v[1] * (r1 * (1.0 - r2)) + v[2] * (r1 * r2);
            lights.push(light(p, cross.normalize(), area / samples as f32));
        }
    }
    lights
}

/// The material of `triangle` of mesh `mesh` evaluated at barycentrics `(u, v)`
/// ([`scene::Material::evaluate`], level 0 of each texture): its albedo is what a photon's
/// VPL reflects.
pub(crate) fn material_at(
    scene: &Scene,
    textures: &SceneTextures,
    (mesh, triangle): (u32, u32),
    (u, v): (f32, f32),
) -> Option<scene::MaterialSample> {
    let mesh = &scene.meshes[mesh as usize];
    let material = scene.materials.get(mesh.material as usize)?;
    let i = triangle as usize * 3;
    let idx = [0, 1, 2].map(|k| mesh.indices[i + k] as usize);
    let [a, b, c] = idx.map(|k| mesh.positions[k]);
    let normal = (b - a).cross(c - a).normalize_or(Vec3::Z);
    let at = SurfaceAttributes::blend(mesh, idx, [1.0 - u - v, u, v], normal, false);
    Some(material.evaluate(textures, &at, 1))
}

/// The VPLs a photon places: one where it first hits the scene with non-zero flux, and with
/// `bounces` > 1 one more at each later hit (within `reach`) of its Lambertian reflection,
/// which continues by Russian roulette on the albedo (`random(g)`: five uniforms for bounce g).
fn place(
    scene: &Scene,
    bvh: &Bvh,
    textures: &SceneTextures,
    photon: &Photon,
    (bounces, reach): (u32, f32),
    random: impl Fn(u32) -> [f32; 5],
) -> Vec<Vpl> {
    let mut vpls = Vec::new();
    let mut photon = *photon;
    for g in 0..bounces {
        let Some(hit) = bvh.closest_hit(photon.origin, photon.direction, photon.t_max) else {
            break;
        };
        let w = if photon.radius.is_finite() {
            window(hit.t, photon.radius)
        } else {
            1.0
        };
        let mesh = &scene.meshes[hit.mesh as usize];
        let i = hit.triangle as usize * 3;
        let [a, b, c] = [0, 1, 2].map(|k| mesh.positions[mesh.indices[i + k] as usize]);
        let Some(normal) = (b - a).cross(c - a).try_normalize() else {
            break;
        };
        let normal = if normal.dot(photon.direction) > 0.0 {
            -normal
        } else {
            normal
        };
        let albedo = material_at(
            scene,
            textures,
            (hit.mesh, hit.triangle),
            (hit.barycentrics.x, hit.barycentrics.y),
        )
        .map_or(Vec3::ZERO, |m| m.albedo);
        let flux = photon.flux * w * albedo;
        if !(flux.max_element() > 0.0 && flux.is_finite()) {
            break;
        }
        vpls.push(Vpl {
            position: hit.position,
            normal,
            flux,
        });
        // The reflected flux leaves cosine-distributed; it survives with probability q and
        // then carries flux / q (unbiased).
        let u = random(g);
        let q = albedo.max_element().min(0.95);
        if g + 1 == bounces || u[2] >= q {
            break;
        }
        photon = Photon {
            origin: hit.position + normal * (1e-4 * reach),
            direction: cosine_direction(normal, u[0], u[1]),
            t_max: reach,
            flux: flux / q,
            radius: f32::INFINITY,
        };
    }
    vpls
}

/// Generates `config.count` VPLs in `config.subsets` subsets from `lights` and the scene's
/// emissive triangles, deterministically for `config.seed`.
pub fn generate(
    scene: &Scene,
    bvh: &Bvh,
    lights: &[Light],
    config: &VplConfig,
) -> Result<VplSet, VplError> {
    let subsets = config.subsets.max(1);
    if !VPL_RANGE.contains(&config.count) || !config.count.is_multiple_of(subsets as usize) {
        return Err(VplError::Count {
            count: config.count,
            subsets,
        });
    }
    tiled_shading::gpu_lights(lights).map_err(|e| match e {
        tiled_shading::ShadingError::InvalidLight { index, problem } => {
            VplError::InvalidLight(index, problem)
        }
        other => VplError::InvalidLight(0, other.to_string()),
    })?;
    let bounds = scene.bounds();
    let mut emitters: Vec<Emitter> = lights.iter().copied().map(Emitter::Light).collect();
    if config.emissive {
        emitters.extend(area_emitters(scene));
    }
    let power: Vec<f32> = emitters
        .iter()
        .map(|e| e.flux(&bounds).element_sum() / 3.0)
        .collect();
    let total: f32 = power.iter().sum();
    if !(total > 0.0 && total.is_finite()) {
        return Err(VplError::NoEmitter);
    }
    let cdf: Vec<f32> = power
        .iter()
        .scan(0.0, |acc, p| {
            *acc += p / total;
            Some(*acc)
        })
        .collect();
    let textures = SceneTextures::new(scene, false);
    let k = config.count / subsets as usize;
    let bounces = config.bounces.max(1);
    let reach = 2.0 * bounds.diagonal();

    let results: Vec<(Vec<Vpl>, u64)> = (0..subsets)
        .into_par_iter()
        .map(|s| {
            let rot = rotation(config.seed, s);
            let mut vpls = Vec::with_capacity(k);
            let mut shot = 0u64;
            let limit = ATTEMPTS * k as u64;
            while vpls.len() < k && shot < limit {
                let batch = ((k - vpls.len()) as u64).max(64).min(limit - shot);
                let placed: Vec<Vec<Vpl>> = (shot..shot + batch)
                    .into_par_iter()
                    .map(|i| {
                        let u = halton(i, &rot);
                        let e = cdf.partition_point(|&c| c <= u[0]).min(emitters.len() - 1);
                        let share = emitters[e].flux(&bounds) * (total / power[e]);
                        let photon = emitters[e].photon(&u, share, &bounds);
                        // Bounce g of photon i of subset s: its own SplitMix64 stream.
                        let path = config.seed.rotate_left(24) ^ (u64::from(s) << 48) ^ i;
                        let random = |g: u32| rotation(path, 1 + g);
                        place(scene, bvh, &textures, &photon, (bounces, reach), random)
                    })
                    .collect();
                // Photons count up to the one that places the last VPL (whose path may be
                // cut short there).
                let mut used = batch;
                'photons: for (j, path) in placed.into_iter().enumerate() {
                    for v in path {
                        vpls.push(v);
                        if vpls.len() == k {
                            used = j as u64 + 1;
                            break 'photons;
                        }
                    }
                }
                shot += used;
            }
            (vpls, shot)
        })
        .collect();
    if let Some((vpls, shot)) = results.iter().find(|(v, _)| v.len() < k) {
        return Err(VplError::TooFewHits {
            placed: vpls.len(),
            wanted: k,
            photons: *shot,
        });
    }
    let mut set = VplSet {
        vpls: Vec::with_capacity(config.count),
        subsets,
        per_subset: k as u32,
        photons: Vec::with_capacity(subsets as usize),
    };
    for (vpls, shot) in results {
        let scale = 1.0 / (shot as f32 * subsets as f32);
        set.vpls.extend(vpls.into_iter().map(|v| Vpl {
            flux: v.flux * scale,
            ..v
        }));
        set.photons.push(shot);
    }
    Ok(set)
}

/// VPLs shot from `scene`'s [`primary_lights`] (and from its emissive triangles where
/// those lights stand in for them): `count` rounded to whole subsets ([`per_subset`]), with
/// the rotations of `seed`.
pub fn generate_from_primary(
    scene: &Scene,
    bvh: &Bvh,
    count: usize,
    subsets: u32,
    seed: u64,
) -> Result<VplSet, VplError> {
    let (lights, emissive, _) = primary_lights(scene);
    let config = VplConfig {
        count: per_subset(count, subsets) as usize * subsets.max(1) as usize,
        subsets,
        seed,
        emissive,
        bounces: 1,
    };
    generate(scene, bvh, photon_lights(&lights, emissive), &config)
}

/// The lights photons leave besides the emissive triangles: none where `lights` are
/// [`primary_lights`]' stand-ins for those triangles (`emissive`; shooting from both would
/// count the lamps' flux twice), else `lights`.
pub fn photon_lights(lights: &[Light], emissive: bool) -> &[Light] {
    if emissive { &[] } else { lights }
}

/// The primary lights of a scene, whether photons must also leave its emissive triangles
/// ([`VplConfig::emissive`]) and a description: the scene's punctual lights; else
/// hemispherical stand-ins for its emissive meshes ([`area_lights`]); else a default sun.
pub fn primary_lights(scene: &Scene) -> (Vec<Light>, bool, &'static str) {
    primary_lights_sampled(scene, 1)
}

/// [`primary_lights`] with `area_samples` hemispherical lights per emissive mesh
/// ([`area_lights`]).
pub fn primary_lights_sampled(
    scene: &Scene,
    area_samples: u32,
) -> (Vec<Light>, bool, &'static str) {
    primary_lights_frame(scene, area_samples, 0)
}

/// [`primary_lights_sampled`] for frame `frame` of a progressive render: the emissive meshes'
/// samples of [`area_lights_frame`] (punctual lights and the default sun are the same in every
/// frame).
pub fn primary_lights_frame(
    scene: &Scene,
    area_samples: u32,
    frame: u32,
) -> (Vec<Light>, bool, &'static str) {
    if !scene.lights.is_empty() {
        return (scene.lights.clone(), false, "the scene's lights");
    }
    let area = area_lights_frame(scene, area_samples, frame);
    if !area.is_empty() {
        return (area, true, "the emissive meshes (as hemispherical lights)");
    }
    let sun = Light::Directional {
        direction: Vec3::new(0.3, -1.0, 0.25).normalize(),
        color: Vec3::new(1.0, 0.95, 0.85),
        intensity: 3.0,
    };
    (vec![sun], false, "a default sun (the scene has no lights)")
}
