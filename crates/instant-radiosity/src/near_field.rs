//! The VPLs' near field — Kollig & Keller 2004's bias compensation of the clamp. The VPL
//! estimator bounds a VPL's `1/d²` at the clamp distance c ([`crate::cpu::vpl_intensity`]),
//! which takes away, at a receiver x, the light of the surfaces within c:
//!
//! `E_lost(x)/π = 1/π ∫ L(y(ω)) cos θ (1 − d²/c²)⁺ dω`, d = |x − y(ω)|.
//!
//! That is most of what a receiver h above a floor gets when h ≪ c: the dark band along every
//! contact in docs/ground-truth.md, which a smaller clamp does not bring back (a 1024-VPL set
//! almost never has a VPL within h). One cosine-distributed ray of length c per pixel and
//! frame estimates it: at its first hit y, `L(y) · (1 − d²/c²)`, with `L(y) = ρ_y/π · E(y)`
//! and E(y) the lights' irradiance by shadow rays plus the clamped irradiance of
//! [`Y_VPLS`] VPLs drawn at random (× the set's size over that) by rays — the estimator's own
//! light one bounce further, so
//! the compensation of y's near field is not recursed. Lambert at both ends; y's albedo is its
//! triangle's ([`triangle_albedos`]: the base-colour texture at the triangle's centroid).
//! Every frame brings another sample ([`BoundNearField::set_vpls`] advances the seed): the
//! progressive mode's mean converges to the unclamped one-bounce light plus the VPLs' later
//! bounces.
//!
//! [`near_field`] is the CPU twin of `near_field.wgsl`; [`NearField`] the GPU kernel
//! (`new` → `bind` → `encode`). The renderer adds its output to the indirect diffuse light
//! (`pipeline::gpu::GpuRenderer::set_near_field`).

use std::f32::consts::{FRAC_1_PI, TAU};

use ::gpu::kernel::{Binding, Kernel, Passes, Workgroups, check_texture};
use ::gpu::shader::Specialisation;
use ::gpu::{PassTimer, transfer, wgpu};
use gbuffer::{Frame, GBuffer, Image, gpu::GBufferTextures};
use glam::Vec3;
use interleave::gpu::IRRADIANCE_FORMAT;
use rayon::prelude::*;
use scene::Scene;
use tiled_shading::gpu::shadows::GpuRays;
use tiled_shading::lighting::light_incidence;
use tiled_shading::rays::{RayBvh, RayParams, scene_mesh};
use tiled_shading::{GpuLight, LIGHT_DIRECTIONAL};

use crate::IndirectError;
use crate::cpu::vpl_intensity;
use crate::rays::ray_lift;
use crate::vpl::{GpuVpl, VplSet};

/// VPLs that light a near-field hit (fewer when the set has fewer): the second bounce of a
/// short ray's light needs no more, and all 1024 of a progressive frame made the pass as
/// costly as the VPL shading itself.
pub const Y_VPLS: u32 = 64;

/// Uniform block `NearFieldParams` of `near_field.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct NearFieldParams {
    /// Square of the VPL clamp distance c (0: nothing is clamped, nothing to compensate).
    pub clamp_squared: f32,
    /// VPLs that light y: a run of this many from a random start (wrapping round), which
    /// takes every VPL with the same probability.
    pub samples: u32,
    /// VPLs in the set.
    pub vpls: u32,
    /// Seed of the frame's samples.
    pub seed: u32,
    /// Length of a directional light's shadow ray (twice the scene's diagonal).
    pub reach: f32,
    /// Lights in the light buffer.
    pub lights: u32,
    /// Padding.
    pub _pad: [u32; 2],
}

/// Everything the near field reads besides the receiver.
pub struct NearFieldInputs<'a> {
    /// The scene's triangles.
    pub bvh: &'a RayBvh,
    /// Packed linear albedo of every triangle ([`triangle_albedos`]).
    pub albedos: &'a [u32],
    /// The direct lights.
    pub lights: &'a [GpuLight],
    /// The VPLs.
    pub vpls: &'a [GpuVpl],
    /// Clamp, VPL samples, seed, reach.
    pub params: NearFieldParams,
}

/// The diffuse albedo ρ(1 − metallic) of every triangle of `scene` in [`scene_mesh`]'s order,
/// its material evaluated at the triangle's centroid, packed as WGSL's `pack4x8unorm`.
pub fn triangle_albedos(scene: &Scene) -> Vec<u32> {
    let textures = scene::SceneTextures::new(scene, false);
    let mut albedos = Vec::with_capacity(scene.triangle_count());
    for (m, mesh) in scene.meshes.iter().enumerate() {
        for t in 0..mesh.indices.len() / 3 {
            let third = 1.0 / 3.0;
            let albedo =
                crate::vpl::material_at(scene, &textures, (m as u32, t as u32), (third, third))
                    .map_or(Vec3::ZERO, |s| s.albedo * (1.0 - s.metallic));
            albedos.push(pack4x8unorm(albedo.extend(1.0).to_array()));
        }
    }
    albedos
}

