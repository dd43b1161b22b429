//! The ground truth: a CPU path tracer on the [`Bvh`] (rayon), sharing no code with the
//! rasteriser but the scene types. It renders what the renderer models, with shadows and
//! interreflections: the same BRDF (Lambert `albedo·(1 − metallic)/π` plus GGX `D·V·F` with
//! α = roughness², Smith height-correlated visibility and Schlick's Fresnel from
//! `F0 = lerp(0.04, albedo, metallic)`, the dielectric term scaled by the material's specular
//! factor), the same punctual lights with their finite-radius
//! attenuation `saturate(1 − (d/r)⁴)² / max(d², 10⁻⁴)` (spot smoothstep cone, hemispherical
//! `cos`), and emissive triangles as true area lights (Lambertian, on the side of their
//! normal) instead of the rasteriser's point stand-ins.
//!
//! Next-event estimation at every path vertex (punctual and area lights, shadow rays), BRDF
//! sampling (cosine-weighted diffuse, GGX half vectors) combined with area-light sampling by
//! the power heuristic, and a bounce limit: `max_bounces = 0` is direct light only, `1` adds
//! one bounce (what instant radiosity's VPLs approximate). Deterministic per seed whatever the
//! thread count, and progressive: [`PathTracer::add_samples`] continues the same sequence.
//!
//! ```no_run
//! let scene = scene::cornell_box();
//! let camera = scene.camera_or_framed();
//! let config = scene::reference::ReferenceConfig { max_bounces: 1, ..Default::default() };
//! let mut pt = scene::reference::PathTracer::new(&scene, camera, 256, 256, &scene.lights, config);
//! pt.add_samples(64);
//! let radiance: Vec<glam::Vec3> = pt.image();
//! ```

use std::f32::consts::{FRAC_1_PI, PI};

use glam::Vec3;
use rayon::prelude::*;

use crate::{
    Bvh, Camera, Light, MaterialSample, Scene, SceneTextures, SurfaceAttributes, luminance,
};

/// How far a ray leaves a surface at `p`: 10⁻⁴ of (1 + its largest coordinate), so the
/// surface does not hit itself in f32 at any distance from the origin. The renderer's shadow
/// and VPL rays leave by the same rule (`tiled_shading::rays`), so both see the same
/// occluders a few millimetres off a wall.
pub fn ray_lift(p: Vec3) -> f32 {
    1e-4 * (1.0 + p.abs().max_element())
}

/// How the reference renders.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReferenceConfig {
    /// Bounces after the first surface: 0 = direct light only, 1 = one indirect bounce.
    pub max_bounces: u32,
    /// Light with fewer bounces is left out: 0 (default) keeps everything; 1 with
    /// `max_bounces = 1` is the one-bounce indirect light alone, what instant radiosity's VPLs
    /// add to the direct light. The random sequence does not depend on it, so for the same
    /// seed the image with `min_bounces = 0` is the sum of those with 0..1 and 1..max bounces.
    pub min_bounces: u32,
    /// Seed of every random decision.
    pub seed: u64,
    /// Include the GGX specular lobe (default). `false` leaves the Lambert lobe alone: the
    /// furnace test's analytic case.
    pub specular: bool,
    /// Jitter the camera rays over each pixel (default: the pixel's box-filtered radiance).
    /// `false` traces through pixel centres only, where a rasteriser without antialiasing
    /// samples: per-pixel measures (RMS) then compare like with like at silhouettes.
    pub jitter: bool,
}

impl Default for ReferenceConfig {
    /// One bounce (all light up to it), seed 1, the full BRDF.
    fn default() -> Self {
        Self {
            max_bounces: 1,
            min_bounces: 0,
            seed: 1,
            specular: true,
            jitter: true,
        }
    }
}

/// An emissive triangle of a light ([`crate::Material::is_light`]): corners, emitted
/// radiance, area.
#[derive(Clone, Copy, Debug)]
struct Emitter {
    v: [Vec3; 3],
    normal: Vec3,
    radiance: Vec3,
    area: f32,
}

