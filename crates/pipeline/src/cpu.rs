//! CPU reference of the deferred renderer (rayon over rows), mirroring
//! `shaders/pipeline/{lighting,light_accumulation,composition}.wgsl` function for function.

use std::f32::consts::FRAC_1_PI;
use std::time::Instant;

use gbuffer::{
    Frame, GBuffer, Image, NO_MATERIAL, normal::unpack_octahedral, position, unpack_material,
};
use glam::Vec3;
use rayon::prelude::*;
use scene::{Camera, Light, Scene};

use crate::indirect::{IndirectConfig, IndirectStages, vpl::VplSet};
use crate::{GpuLight, PassTiming, RenderError, Rendered};

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

/// One light's (diffuse, specular) contribution (`shade_light`).
pub fn shade_light(
    light: &GpuLight,
    p: Vec3,
    n: Vec3,
    v: Vec3,
    albedo: Vec3,
    roughness: f32,
    metallic: f32,
) -> (Vec3, Vec3) {
    let (l, att) = light_incidence(light, p);
    if att <= 0.0 {
        return (Vec3::ZERO, Vec3::ZERO);
    }
    let intensity = Vec3::from(light.color) * att;
    reflect_light(intensity, l, n, v, albedo, roughness, metallic)
}

/// The (diffuse, specular) light reflected towards `v` from light arriving along `l` with
/// attenuated `intensity` (irradiance `intensity · N·L`): Lambert `E/π` and GGX `E·D·V·F`
/// (`reflect_light`).
pub fn reflect_light(
    intensity: Vec3,
    l: Vec3,
    n: Vec3,
    v: Vec3,
    albedo: Vec3,
    roughness: f32,
    metallic: f32,
) -> (Vec3, Vec3) {
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
    let f0 = Vec3::splat(0.04).lerp(albedo, metallic);
    let f = f0 + (Vec3::ONE - f0) * (1.0 - v_dot_h).powi(5);
    (e * FRAC_1_PI, e * (d * vis) * f)
}

fn albedo_of(p: [u8; 4]) -> Vec3 {
    Vec3::new(f32::from(p[0]), f32::from(p[1]), f32::from(p[2])) / 255.0
}

/// Light accumulation: per pixel, the sums of diffuse and specular over all lights.
pub fn light_accumulation(
    gb: &GBuffer,
    frame: &Frame,
    lights: &[GpuLight],
) -> (Image<Vec3>, Image<Vec3>) {
    let (w, h) = (gb.width(), gb.height());
    let rows: Vec<(Vec<Vec3>, Vec<Vec3>)> = (0..h)
        .into_par_iter()
        .map(|y| {
            (0..w)
                .map(|x| {
                    let depth = gb.depth.get(x, y);
                    if depth >= 1.0 {
                        return (Vec3::ZERO, Vec3::ZERO);
                    }
                    let p = position::from_depth(frame, x, y, depth);
                    let n = unpack_octahedral(gb.normal.get(x, y));
                    let v = (frame.eye.truncate() - p).normalize();
                    let albedo = albedo_of(gb.albedo.get(x, y));
                    let (roughness, metallic, _) = unpack_material(gb.material.get(x, y));
                    lights
                        .iter()
                        .fold((Vec3::ZERO, Vec3::ZERO), |(d, s), light| {
                            let (dl, sl) = shade_light(light, p, n, v, albedo, roughness, metallic);
                            (d + dl, s + sl)
                        })
                })
                .unzip()
        })
        .collect();
    let (d, s): (Vec<_>, Vec<_>) = rows.into_iter().unzip();
    let image = |v: Vec<Vec<Vec3>>| Image::from_vec(w, h, v.concat()).expect("w × h pixels");
    (image(d), image(s))
}

/// Diffuse and specular indirect light images (see [`IndirectStages::result`]).
pub type IndirectLight<'a> = (&'a Image<[f32; 4]>, &'a Image<[f32; 4]>);

