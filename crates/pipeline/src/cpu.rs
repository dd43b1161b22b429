//! CPU reference of the deferred renderer (rayon over rows): the light accumulation of
//! `tiled_shading::cpu` and the composition, mirroring `shaders/pipeline/composition.wgsl`.

use std::time::Instant;

use gbuffer::{Frame, GBuffer, Image, NO_MATERIAL, TextureOptions, unpack_material};
use glam::Vec3;
use rayon::prelude::*;
use scene::{Camera, Light, Scene};

use crate::{PassTiming, RenderError, Rendered, ShadingConfig};
use instant_radiosity::{IndirectConfig, IndirectStages, vpl::VplSet};
use tiled_shading::shadows::{self, ShadowMapConfig};

pub use tiled_shading::lighting::{
    Surface, distance_attenuation, light_incidence, reflect_light, shade_light,
};

fn albedo_of(p: [u8; 4]) -> Vec3 {
    Vec3::new(f32::from(p[0]), f32::from(p[1]), f32::from(p[2])) / 255.0
}

/// Diffuse and specular indirect light images (see [`IndirectStages::result`]).
pub type IndirectLight<'a> = (&'a Image<[f32; 4]>, &'a Image<[f32; 4]>);

/// Composition: `albedo · (1 − metallic) · (diffuse + ao · (ambient + indirect diffuse)) +
/// specular + ao · indirect specular + emission`, with the emission and the ambient
/// occlusion `ao` from the G-buffer's emission image.
pub fn composition(
    gb: &GBuffer,
    (diffuse, specular): (&Image<Vec3>, &Image<Vec3>),
    indirect: Option<IndirectLight<'_>>,
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
            let (_, metallic, _) = unpack_material(word);
            let albedo = albedo_of(gb.albedo.pixels()[i]);
            let emission = gb.emission.pixels()[i];
            let occlusion = emission[3];
            let (ind_d, ind_s) = indirect.map_or((Vec3::ZERO, Vec3::ZERO), |(d, s)| {
                (rgb(d.pixels()[i]), rgb(s.pixels()[i]))
            });
            let c =
                albedo * (1.0 - metallic) * (diffuse.pixels()[i] + occlusion * (ambient + ind_d))
                    + specular.pixels()[i]
                    + occlusion * ind_s
                    + rgb(emission);
            [c.x, c.y, c.z, 1.0]
        })
        .collect();
    Image::from_vec(gb.width(), gb.height(), pixels).expect("w × h pixels")
}

/// What a CPU frame renders: `scene` seen by `camera` at `width × height`, lit by `lights`
/// and `ambient`.
#[derive(Clone, Copy, Debug)]
pub struct FrameInputs<'a> {
    scene: &'a Scene,
    camera: &'a Camera,
    lights: &'a [Light],
    width: u32,
    height: u32,
    ambient: Vec3,
    shadows: Option<ShadowMapConfig>,
    textures: TextureOptions,
}

impl<'a> FrameInputs<'a> {
    /// Filters textures as `options` say (`GpuRenderer::new_with`'s twin).
    pub fn with_textures(self, options: TextureOptions) -> Self {
        Self {
            textures: options,
            ..self
        }
    }

    /// Shadows every light with maps of `config` (`GpuRenderer::set_shadows`' twin), whose
    /// depth the CPU ray-casts through every texel centre
    /// ([`tiled_shading::shadows::ray_cast_maps`]).
    pub fn with_shadows(self, config: ShadowMapConfig) -> Self {
        Self {
            shadows: Some(config),
            ..self
        }
    }

    /// `scene` from `camera` at `(width, height)`, lit by `lights` and `ambient`.
    pub fn new(
        scene: &'a Scene,
        camera: &'a Camera,
        lights: &'a [Light],
        (width, height): (u32, u32),
        ambient: Vec3,
    ) -> Self {
        Self {
            scene,
            camera,
            lights,
            width,
            height,
            ambient,
            shadows: None,
            textures: TextureOptions::default(),
        }
    }
}

/// Renders a frame on the CPU: rasterize the G-buffer, accumulate lights (tiled, the
/// default [`ShadingConfig`]), compose.
pub fn render(inputs: &FrameInputs<'_>) -> Result<Rendered, RenderError> {
    render_indirect(inputs, &ShadingConfig::default(), None).map(|(r, _)| r)
}

/// [`render`] with the light accumulation of `shading`, plus the indirect light of
/// `indirect`'s VPLs (BS → SNSM → BG → DB → B, timed per stage), added in the composition.
/// Returns the frame and every indirect stage's image.
pub fn render_indirect(
    inputs: &FrameInputs<'_>,
    shading: &ShadingConfig,
    indirect: Option<(&IndirectConfig, &VplSet)>,
) -> Result<(Rendered, Option<IndirectStages>), RenderError> {
    let (scene, camera, width, height) = (inputs.scene, inputs.camera, inputs.width, inputs.height);
    let mut gpu_lights = crate::validate_lights(inputs.lights)?;
    let mut timings = Vec::new();
    let timed = |timings: &mut Vec<PassTiming>, name: &str, t: Instant| {
        timings.push(PassTiming {
            name: name.into(),
            ms: t.elapsed().as_secs_f64() * 1e3,
        })
    };
    let t = Instant::now();
    let gb =
        gbuffer::cpu::rasterize_with(scene, camera, (width, height), &inputs.textures)?.gbuffer;
    timed(&mut timings, "gbuffer", t);
    let frame = Frame::new(camera, width, height);
    let maps = match &inputs.shadows {
        Some(config) => {
            let t = Instant::now();
            let plan = shadows::plan(
                &gpu_lights,
                &vec![true; gpu_lights.len()],
                camera,
                width as f32 / height as f32,
                scene.bounds(),
                config,
                u32::MAX,
            )?;
            plan.assign(&mut gpu_lights);
            let maps = shadows::ray_cast_maps(&scene::Bvh::build(scene), &plan.views, config);
            timed(&mut timings, "shadow maps", t);
            Some(maps)
        }
        None => None,
    };
    let t = Instant::now();
    let mut direct =
        tiled_shading::cpu::shade(&gb, &frame, camera, &gpu_lights, shading, maps.as_ref())?;
    if shading.method == tiled_shading::Method::LightPrePass {
        // Its lighting pass made a light buffer; the second geometry pass applies materials.
        direct = tiled_shading::cpu::apply_light_prepass(&gb, &frame, &direct);
    }
    timed(
        &mut timings,
        &format!("light accumulation ({})", shading.method),
        t,
    );
    let stages = indirect
        .map(|(config, set)| instant_radiosity::cpu::indirect(&gb, &frame, set, config))
        .transpose()?;
    if let Some(stages) = &stages {
        timings.extend(stages.timings.iter().cloned());
    }
    let t = Instant::now();
    let image = composition(
        &gb,
        (&direct.diffuse, &direct.specular),
        stages.as_ref().map(IndirectStages::result),
        inputs.ambient,
    );
    timed(&mut timings, "composition", t);
    Ok((Rendered { image, timings }, stages))
}
