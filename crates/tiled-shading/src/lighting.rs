//! The lights and the BRDF of the deferred renderer, mirroring
//! `shaders/tiled-shading/lighting.wgsl` function for function.
//!
//! Light accumulation (Ishmukhametov 2013 §1.3 step 3) sums, per pixel and light,
//! `E = Att · (N·L) · colour · intensity`, diffuse `E/π` and specular `E·D_GGX·V_Smith·F_Schlick`.
//! Point, spot and hemispherical attenuation is `saturate(1 − (d/r)⁴)² / max(d², 1e-4)`: exactly
//! zero at and beyond the radius `r`, which is what makes culled and brute-force shading agree.

use std::f32::consts::FRAC_1_PI;

use glam::Vec3;

use crate::GpuLight;

/// Distance window: 1 at the light, 0 at and beyond its radius (`distance_attenuation`).
pub fn distance_attenuation(d: f32, radius: f32) -> f32 {
    let x2 = (d / radius) * (d / radius);
    let w = (1.0 - x2 * x2).clamp(0.0, 1.0);
    w * w / (d * d).max(1e-4)
}

fn smoothstep(e0: f32, e1: f32, x: f32) -> f32 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Direction to the light and attenuation at `p` (`light_incidence`).
pub fn light_incidence(light: &GpuLight, p: Vec3) -> (Vec3, f32) {
    if light.kind == 2 {
        return (-Vec3::from(light.direction), 1.0);
    }
    let to_light = Vec3::from(light.position) - p;
    let d = to_light.length();
    let l = to_light / d.max(1e-6);
    let mut att = distance_attenuation(d, light.radius);
    let cos_emission = (-l).dot(Vec3::from(light.direction));
    if light.kind == 1 {
        att *= smoothstep(light.cos_outer, light.cos_inner, cos_emission);
    } else if light.kind == 3 {
        att *= cos_emission.max(0.0);
    }
    (l, att)
}

/// A shaded point: position `p`, unit normal `n`, unit direction to the eye `v` and the
/// G-buffer's material (the arguments of `shade_light`/`reflect_light` after the light).
#[derive(Clone, Copy, Debug)]
pub struct Surface {
    /// World-space position.
    pub p: Vec3,
    /// Unit normal.
    pub n: Vec3,
    /// Unit direction to the eye.
    pub v: Vec3,
    /// Linear base colour.
    pub albedo: Vec3,
    /// Perceptual roughness (GGX α = roughness²).
    pub roughness: f32,
    /// Metalness (F0 from 0.04 to the albedo).
    pub metallic: f32,
    /// The material's specular factor (the G-buffer albedo's alpha): it scales the dielectric
    /// Fresnel term, as `KHR_materials_specular` does.
    pub specular: f32,
}

/// One light's (diffuse, specular) contribution at `s` (`shade_light`).
pub fn shade_light(light: &GpuLight, s: &Surface) -> (Vec3, Vec3) {
    let (l, att) = light_incidence(light, s.p);
    if att <= 0.0 {
        return (Vec3::ZERO, Vec3::ZERO);
    }
    let intensity = Vec3::from(light.color) * att;
    reflect_light(intensity, l, s)
}

/// The (diffuse, specular) light reflected towards `s.v` from light arriving along `l` with
/// attenuated `intensity` (irradiance `intensity · N·L`): Lambert `E/π` and GGX `E·D·V·F`
/// (`reflect_light`).
pub fn reflect_light(intensity: Vec3, l: Vec3, s: &Surface) -> (Vec3, Vec3) {
    let Surface {
        n,
        v,
        albedo,
        roughness,
        metallic,
        specular,
        ..
    } = *s;
    let n_dot_l = n.dot(l).clamp(0.0, 1.0);
    if n_dot_l <= 0.0 {
        return (Vec3::ZERO, Vec3::ZERO);
    }
    let e = intensity * n_dot_l;
    let h = (l + v).normalize();
    let n_dot_v = n.dot(v).clamp(1e-4, 1.0);
    let n_dot_h = n.dot(h).clamp(0.0, 1.0);
    let v_dot_h = v.dot(h).clamp(0.0, 1.0);
    let a = (roughness * roughness).max(1e-3);
    let a2 = a * a;
    let k = n_dot_h * n_dot_h * (a2 - 1.0) + 1.0;
    let d = a2 * FRAC_1_PI / (k * k);
    let vis = 0.5
        / (n_dot_l * (n_dot_v * n_dot_v * (1.0 - a2) + a2).sqrt()
            + n_dot_v * (n_dot_l * n_dot_l * (1.0 - a2) + a2).sqrt());
    let fw = (1.0 - v_dot_h).powi(5);
    let f = Vec3::splat(specular * (0.04 + 0.96 * fw))
        .lerp(albedo + (Vec3::ONE - albedo) * fw, metallic);
    (e * FRAC_1_PI, e * (d * vis) * f)
}