/// Composition: `albedo · (1 − metallic) · (ambient + diffuse + indirect diffuse) + specular
/// + indirect specular + emissive`.
pub fn composition(
    gb: &GBuffer,
    (diffuse, specular): (&Image<Vec3>, &Image<Vec3>),
    indirect: Option<IndirectLight<'_>>,
    emissive: &[Vec3],
    ambient: Vec3,
) -> Image<[f32; 4]> {
    let rgb = |p: [f32; 4]| Vec3::new(p[0], p[1], p[2]);
    let pixels: Vec<[f32; 4]> = (0..gb.width() * gb.height())
        .into_par_iter()
        .map(|i| {
            let i = i as usize;
            let word = gb.material.pixels()[i];
            if word == NO_MATERIAL {
                return [0.0; 4];
            }
            let (_, metallic, id) = unpack_material(word);
            let albedo = albedo_of(gb.albedo.pixels()[i]);
            let (ind_d, ind_s) = indirect.map_or((Vec3::ZERO, Vec3::ZERO), |(d, s)| {
                (rgb(d.pixels()[i]), rgb(s.pixels()[i]))
            });
            let c = albedo * (1.0 - metallic) * (ambient + (diffuse.pixels()[i] + ind_d))
                + (specular.pixels()[i] + ind_s)
                + emissive.get(id as usize).copied().unwrap_or(Vec3::ZERO);
            [c.x, c.y, c.z, 1.0]
        })
        .collect();
    Image::from_vec(gb.width(), gb.height(), pixels).expect("w × h pixels")
}

/// Renders a frame on the CPU: rasterize the G-buffer, accumulate lights, compose.
pub fn render(
    scene: &Scene,
    camera: &Camera,
    lights: &[Light],
    width: u32,
    height: u32,
    ambient: Vec3,
) -> Result<Rendered, RenderError> {
    render_indirect(scene, camera, lights, width, height, ambient, None).map(|(r, _)| r)
}

/// [`render`] plus the indirect light of `indirect`'s VPLs (BS → SNSM → BG → DB → B, timed
/// per stage), added in the composition. Returns the frame and every indirect stage's image.
pub fn render_indirect(
    scene: &Scene,
    camera: &Camera,
    lights: &[Light],
    width: u32,
    height: u32,
    ambient: Vec3,
    indirect: Option<(&IndirectConfig, &VplSet)>,
) -> Result<(Rendered, Option<IndirectStages>), RenderError> {
    crate::validate_lights(lights)?;
    let mut timings = Vec::new();
    let timed = |timings: &mut Vec<PassTiming>, name: &str, t: Instant| {
        timings.push(PassTiming {
            name: name.into(),
            ms: t.elapsed().as_secs_f64() * 1e3,
        })
    };
    let t = Instant::now();
    let gb = gbuffer::cpu::rasterize(scene, camera, width, height)?.gbuffer;
    timed(&mut timings, "gbuffer", t);
    let frame = Frame::new(camera, width, height);
    let gpu_lights: Vec<GpuLight> = lights.iter().map(GpuLight::from).collect();
    let t = Instant::now();
    let direct = light_accumulation(&gb, &frame, &gpu_lights);
    timed(&mut timings, "light accumulation", t);
    let stages = indirect
        .map(|(config, set)| crate::indirect::cpu::indirect(&gb, &frame, set, config))
        .transpose()?;
    if let Some(stages) = &stages {
        timings.extend(stages.timings.iter().cloned());
    }
    let emissive: Vec<Vec3> = scene.materials.iter().map(|m| m.emissive).collect();
    let t = Instant::now();
    let image = composition(
        &gb,
        (&direct.0, &direct.1),
        stages.as_ref().map(IndirectStages::result),
        &emissive,
        ambient,
    );
    timed(&mut timings, "composition", t);
    Ok((Rendered { image, timings }, stages))
}