/// A progressive path tracer of one view.
pub struct PathTracer<'s> {
    scene: &'s Scene,
    bvh: Bvh,
    camera: Camera,
    width: u32,
    height: u32,
    lights: Vec<Light>,
    config: ReferenceConfig,
    emitters: Vec<Emitter>,
    /// Cumulative emitter power (area × luminance), for choosing one.
    emitter_cdf: Vec<f32>,
    /// Emitter index of each (mesh, triangle), for MIS on BRDF-sampled hits.
    emitter_of: Vec<Vec<Option<u32>>>,
    /// The scene's textures decoded for sampling (level 0, as the CPU G-buffer's sampler
    /// reads it when magnifying).
    textures: SceneTextures,
    sums: Vec<[f64; 3]>,
    samples: u32,
}

/// PCG32 (O'Neill), seeded per pixel and sample so that results do not depend on threads.
struct Rng(u64);

impl Rng {
    fn new(seed: u64, pixel: u64, sample: u64) -> Self {
        let mut r = Self(
            seed.wrapping_mul(0x9E37_79B9_7F4A_7C15)
                ^ pixel.wrapping_mul(0xD1B5_4A32_D192_ED03)
                ^ sample.wrapping_mul(0x8CB9_2BA7_2F3D_8DD7),
        );
        r.next();
        r.next();
        r
    }
    fn next(&mut self) -> u32 {
        let old = self.0;
        self.0 = old
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        xorshifted.rotate_right((old >> 59) as u32)
    }
    /// Uniform in \[0, 1).
    fn f(&mut self) -> f32 {
        (self.next() >> 8) as f32 * (1.0 / 16_777_216.0)
    }
}

/// The surface at a hit, as the BRDF needs it.
struct Surface {
    p: Vec3,
    /// Shading normal (interpolated), facing the incoming ray.
    n: Vec3,
    /// Geometric normal, same side as `n`.
    ng: Vec3,
    albedo: Vec3,
    roughness: f32,
    metallic: f32,
    /// Scale of the dielectric F0 ([`crate::Material::specular`]).
    specular: f32,
}

impl Surface {
    /// The Fresnel reflectance at normal incidence (the dielectric's scaled by the specular
    /// factor).
    fn f0(&self) -> Vec3 {
        Vec3::splat(0.04 * self.specular).lerp(self.albedo, self.metallic)
    }

    /// Schlick's Fresnel at `v_dot_h`: dielectric (scaled by the specular factor, as in
    /// `KHR_materials_specular`) blended with metal by the metalness.
    fn fresnel(&self, v_dot_h: f32) -> Vec3 {
        let fw = (1.0 - v_dot_h).powi(5);
        let metal = self.albedo + (Vec3::ONE - self.albedo) * fw;
        Vec3::splat(self.specular * (0.04 + 0.96 * fw)).lerp(metal, self.metallic)
    }

    fn alpha(&self) -> f32 {
        (self.roughness * self.roughness).max(1e-3)
    }

    /// `f(l, v)` of the renderer's BRDF (without the cosine).
    fn brdf(&self, l: Vec3, v: Vec3, specular: bool) -> Vec3 {
        let diffuse = self.albedo * (1.0 - self.metallic) * FRAC_1_PI;
        let n_dot_l = self.n.dot(l);
        if n_dot_l <= 0.0 {
            return Vec3::ZERO;
        }
        if !specular {
            return diffuse;
        }
        let h = (l + v).normalize_or_zero();
        let n_dot_v = self.n.dot(v).clamp(1e-4, 1.0);
        let n_dot_h = self.n.dot(h).clamp(0.0, 1.0);
        let v_dot_h = v.dot(h).clamp(0.0, 1.0);
        let a2 = self.alpha() * self.alpha();
        let k = n_dot_h * n_dot_h * (a2 - 1.0) + 1.0;
        let d = a2 * FRAC_1_PI / (k * k);
        let vis = 0.5
            / (n_dot_l * (n_dot_v * n_dot_v * (1.0 - a2) + a2).sqrt()
                + n_dot_v * (n_dot_l * n_dot_l * (1.0 - a2) + a2).sqrt());
        let f = self.fresnel(v_dot_h);
        diffuse + f * (d * vis)
    }

