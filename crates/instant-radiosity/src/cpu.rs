//! CPU reference of the indirect stage (rayon), mirroring `shaders/instant-radiosity/vpl_shading.wgsl`
//! and the `interleave` kernels it composes.

use std::f32::consts::FRAC_1_PI;
use std::time::Instant;

use gbuffer::{Frame, GBuffer, Image, normal::unpack_octahedral, position, unpack_material};
use glam::Vec3;
use interleave::{SplitLayout, SplitVariant};
use rayon::prelude::*;

use crate::IndirectError;
use crate::rays::RayBvh;
use crate::shadows::vpl_visibility;
use crate::{IndirectConfig, IndirectStages, Interleaving, vpl::GpuVpl, vpl::VplSet};
use gpu::PassTiming;
use manylod::lookup::AtlasParams;
use tiled_shading::lighting::{Surface, reflect_light};

/// The clamped intensity of `vpl` towards `p` and the direction to it (`vpl_intensity`):
/// `Φ/π · max(−n_q·l, 0) / max(d², clamp²)`.
pub fn vpl_intensity(vpl: &GpuVpl, p: Vec3, clamp_squared: f32) -> (Vec3, Vec3) {
    let to_vpl = Vec3::from(vpl.position) - p;
    let d2 = to_vpl.dot(to_vpl);
    let l = to_vpl * (1.0 / d2.max(1e-30).sqrt());
    let cos_vpl = (-Vec3::from(vpl.normal).dot(l)).max(0.0);
    (
        Vec3::from(vpl.flux) * (FRAC_1_PI * cos_vpl / d2.max(clamp_squared)),
        l,
    )
}

/// VPL visibility on the CPU: a shadow-map atlas (read back from
/// [`crate::shadows::VplShadowMaps`]) and its parameters, or rays through the scene's BVH whose
/// ends leave their surfaces by the offset ([`crate::rays::visibility`]).
#[derive(Clone, Copy)]
pub enum Visibility<'a> {
    /// Looked up in the atlas ([`vpl_visibility`]).
    Atlas(&'a [u32], AtlasParams),
    /// Traced ([`crate::rays::visibility`]).
    Rays(&'a RayBvh, f32),
}

/// Inputs of the shading pass besides the G-buffer images.
pub struct ShadingInputs<'a> {
    /// Camera data.
    pub frame: &'a Frame,
    /// Split layout of the G-buffer images (1×1 for the reference).
    pub layout: &'a SplitLayout,
    /// All VPLs, subset-major.
    pub vpls: &'a [GpuVpl],
    /// VPLs per subset.
    pub per_subset: u32,
    /// Factor on the sums (the subset count; 1 for the reference).
    pub scale: f32,
    /// Square of the clamp distance.
    pub clamp_squared: f32,
    /// VPL visibility; `None` shades without visibility (SNSM).
    pub shadows: Option<Visibility<'a>>,
}

/// SNSM on split G-buffer images (`shade_split`): texel (x, y) of the split layout shades the
/// VPL subset of its sub-buffer at the image pixel it holds. Returns diffuse and specular in
/// the split layout, rounded to f16.
pub fn shade_vpls(gb: &GBuffer, inputs: &ShadingInputs<'_>) -> (Image<[f32; 4]>, Image<[f32; 4]>) {
    let l = inputs.layout;
    let (w, h) = (l.split_width(), l.split_height());
    let rows: Vec<Vec<([f32; 4], [f32; 4])>> = (0..h)
        .into_par_iter()
        .map(|y| {
            (0..w)
                .map(|x| {
                    let (i, j) = (x / l.sub_width, y / l.sub_height);
                    let pixel = (
                        (x % l.sub_width) * l.pattern.n + i,
                        (y % l.sub_height) * l.pattern.m + j,
                    );
                    let (d, s) = shade(gb, (x, y), pixel, j * l.pattern.n + i, inputs);
                    let f16 = |v: Vec3| interleave::cpu::to_f16([v.x, v.y, v.z, 0.0]);
                    (f16(d), f16(s))
                })
                .collect()
        })
        .collect();
    let (d, s): (Vec<_>, Vec<_>) = rows.into_iter().flatten().unzip();
    let image = |v| Image::from_vec(w, h, v).expect("split size");
    (image(d), image(s))
}