/// WGSL `pack4x8unorm`.
fn pack4x8unorm(v: [f32; 4]) -> u32 {
    v.iter().enumerate().fold(0, |word, (i, c)| {
        word | (((c.clamp(0.0, 1.0) * 255.0).round() as u32) << (8 * i))
    })
}

/// WGSL `unpack4x8unorm`, RGB.
pub(crate) fn unpack_rgb(word: u32) -> Vec3 {
    Vec3::from_array([0, 1, 2].map(|i| ((word >> (8 * i)) & 0xff) as f32 / 255.0))
}

/// PCG hash (Jarzynski & Olano 2020; `pcg` of `near_field.wgsl`).
fn pcg(x: u32) -> u32 {
    let state = x.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

fn unit(x: u32) -> f32 {
    (x >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// A cosine-distributed direction around the unit `n` (`cosine_direction`), in
/// [`scene::orthonormal_basis`]'s frame.
fn cosine_direction(n: Vec3, u1: f32, u2: f32) -> Vec3 {
    let (t, bt) = scene::orthonormal_basis(n);
    let r = u1.sqrt();
    let phi = TAU * u2;
    t * (r * phi.cos()) + bt * (r * phi.sin()) + n * (1.0 - u1).max(0.0).sqrt()
}

/// Irradiance / π at `y` (unit normal `n`): the lights by shadow rays, `samples` VPLs from
/// `first` by rays, × `vpls / samples` (`irradiance_at`).
fn irradiance_at(inputs: &NearFieldInputs<'_>, y: Vec3, n: Vec3, first: u32) -> Vec3 {
    let params = &inputs.params;
    let lights = &inputs.lights[..params.lights as usize];
    let e = direct_irradiance(inputs.bvh, lights, params.reach, (y, n));
    let mut indirect = Vec3::ZERO;
    for i in 0..params.samples {
        let vpl = &inputs.vpls[((first + i) % params.vpls) as usize];
        let (intensity, l) = vpl_intensity(vpl, y, params.clamp_squared);
        let cos_y = n.dot(l);
        if cos_y <= 0.0 || intensity == Vec3::ZERO {
            continue;
        }
        let q = (Vec3::from(vpl.position), Vec3::from(vpl.normal));
        indirect += intensity * (cos_y * crate::rays::visibility(inputs.bvh, (y, n), q, 1.0));
    }
    (e + indirect * (params.vpls as f32 / params.samples as f32)) * FRAC_1_PI
}

/// Irradiance at `y` (unit normal `n`) from `lights`, each seen by a shadow ray through `bvh`
/// (leaving `y` lifted by [`ray_lift`]; a directional light's ray is `reach` long): what the
/// near field's hit and point-based GI's surfels (`crate::pbgi`) receive.
pub fn direct_irradiance(
    bvh: &RayBvh,
    lights: &[GpuLight],
    reach: f32,
    (y, n): (Vec3, Vec3),
) -> Vec3 {
    let origin = y + n * ray_lift(y);
    let mut e = Vec3::ZERO;
    for light in lights {
        let (l, attenuation) = light_incidence(light, y);
        let cos_y = n.dot(l);
        if attenuation <= 0.0 || cos_y <= 0.0 {
            continue;
        }
        let to = if light.kind == LIGHT_DIRECTIONAL {
            -Vec3::from(light.direction) * reach
        } else {
            Vec3::from(light.position) - origin
        };
        if !bvh.occluded(origin, to) {
            e += Vec3::from(light.color) * (attenuation * cos_y);
        }
    }
    e
}

/// `E_lost/π` at `p` (unit normal `n`): pixel `(x, y)`'s sample of the frame's seed
/// (`near_field`).
pub fn near_field(inputs: &NearFieldInputs<'_>, p: Vec3, n: Vec3, (x, y): (u32, u32)) -> Vec3 {
    let params = &inputs.params;
    if params.clamp_squared <= 0.0 {
        return Vec3::ZERO;
    }
    let mut h = pcg(x ^ pcg(y ^ pcg(params.seed)));
    let u1 = unit(h);
    h = pcg(h);
    let u2 = unit(h);
    h = pcg(h);
    let first = h % params.vpls;
    let dir = cosine_direction(n, u1, u2);
    let lift = ray_lift(p);
    let origin = p + n * lift;
    let to = dir * params.clamp_squared.sqrt();
    let Some((t, slot)) = inputs.bvh.nearest(origin, to) else {
        return Vec3::ZERO;
    };
    // A surface within the lift is the receiver's own contact, as for every ray that leaves
    // it: a pixel centre on an edge must not see the other face at distance 0.
    if t * params.clamp_squared.sqrt() < lift {
        return Vec3::ZERO;
    }
    let tri = &inputs.bvh.triangles[slot];
    let mut n_y = Vec3::from_slice(&tri.e1)
        .cross(Vec3::from_slice(&tri.e2))
        .normalize();
    if n_y.dot(dir) > 0.0 {
        n_y = -n_y;
    }
    let albedo = unpack_rgb(inputs.albedos[tri.index as usize]);
    albedo * irradiance_at(inputs, origin + to * t, n_y, first) * (1.0 - t * t)
}

/// The near field of every pixel of a G-buffer (`near_field_main`), rounded to f16 as the
/// GPU stores it.
pub fn near_field_image(
    gb: &GBuffer,
    frame: &Frame,
    inputs: &NearFieldInputs<'_>,
) -> Image<[f32; 4]> {
    let (w, h) = (gb.linear_depth.width(), gb.linear_depth.height());
    let pixels: Vec<[f32; 4]> = (0..w * h)
        .into_par_iter()
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let depth = gb.linear_depth.get(x, y);
            if depth <= 0.0 {
                return [0.0; 4];
            }
            let p = gbuffer::position::from_view_ray(frame, x, y, depth);
            let n = gbuffer::normal::unpack_octahedral(gb.normal.get(x, y));
            let e = near_field(inputs, p, n, (x, y));
            interleave::cpu::to_f16([e.x, e.y, e.z, 0.0])
        })
        .collect();
    Image::from_vec(w, h, pixels).expect("G-buffer size")
}

/// `near_field.wgsl`'s specialisation: the BVH buffers of `rays.wgsl` at bindings 8 and 9 of
/// its one group.
pub fn rays_at() -> Specialisation {
    Specialisation::default()
        .set("RAY_GROUP", "0u")
        .set("RAY_NODES", "8u")
        .set("RAY_TRIANGLES", "9u")
}

/// `near_field.wgsl`: frame, params, VPLs, lights, triangle albedos; linear depth, normals;
/// output; the BVH's nodes and triangles.
const BINDINGS: [Binding; 10] = [
    Binding::Uniform,
    Binding::Uniform,
    Binding::StorageRead,
    Binding::StorageRead,
    Binding::StorageRead,
    Binding::TextureUnfilterable,
    Binding::TextureUint,
    Binding::StorageTexture(IRRADIANCE_FORMAT),
    Binding::StorageRead,
    Binding::StorageRead,
];

/// The near-field kernel for one scene (phase `new`): the pipeline, the scene's BVH and its
/// triangles' albedos on the GPU.
pub struct NearField {
    kernel: Kernel,
    rays: GpuRays,
    albedos: wgpu::Buffer,
    reach: f32,
}

/// The kernel bound to one G-buffer, light list, VPL set and output (phase `bind`).
pub struct BoundNearField {
    passes: Passes,
    params: NearFieldParams,
    params_buffer: wgpu::Buffer,
    vpls: wgpu::Buffer,
    lights: wgpu::Buffer,
    light_capacity: usize,
}

impl NearField {
    /// Builds the pipeline and uploads `scene`'s BVH ([`RayBvh::new`]) and
    /// [`triangle_albedos`].
    pub fn new(device: &wgpu::Device, scene: &Scene) -> Result<Self, IndirectError> {
        let (positions, indices) = scene_mesh(scene);
        let bvh = RayBvh::new((&positions, &indices))?;
        let module = crate::SHADERS.module_with(device, "near_field.wgsl", &rays_at())?;
        let kernel = Kernel::new(device, &module, "near_field_main", &BINDINGS, &[]);
        let albedos = transfer::buffer_init(
            device,
            "triangle albedos",
            bytemuck::cast_slice(&triangle_albedos(scene)),
            wgpu::BufferUsages::STORAGE,
        )?;
        Ok(Self {
            kernel,
            rays: GpuRays::new(device, &bvh, RayParams::default())?,
            albedos,
            reach: 2.0 * scene.bounds().diagonal().max(1e-6),
        })
    }

    /// Binds the kernel to the frame's camera buffer, the G-buffer's linear depth and normals,
    /// the direct `lights`, the VPLs of `set` with their clamp distance, and `output` (an
    /// [`IRRADIANCE_FORMAT`] storage texture of the G-buffer's size).
    #[allow(clippy::too_many_arguments)]
    pub fn bind(
        &self,
        device: &wgpu::Device,
        frame: &wgpu::Buffer,
        gbuffer: GBufferTextures<'_>,
        lights: &[GpuLight],
        set: &VplSet,
        clamp_distance: f32,
        output: &wgpu::Texture,
    ) -> Result<BoundNearField, IndirectError> {
        if !(clamp_distance.is_finite() && clamp_distance >= 0.0) {
            return Err(IndirectError::Clamp(clamp_distance));
        }
        let size = (gbuffer.linear_depth.width(), gbuffer.linear_depth.height());
        check_texture(
            "near-field output",
            output,
            size,
            IRRADIANCE_FORMAT,
            wgpu::TextureUsages::STORAGE_BINDING,
        )?;
        let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
        let vpls = transfer::buffer_init(
            device,
            "near-field vpls",
            bytemuck::cast_slice(&set.gpu()),
            storage,
        )?;
        // A buffer of one zeroed light stands in for none (a storage array binds non-empty).
        let stand_in = [bytemuck::Zeroable::zeroed()];
        let held: &[GpuLight] = if lights.is_empty() { &stand_in } else { lights };
        let light_capacity = held.len();
        let lights_buffer = transfer::buffer_init(
            device,
            "near-field lights",
            bytemuck::cast_slice(held),
            storage,
        )?;
        let params = NearFieldParams {
            clamp_squared: clamp_distance * clamp_distance,
            samples: (set.vpls.len() as u32).min(Y_VPLS),
            vpls: set.vpls.len() as u32,
            seed: 0,
            reach: self.reach,
            lights: lights.len() as u32,
            _pad: [0; 2],
        };
        let params_buffer = transfer::buffer_init(
            device,
            "near-field params",
            bytemuck::bytes_of(&params),
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        )?;
        let views = [gbuffer.linear_depth, gbuffer.normal, output]
            .map(|t| t.create_view(&Default::default()));
        let group = self.kernel.bind(
            device,
            &[
                frame.as_entire_binding(),
                params_buffer.as_entire_binding(),
                vpls.as_entire_binding(),
                lights_buffer.as_entire_binding(),
                self.albedos.as_entire_binding(),
                wgpu::BindingResource::TextureView(&views[0]),
                wgpu::BindingResource::TextureView(&views[1]),
                wgpu::BindingResource::TextureView(&views[2]),
                self.rays.nodes.as_entire_binding(),
                self.rays.triangles.as_entire_binding(),
            ],
        );
        let passes = Passes::one(
            "near field",
            &self.kernel.pipeline,
            vec![group],
            Workgroups::covering(size.0, size.1, 8),
        );
        Ok(BoundNearField {
            passes,
            params,
            params_buffer,
            vpls,
            lights: lights_buffer,
            light_capacity,
        })
    }
}

impl BoundNearField {
    /// Writes the lights (`false` when there are more than the bound buffer holds: bind
    /// again).
    #[must_use]
    pub fn set_lights(&mut self, queue: &wgpu::Queue, lights: &[GpuLight]) -> bool {
        if lights.len() > self.light_capacity {
            return false;
        }
        queue.write_buffer(&self.lights, 0, bytemuck::cast_slice(lights));
        self.params.lights = lights.len() as u32;
        queue.write_buffer(&self.params_buffer, 0, bytemuck::bytes_of(&self.params));
        true
    }

    /// Replaces the VPLs by another set of as many, and takes the next
    /// seed: each set brings another sample of the near field.
    pub fn set_vpls(&mut self, queue: &wgpu::Queue, set: &VplSet) -> Result<(), IndirectError> {
        if set.vpls.len() != self.params.vpls as usize {
            return Err(IndirectError::NearField(format!(
                "it was bound to {} VPLs, not {}",
                self.params.vpls,
                set.vpls.len()
            )));
        }
        queue.write_buffer(&self.vpls, 0, bytemuck::cast_slice(&set.gpu()));
        self.params.seed = self.params.seed.wrapping_add(1);
        queue.write_buffer(&self.params_buffer, 0, bytemuck::bytes_of(&self.params));
        Ok(())
    }

    /// The parameters the next frame runs with (the CPU twin's [`NearFieldInputs::params`]).
    pub fn params(&self) -> NearFieldParams {
        self.params
    }

    /// Records the pass into `encoder`, timed as "near field".
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&PassTimer>) {
        self.passes.encode(encoder, timer);
    }
}