    /// Probability of sampling the specular lobe.
    fn specular_probability(&self, specular: bool) -> f32 {
        if !specular {
            return 0.0;
        }
        let w_d = luminance(self.albedo) * (1.0 - self.metallic);
        let w_s = luminance(self.f0());
        if w_s <= 0.0 {
            return 0.0;
        }
        (w_s / (w_d + w_s).max(1e-6)).clamp(0.1, 0.9)
    }

    /// Solid-angle pdf of [`Surface::sample`] choosing `l`.
    fn pdf(&self, l: Vec3, v: Vec3, specular: bool) -> f32 {
        let cos = self.n.dot(l);
        if cos <= 0.0 {
            return 0.0;
        }
        let ps = self.specular_probability(specular);
        let diffuse = cos * FRAC_1_PI;
        if ps == 0.0 {
            return diffuse;
        }
        let h = (l + v).normalize_or_zero();
        let n_dot_h = self.n.dot(h).max(0.0);
        let a2 = self.alpha() * self.alpha();
        let k = n_dot_h * n_dot_h * (a2 - 1.0) + 1.0;
        let d = a2 * FRAC_1_PI / (k * k);
        let spec = d * n_dot_h / (4.0 * v.dot(h).max(1e-6));
        (1.0 - ps) * diffuse + ps * spec
    }

    /// A direction drawn from the mixture of the cosine lobe and GGX half vectors.
    fn sample(&self, v: Vec3, rng: &mut Rng, specular: bool) -> Vec3 {
        let (t, b) = crate::orthonormal_basis(self.n);
        let (u1, u2) = (rng.f(), rng.f());
        if rng.f() >= self.specular_probability(specular) {
            let r = u1.sqrt();
            let phi = 2.0 * PI * u2;
            return (t * (r * phi.cos()) + b * (r * phi.sin()) + self.n * (1.0 - u1).sqrt())
                .normalize();
        }
        let a2 = self.alpha() * self.alpha();
        let cos_h = ((1.0 - u1) / (1.0 + (a2 - 1.0) * u1)).sqrt();
        let sin_h = (1.0 - cos_h * cos_h).max(0.0).sqrt();
        let phi = 2.0 * PI * u2;
        let h = t * (sin_h * phi.cos()) + b * (sin_h * phi.sin()) + self.n * cos_h;
        (2.0 * v.dot(h) * h - v).normalize()
    }
}

impl<'s> PathTracer<'s> {
    /// A path tracer of `scene` seen by `camera` at `width × height`, lit by `lights` (the
    /// punctual ones) and the scene's emissive triangles.
    pub fn new(
        scene: &'s Scene,
        camera: Camera,
        width: u32,
        height: u32,
        lights: &[Light],
        config: ReferenceConfig,
    ) -> Self {
        let mut emitters = Vec::new();
        let mut emitter_cdf = Vec::new();
        let mut emitter_of = Vec::new();
        let mut total = 0.0;
        for m in &scene.meshes {
            let material = scene.materials.get(m.material as usize);
            let radiance = material.map_or(Vec3::ZERO, |mat| mat.emissive);
            let mut own = vec![None; m.triangle_count()];
            if material.is_some_and(|mat| mat.is_light()) && luminance(radiance) > 0.0 {
                for (t, tri) in m.indices.chunks_exact(3).enumerate() {
                    let v = [tri[0], tri[1], tri[2]].map(|i| m.positions[i as usize]);
                    let cross = (v[1] - v[0]).cross(v[2] - v[0]);
                    let area = 0.5 * cross.length();
                    if area <= 0.0 {
                        continue;
                    }
                    // The emitting side: the side of the vertex normals.
                    let shading: Vec3 = [tri[0], tri[1], tri[2]]
                        .iter()
                        .map(|&i| m.normals[i as usize])
                        .sum();
                    let mut normal = cross / (2.0 * area);
                    if normal.dot(shading) < 0.0 {
                        normal = -normal;
                    }
                    own[t] = Some(emitters.len() as u32);
                    total += area * luminance(radiance);
                    emitter_cdf.push(total);
                    emitters.push(Emitter {
                        v,
                        normal,
                        radiance,
                        area,
                    });
                }
            }
            emitter_of.push(own);
        }
        Self {
            scene,
            bvh: Bvh::build(scene),
            camera,
            width,
            height,
            lights: lights.to_vec(),
            config,
            emitters,
            emitter_cdf,
            emitter_of,
            textures: SceneTextures::new(scene, false),
            sums: vec![[0.0; 3]; width as usize * height as usize],
            samples: 0,
        }
    }