/// The scaled subset sums at G-buffer texel `texel`, which holds image pixel `pixel` (`shade`).
fn shade(
    gb: &GBuffer,
    (tx, ty): (u32, u32),
    (px, py): (u32, u32),
    subset: u32,
    inputs: &ShadingInputs<'_>,
) -> (Vec3, Vec3) {
    let depth = gb.linear_depth.get(tx, ty);
    let (mut diffuse, mut specular) = (Vec3::ZERO, Vec3::ZERO);
    if depth > 0.0 {
        let p = position::from_view_ray(inputs.frame, px, py, depth);
        let n = unpack_octahedral(gb.normal.get(tx, ty));
        let v = (inputs.frame.eye.truncate() - p).normalize();
        let (albedo, specular_factor) = gbuffer::unpack_albedo(gb.albedo.get(tx, ty));
        let (roughness, metallic, _) = unpack_material(gb.material.get(tx, ty));
        let surface = Surface {
            p,
            n,
            v,
            albedo,
            roughness,
            metallic,
            specular: specular_factor,
        };
        let first = (subset * inputs.per_subset) as usize;
        for (k, vpl) in inputs
            .vpls
            .iter()
            .enumerate()
            .skip(first)
            .take(inputs.per_subset as usize)
        {
            let (mut intensity, l) = vpl_intensity(vpl, p, inputs.clamp_squared);
            intensity *= match inputs.shadows {
                None => 1.0,
                Some(Visibility::Atlas(atlas, params)) => {
                    vpl_visibility(atlas, &params, k as u32, vpl, p, n)
                }
                Some(Visibility::Rays(bvh, offset)) => {
                    let q = (Vec3::from(vpl.position), Vec3::from(vpl.normal));
                    crate::rays::visibility(bvh, (p, n), q, offset)
                }
            };
            let (d, s) = reflect_light(intensity, l, &surface);
            diffuse += d;
            specular += s;
        }
    }
    (diffuse * inputs.scale, specular * inputs.scale)
}

/// Splits every G-buffer image (BS).
fn split_gbuffer(
    gb: &GBuffer,
    layout: &SplitLayout,
    variant: SplitVariant,
) -> Result<GBuffer, IndirectError> {
    use interleave::cpu::split;
    Ok(GBuffer {
        depth: split(&gb.depth, layout, variant)?,
        linear_depth: split(&gb.linear_depth, layout, variant)?,
        normal: split(&gb.normal, layout, variant)?,
        albedo: split(&gb.albedo, layout, variant)?,
        material: split(&gb.material, layout, variant)?,
        emission: split(&gb.emission, layout, variant)?,
    })
}

/// The indirect stage on the CPU: BS → SNSM → BG → DB → B (or the reference shading), every
/// stage's image kept.
pub fn indirect(
    gb: &GBuffer,
    frame: &Frame,
    set: &VplSet,
    config: &IndirectConfig,
) -> Result<IndirectStages, IndirectError> {
    indirect_with_shadows(gb, frame, set, config, None)
}

/// [`indirect`] with VPL visibility from `shadows` (e.g.
/// [`crate::shadows::VplShadowMaps::cpu_visibility`] of the maps' read-back atlas).
pub fn indirect_with_shadows(
    gb: &GBuffer,
    frame: &Frame,
    set: &VplSet,
    config: &IndirectConfig,
    shadows: Option<Visibility<'_>>,
) -> Result<IndirectStages, IndirectError> {
    config.validate(set)?;
    let (w, h) = (gb.width(), gb.height());
    let layout = SplitLayout::new(w, h, config.shading_pattern())?;
    let vpls = set.gpu();
    let inputs = ShadingInputs {
        frame,
        layout: &layout,
        vpls: &vpls,
        per_subset: config.per_invocation(set),
        scale: config.scale(set),
        clamp_squared: config.clamp_distance * config.clamp_distance,
        shadows,
    };
    let mut timings = Vec::new();
    let mut clock = Instant::now();
    let mut lap = |name: &str| {
        timings.push(PassTiming {
            name: name.into(),
            ms: clock.elapsed().as_secs_f64() * 1e3,
        });
        clock = Instant::now();
    };
    let (split_normal, shaded_diffuse, diffuse, specular) = match config.interleaving {
        Interleaving::Split(variant) => {
            let split = split_gbuffer(gb, &layout, variant)?;
            lap("BS");
            let (sd, ss) = shade_vpls(&split, &inputs);
            lap("SNSM");
            let diffuse = interleave::cpu::gather(&sd, &layout, variant)?;
            let specular = interleave::cpu::gather(&ss, &layout, variant)?;
            lap("BG");
            (Some(split.normal), sd, diffuse, specular)
        }
        // Fused shading computes the same texel values in place (timed as one SNSM pass);
        // the reference is the 1×1 layout, whose split is the image itself.
        Interleaving::Fused | Interleaving::Reference => {
            let split = split_gbuffer(gb, &layout, SplitVariant::OnePass)?;
            let (sd, ss) = shade_vpls(&split, &inputs);
            let diffuse = interleave::cpu::gather(&sd, &layout, SplitVariant::OnePass)?;
            let specular = interleave::cpu::gather(&ss, &layout, SplitVariant::OnePass)?;
            lap(if config.interleaving == Interleaving::Fused {
                "SNSM"
            } else {
                "shading (reference)"
            });
            (None, diffuse.clone(), diffuse, specular)
        }
    };
    let (discontinuities, blurred) = match config.applied_blur() {
        Some(blur) => {
            let db =
                interleave::cpu::discontinuity(&gb.linear_depth, &gb.normal, &config.thresholds)?;
            lap("DB");
            let d = interleave::cpu::blur(&diffuse, &db, &blur)?;
            let s = interleave::cpu::blur(&specular, &db, &blur)?;
            lap("B");
            (Some(db), Some([d, s]))
        }
        None => (None, None),
    };
    Ok(IndirectStages {
        split_normal,
        shaded_diffuse,
        diffuse,
        specular,
        discontinuities,
        blurred,
        timings,
    })
}