    /// Samples per pixel so far.
    pub fn samples(&self) -> u32 {
        self.samples
    }

    /// Adds `n` samples per pixel (continuing the sequence: 2 × 8 equals 16 at once).
    pub fn add_samples(&mut self, n: u32) {
        let (w, first) = (self.width as usize, self.samples);
        let this = &*self;
        let sums: Vec<[f64; 3]> = (0..self.sums.len())
            .into_par_iter()
            .map(|i| {
                // Each sample is added to the running sum in order, so the result does not
                // depend on how the samples are split between calls.
                let mut sum = this.sums[i];
                for s in first..first + n {
                    let mut rng = Rng::new(this.config.seed, i as u64, u64::from(s));
                    let c = this.radiance(((i % w) as u32, (i / w) as u32), &mut rng);
                    if c.is_finite() {
                        for k in 0..3 {
                            sum[k] += f64::from(c[k]);
                        }
                    }
                }
                sum
            })
            .collect();
        self.sums = sums;
        self.samples += n;
    }

    /// The mean radiance per pixel, row-major from the top-left.
    pub fn image(&self) -> Vec<Vec3> {
        let n = f64::from(self.samples.max(1));
        self.sums
            .iter()
            .map(|s| Vec3::new((s[0] / n) as f32, (s[1] / n) as f32, (s[2] / n) as f32))
            .collect()
    }

    /// The camera ray through a jittered point of pixel `(x, y)`.
    fn camera_ray(&self, (x, y): (u32, u32), rng: &mut Rng) -> (Vec3, Vec3) {
        let c = &self.camera;
        let forward = (c.target - c.eye).normalize_or(Vec3::NEG_Z);
        let up = if forward.cross(c.up).length_squared() < 1e-12 {
            Vec3::Z
        } else {
            c.up
        };
        let right = forward.cross(up).normalize();
        let up = right.cross(forward);
        let tan = (c.fov_y * 0.5).tan();
        let aspect = self.width as f32 / self.height as f32;
        let (jx, jy) = if self.config.jitter {
            (rng.f(), rng.f())
        } else {
            (0.5, 0.5)
        };
        let sx = (2.0 * (x as f32 + jx) / self.width as f32 - 1.0) * tan * aspect;
        let sy = (1.0 - 2.0 * (y as f32 + jy) / self.height as f32) * tan;
        (c.eye, (forward + right * sx + up * sy).normalize())
    }

    /// The surface at `hit` seen along `dir`, its material evaluated there
    /// ([`crate::Material::evaluate`], level 0 of each texture), and whether `dir` sees the
    /// back of the triangle's counter-clockwise winding.
    fn surface(&self, hit: &crate::Hit, dir: Vec3) -> (Surface, MaterialSample, bool) {
        let m = &self.scene.meshes[hit.mesh as usize];
        let t = hit.triangle as usize * 3;
        let idx = [m.indices[t], m.indices[t + 1], m.indices[t + 2]].map(|i| i as usize);
        let (u, v) = (hit.barycentrics.x, hit.barycentrics.y);
        let w = [1.0 - u - v, u, v];
        let vertex_normal = (0..3)
            .map(|k| m.normals[idx[k]] * w[k])
            .sum::<Vec3>()
            .normalize_or(Vec3::Y);
        let [p0, p1, p2] = idx.map(|i| m.positions[i]);
        let winding = (p1 - p0).cross(p2 - p0).normalize_or(vertex_normal);
        let back = winding.dot(dir) > 0.0;
        let ng = if back { -winding } else { winding };
        let n = crate::facing_shading_normal(vertex_normal, ng);
        let at = SurfaceAttributes::blend(m, idx, w, n, vertex_normal.dot(ng) < 0.0);
        let mat = &self.scene.materials[m.material as usize];
        let sample = mat.evaluate(&self.textures, &at, 1);
        (
            Surface {
                p: hit.position,
                n: sample.normal,
                ng,
                albedo: sample.albedo,
                roughness: sample.roughness,
                metallic: sample.metallic,
                specular: sample.specular,
            },
            sample,
            back,
        )
    }

    /// A point just off the surface on the side of `dir` ([`ray_lift`]).
    fn offset(s: &Surface, dir: Vec3) -> Vec3 {
        s.p + s.ng * ray_lift(s.p) * dir.dot(s.ng).signum()
    }

    fn visible(&self, s: &Surface, to: Vec3) -> bool {
        let origin = Self::offset(s, to - s.p);
        let d = to - origin;
        !self.bvh.any_hit(origin, d, 1.0 - 1e-4)
    }

    /// Punctual lights at `s` seen from `v` (next-event estimation, shadow rays).
    fn punctual(&self, s: &Surface, v: Vec3) -> Vec3 {
        let mut sum = Vec3::ZERO;
        for light in &self.lights {
            let (l, intensity, shadow_to) = match *light {
                Light::Directional {
                    direction,
                    color,
                    intensity,
                } => {
                    let l = -direction.normalize_or_zero();
                    (l, color * intensity, None)
                }
                Light::Point {
                    position,
                    color,
                    intensity,
                    radius,
                } => {
                    let (l, att) = attenuation(position, radius, s.p);
                    (l, color * intensity * att, Some(position))
                }
                Light::Spot {
                    position,
                    direction,
                    color,
                    intensity,
                    radius,
                    inner_angle,
                    outer_angle,
                } => {
                    let (l, att) = attenuation(position, radius, s.p);
                    let (cos_outer, cos_inner) = (
                        outer_angle.cos(),
                        inner_angle.cos().max(outer_angle.cos() + 1e-4),
                    );
                    let t = (((-l).dot(direction) - cos_outer) / (cos_inner - cos_outer))
                        .clamp(0.0, 1.0);
                    let cone = t * t * (3.0 - 2.0 * t);
                    (l, color * intensity * att * cone, Some(position))
                }
                Light::Hemispherical {
                    position,
                    direction,
                    color,
                    intensity,
                    radius,
                } => {
                    let (l, att) = attenuation(position, radius, s.p);
                    let cos = (-l).dot(direction).max(0.0);
                    (l, color * intensity * att * cos, Some(position))
                }
            };
            let cos = s.n.dot(l);
            if cos <= 0.0 || intensity.max_element() <= 0.0 {
                continue;
            }
            let visible = match shadow_to {
                Some(p) => self.visible(s, p),
                None => {
                    let origin = Self::offset(s, l);
                    !self.bvh.any_hit(origin, l, 1e30)
                }
            };
            if visible {
                sum += self.brdf(s, l, v) * intensity * cos;
            }
        }
        sum
    }

    fn brdf(&self, s: &Surface, l: Vec3, v: Vec3) -> Vec3 {
        s.brdf(l, v, self.config.specular)
    }

    /// Solid-angle pdf of sampling the point `q` on emitter `e` from `p`.
    fn emitter_pdf(&self, e: &Emitter, p: Vec3, q: Vec3) -> f32 {
        let total = *self.emitter_cdf.last().unwrap_or(&1.0);
        let choose = e.area * luminance(e.radiance) / total;
        let d = q - p;
        let cos = e.normal.dot(-d.normalize_or_zero());
        if cos <= 0.0 {
            return 0.0;
        }
        choose / e.area * d.length_squared() / cos
    }

    /// One area-light sample at `s` (MIS-weighted against BRDF sampling).
    fn area(&self, s: &Surface, v: Vec3, rng: &mut Rng) -> Vec3 {
        let Some(&total) = self.emitter_cdf.last() else {
            return Vec3::ZERO;
        };
        let pick = rng.f() * total;
        let i = self
            .emitter_cdf
            .partition_point(|&c| c <= pick)
            .min(self.emitters.len() - 1);
        let e = &self.emitters[i];
        let (mut a, mut b) = (rng.f(), rng.f());
        if a + b > 1.0 {
            (a, b) = (1.0 - a, 1.0 - b);
        }
        let q = e.v[0] + (e.v[1] - e.v[0]) * a + (e.v[2] - e.v[0]) * b;
        let d = q - s.p;
        let l = d.normalize_or_zero();
        let cos = s.n.dot(l);
        let pdf = self.emitter_pdf(e, s.p, q);
        if cos <= 0.0 || pdf <= 0.0 || !self.visible(s, q) {
            return Vec3::ZERO;
        }
        let bsdf_pdf = s.pdf(l, v, self.config.specular);
        let weight = pdf * pdf / (pdf * pdf + bsdf_pdf * bsdf_pdf);
        self.brdf(s, l, v) * e.radiance * cos * weight / pdf
    }

    /// The first surface along the ray that is there for it: surfaces whose alpha discards
    /// them ([`crate::AlphaMode::keeps`], a random threshold for blended ones) and, for camera
    /// rays, the backs of one-sided materials are passed through, as the G-buffer culls and
    /// discards them (at most [`PASS_THROUGH`] of them).
    fn next_surface(
        &self,
        mut origin: Vec3,
        dir: Vec3,
        camera: bool,
        rng: &mut Rng,
    ) -> Option<(crate::Hit, Surface, MaterialSample)> {
        for _ in 0..PASS_THROUGH {
            let hit = self.bvh.closest_hit(origin, dir, 1e30)?;
            let (s, sample, back) = self.surface(&hit, dir);
            let m = &self.scene.materials[self.scene.meshes[hit.mesh as usize].material as usize];
            let threshold = if m.alpha_mode == crate::AlphaMode::Blend {
                rng.f()
            } else {
                0.0
            };
            let culled = camera && back && !m.double_sided;
            if !culled && m.alpha_mode.keeps(sample.alpha, threshold) {
                return Some((hit, s, sample));
            }
            origin = Self::offset(&s, dir);
        }
        None
    }

    /// The radiance arriving through pixel `pixel` along one path. A surface's ambient
    /// occlusion ([`MaterialSample::occlusion`]) scales what its continuation ray brings,
    /// except the emitters that ray hits (direct light, as next-event estimation's).
    fn radiance(&self, pixel: (u32, u32), rng: &mut Rng) -> Vec3 {
        let (mut origin, mut dir) = self.camera_ray(pixel, rng);
        let mut throughput = Vec3::ONE;
        // `throughput` without the last surface's occlusion: for the emitters a ray hits.
        let mut direct_throughput = Vec3::ONE;
        let mut sum = Vec3::ZERO;
        // The solid-angle pdf of the BRDF sample that produced `dir` (None: camera ray).
        let mut last_pdf: Option<(f32, Vec3)> = None;
        for depth in 0..=self.config.max_bounces + 1 {
            let Some((hit, s, sample)) = self.next_surface(origin, dir, last_pdf.is_none(), rng)
            else {
                break;
            };
            // Emission seen at vertex `depth` has bounced at the `depth − 1` surfaces before
            // it (none for the camera's own view of it); light sampled at vertex `depth`
            // bounces there and at the `depth` surfaces before.
            let emitted_kept = depth.saturating_sub(1) >= self.config.min_bounces;
            let sampled_kept = depth >= self.config.min_bounces;
            match self.emitter_of[hit.mesh as usize][hit.triangle as usize] {
                Some(e) => {
                    let e = &self.emitters[e as usize];
                    if emitted_kept && e.normal.dot(-dir) > 0.0 {
                        let weight = match last_pdf {
                            None => 1.0,
                            Some((bsdf_pdf, from)) => {
                                let light_pdf = self.emitter_pdf(e, from, s.p);
                                bsdf_pdf * bsdf_pdf / (bsdf_pdf * bsdf_pdf + light_pdf * light_pdf)
                            }
                        };
                        sum += direct_throughput * sample.emission * weight;
                    }
                }
                // Textured emission (not a sampled light): reached by BRDF samples only, on
                // the side the camera or the ray sees.
                None if emitted_kept => sum += direct_throughput * sample.emission,
                None => {}
            }
            if depth > self.config.max_bounces {
                break;
            }
            let v = -dir;
            // Both estimators draw their random numbers whether or not the light is kept.
            let light = self.punctual(&s, v) + self.area(&s, v, rng);
            if sampled_kept {
                sum += throughput * light;
            }
            let l = s.sample(v, rng, self.config.specular);
            let pdf = s.pdf(l, v, self.config.specular);
            let cos = s.n.dot(l);
            if pdf <= 0.0 || cos <= 0.0 || l.dot(s.ng) <= 0.0 {
                break;
            }
            direct_throughput = throughput * self.brdf(&s, l, v) * cos / pdf;
            throughput = direct_throughput * sample.occlusion;
            if depth >= 3 {
                let survive = throughput.max_element().clamp(0.05, 1.0);
                if rng.f() >= survive {
                    break;
                }
                throughput /= survive;
                direct_throughput /= survive;
            }
            origin = Self::offset(&s, l);
            dir = l;
            last_pdf = Some((pdf, s.p));
        }
        sum
    }
}

/// The most surfaces a ray passes through (alpha-discarded or culled) before it gives up.
const PASS_THROUGH: usize = 64;

/// Direction to a light at `position` and its finite-radius attenuation at `p`.
fn attenuation(position: Vec3, radius: f32, p: Vec3) -> (Vec3, f32) {
    let to = position - p;
    let d = to.length();
    let x2 = (d / radius) * (d / radius);
    let w = (1.0 - x2 * x2).clamp(0.0, 1.0);
    (to / d.max(1e-6), w * w / (d * d).max(1e-4))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The BRDF sampler's estimate of the directional albedo `∫ f cos dω` (f·cos / pdf over
    /// its own samples) equals a dense quadrature over the hemisphere: the pdf is the density
    /// the sampler draws from.
    #[test]
    fn brdf_sampling_matches_quadrature() {
        for (roughness, metallic, albedo, theta) in [
            (1.0, 0.0, 0.8, 0.2),
            (0.5, 0.0, 0.5, 0.9),
            (0.3, 1.0, 0.9, 0.5),
            (0.15, 0.5, 0.7, 1.2),
        ] {
            let s = Surface {
                p: Vec3::ZERO,
                n: Vec3::Z,
                ng: Vec3::Z,
                albedo: Vec3::splat(albedo),
                roughness,
                metallic,
                specular: 1.0,
            };
            let v = Vec3::new((theta as f32).sin(), 0.0, (theta as f32).cos());
            let mut rng = Rng::new(7, 0, 0);
            let n = 400_000;
            let mut sampled = 0.0f64;
            for _ in 0..n {
                let l = s.sample(v, &mut rng, true);
                let pdf = s.pdf(l, v, true);
                let cos = l.z;
                if pdf > 0.0 && cos > 0.0 {
                    sampled += f64::from(s.brdf(l, v, true).x * cos / pdf);
                }
            }
            sampled /= f64::from(n);
            // Midpoint rule in (cos θ, φ): dω = d(cos θ) dφ.
            let (nt, np) = (2000, 400);
            let mut quad = 0.0f64;
            for i in 0..nt {
                let c = (i as f32 + 0.5) / nt as f32;
                let sn = (1.0 - c * c).sqrt();
                for j in 0..np {
                    let phi = 2.0 * PI * (j as f32 + 0.5) / np as f32;
                    let l = Vec3::new(sn * phi.cos(), sn * phi.sin(), c);
                    quad += f64::from(s.brdf(l, v, true).x * c);
                }
            }
            quad *= f64::from(2.0 * PI) / f64::from(nt * np);
            let rel = (sampled - quad).abs() / quad;
            assert!(
                rel < 0.01,
                "roughness {roughness} metallic {metallic}: sampled {sampled}, quadrature {quad}"
            );
        }
    }
}
