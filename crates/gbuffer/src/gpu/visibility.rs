//! A visibility buffer written by a compute rasteriser (Burns & Hunt 2013): per pixel the
//! nearest triangle's depth and id in 64 bits, `(depth bits << 32) | id`, merged with 64-bit
//! `atomicMin`, or in two passes of 32-bit `atomicMin` on devices without it ([`Atomics`]:
//! the same buffer, bit for bit, at twice the coverage work; `visibility.wgsl`,
//! `visibility_word.wgsl`). Coverage and depth are [`crate::cpu::rasterize`]'s — same
//! clip planes, snapping, top-left rule and depth test in submission order — so its triangle
//! ids are the CPU's ([`crate::cpu::Rasterized::triangle_id`]) but for pixels on triangle
//! edges where the two compute a vertex's clip position or depth one rounding apart.
//!
//! **Split rule.** All meshes go through one set of dispatches. One invocation per triangle
//! covers the pixels of its bounding box when the box has at most 64 pixels and no vertex lies
//! outside a clip plane (near, far, the 4w guard band); every other triangle is deferred: one
//! invocation clips it into a fan and cuts each fan triangle's box into 32 × 32 blocks, and a
//! workgroup of 64 invocations covers each block. Lists that overflow their capacity
//! ([`Capacity`]) lose triangles; [`Visibility::overflow`] reads how many entries did not fit.
//!
//! **Meshes drawn by the hardware rasteriser.** Alpha-tested meshes (masked, or blended and
//! dithered): their coverage depends on a texture lookup, so the hardware rasteriser draws them
//! into the same buffer, each fragment the G-buffer pass would keep merging its depth and id
//! the same way ([`Visibility::encode`], `visibility_hardware.wgsl`). Any other mesh can be
//! drawn so too ([`VisibilityPass::bind_split`]): meshes of large triangles, which the
//! hardware rasteriser covers faster than the deferred path's blocks
//! ([`GpuScene::pixels_per_triangle`] ranks them; the renderer measures where to split). Blended meshes the scene draws
//! forward ([`BlendedSurfaces::Forward`](super::BlendedSurfaces)) are left out, as the
//! G-buffer pass leaves them out. The device needs no feature ([`FEATURES`]: the edge
//! functions' products are exact in pairs of 32-bit words; 64-bit atomics, [`WIDE_FEATURES`],
//! are used where it has them), and the resolve ([`ResolvePass`]) five storage textures per
//! stage ([`device_needs`]).
//!
//! ```no_run
//! use gbuffer::{Frame, gpu::{GBufferPass, GBufferTargets, GpuScene, visibility::{self, ResolvePass, VisibilityPass}}};
//! # let gpu = gpu::Gpu::from_env_with(&visibility::device_needs())?;
//! let scene = scene::spheres_on_plane(4);
//! let gpass = GBufferPass::new(&gpu.device)?;
//! let uploaded = GpuScene::upload(&gpu.device, &gpu.queue, &scene, &gpass)?;
//! gpass.write_frame(&gpu.queue, &Frame::new(&scene.camera_or_framed(), 640, 480));
//! let buffer = VisibilityPass::buffer(&gpu.device, 640, 480)?;
//! let targets = GBufferTargets::new(&gpu.device, 640, 480)?;
//! let vis = VisibilityPass::new(&gpu.device, &gpass)?.bind(
//!     &gpu.device, &uploaded, gpass.frame_buffer(), (640, 480), &buffer)?;
//! let resolve = ResolvePass::new(&gpu.device, &gpass)?.bind(
//!     &gpu.device, &uploaded, gpass.frame_buffer(), &vis, &targets)?;
//! let mut encoder = gpu.device.create_command_encoder(&Default::default());
//! vis.encode(&mut encoder, Some(&targets.depth), None)?;
//! resolve.passes.encode(&mut encoder, None);
//! gpu.queue.submit([encoder.finish()]);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use ::gpu::kernel::{self, Binding, Dispatch, Layout, Passes, Workgroups};
use ::gpu::shader::Specialisation;
use ::gpu::{PassTimer, transfer, wgpu};
use bytemuck::{Pod, Zeroable};
use std::sync::Mutex;

use super::upload::GpuScene;
use crate::GBufferError;

/// What the kernels need of a device's features: none (the edge functions' 64-bit products
/// are taken exactly in 32-bit words, and [`Atomics::Narrow`] merges with 32-bit atomics).
pub const FEATURES: wgpu::Features = wgpu::Features::empty();

/// What [`Atomics::Wide`] needs: 64-bit integers and 64-bit atomic min on storage buffers.
pub const WIDE_FEATURES: wgpu::Features =
    wgpu::Features::SHADER_INT64.union(wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX);

/// What the resolve in one dispatch ([`ResolvePath::OneDispatch`]) needs: binding arrays of
/// textures and samplers, indexed by values that differ between invocations; and room in
/// them for every texture of the scene ([`bindless_needs`]).
pub const BINDLESS_FEATURES: wgpu::Features = wgpu::Features::TEXTURE_BINDING_ARRAY
    .union(wgpu::Features::SAMPLED_TEXTURE_AND_STORAGE_BUFFER_ARRAY_NON_UNIFORM_INDEXING);

/// [`device_needs`] with [`BINDLESS_FEATURES`] and binding arrays of `textures` textures and
/// samplers: a device on which a scene of that many textures
/// ([`super::MaterialTextures::all`]) resolves in one dispatch.
pub fn bindless_needs(textures: u32) -> ::gpu::DeviceNeeds {
    let mut needs = device_needs();
    needs.features |= BINDLESS_FEATURES;
    needs.limits.max_binding_array_elements_per_shader_stage = textures;
    needs
        .limits
        .max_binding_array_sampler_elements_per_shader_stage = textures;
    needs
}

/// Storage textures the resolve writes in one stage (the five colour targets; WebGPU's
/// default limit is 4).
pub const STORAGE_TEXTURES: u32 = 5;

/// The device this module's kernels need: [`FEATURES`], and [`STORAGE_TEXTURES`] storage
/// textures per stage.
pub fn device_needs() -> ::gpu::DeviceNeeds {
    ::gpu::DeviceNeeds {
        features: FEATURES,
        limits: wgpu::Limits {
            max_storage_textures_per_shader_stage: STORAGE_TEXTURES,
            ..Default::default()
        },
    }
}

/// The id of a pixel no triangle covers.
pub const NO_TRIANGLE: u32 = u32::MAX;

const WORKGROUP: u32 = 64;

/// How many entries the deferred path's lists hold.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Capacity {
    /// Deferred triangles (large or clipped).
    pub deferred: u32,
    /// Their fan triangles, set up.
    pub setups: u32,
    /// 32 × 32 blocks of the fan triangles' boxes.
    pub blocks: u32,
}

impl Default for Capacity {
    /// 2^20 deferred triangles, 2^16 fan triangles, 2^22 blocks (about 60 MB).
    fn default() -> Self {
        Self {
            deferred: 1 << 20,
            setups: 1 << 16,
            blocks: 1 << 22,
        }
    }
}

impl Capacity {
    /// Four times the entries of each list, within `device`'s largest storage binding; none
    /// when every list is already at that limit.
    pub fn grown(self, device: &wgpu::Device) -> Option<Self> {
        let limits = device.limits();
        let largest = limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size);
        let grow = |entries: u32, bytes: u64| (u64::from(entries) * 4).min(largest / bytes) as u32;
        let grown = Self {
            deferred: grow(self.deferred, 4),
            setups: grow(self.setups, SETUP_BYTES),
            blocks: grow(self.blocks, 8),
        };
        (grown != self).then_some(grown)
    }
}

/// Bytes of one set-up fan triangle (`LargeSetup` of `visibility.wgsl`: its `Setup` of 128
/// bytes and the id, rounded to the 16-byte alignment).
const SETUP_BYTES: u64 = 144;

/// Uniform block `Raster` of `visibility.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct RasterUniform {
    triangle_count: u32,
    _pad: [u32; 3],
}

/// Checks that `visibility` holds `width × height` pixels.
fn check_buffer(
    visibility: &wgpu::Buffer,
    (width, height): (u32, u32),
) -> Result<(), GBufferError> {
    crate::validate_size(width, height)?;
    let needed = u64::from(width) * u64::from(height) * 8;
    if visibility.size() != needed {
        return Err(GBufferError::InvalidOptions(format!(
            "a visibility buffer of {} bytes for {width}×{height} pixels (needs {needed})",
            visibility.size()
        )));
    }
    Ok(())
}

/// A mesh in triangle-id order: `Mesh` of `meshes.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct MeshEntry {
    first_id: u32,
    base_vertex: u32,
    first_index: u32,
    /// Triangles rasterised (0 for a mesh left out).
    triangle_count: u32,
    cull_back: u32,
    material: u32,
    /// The resolve's index of `material` ([`Visibility::materials`]); `NO_SLOT` for a mesh
    /// left out.
    slot: u32,
    _pad: u32,
}

const NO_SLOT: u32 = u32::MAX;

/// The uploaded scene's meshes in triangle-id order (ids numbered over the meshes' index
/// slots, as the CPU rasteriser numbers [`Scene::meshes`]' triangles).
struct MeshTable {
    entries: Vec<MeshEntry>,
    /// Meshes drawn by the hardware rasteriser: those whose material discards fragments by
    /// alpha, and those asked for.
    hardware: Vec<usize>,
    /// The materials the other meshes draw, in slot order.
    materials: Vec<usize>,
    /// Triangle ids spanned.
    triangle_count: u32,
}

fn mesh_table(uploaded: &GpuScene, asked: &[usize]) -> MeshTable {
    let mut entries = Vec::with_capacity(uploaded.draws.len());
    let mut hardware = Vec::new();
    let mut materials: Vec<usize> = Vec::new();
    let mut first_id = 0u32;
    let forward = uploaded.blended() == super::BlendedSurfaces::Forward;
    for (m, draw) in uploaded.draws.iter().enumerate() {
        let triangles = draw.index_count / 3;
        // As the G-buffer pass draws: blended meshes drawn forward are not in the G-buffer.
        let drawn = triangles > 0 && !(forward && draw.state.blended);
        let by_hardware = drawn && (draw.state.alpha_tested || asked.contains(&m));
        if by_hardware {
            hardware.push(m);
        }
        let slot = if !drawn {
            NO_SLOT
        } else if let Some(s) = materials.iter().position(|&k| k == draw.material) {
            s as u32
        } else {
            materials.push(draw.material);
            materials.len() as u32 - 1
        };
        entries.push(MeshEntry {
            first_id,
            base_vertex: draw.base_vertex as u32,
            first_index: draw.first_index,
            triangle_count: if drawn && !by_hardware { triangles } else { 0 },
            cull_back: u32::from(draw.state.cull),
            material: draw.material as u32,
            slot,
            _pad: 0,
        });
        first_id += triangles;
    }
    MeshTable {
        entries,
        hardware,
        materials,
        triangle_count: first_id,
    }
}

/// How covered pixels are merged into the visibility buffer (`visibility_word.wgsl`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Atomics {
    /// One 64-bit `atomicMin` of (depth bits << 32) | id per covered pixel: needs
    /// `SHADER_INT64_ATOMIC_MIN_MAX`.
    Wide,
    /// Two passes over the same coverage with 32-bit `atomicMin`, on the depth word, then on
    /// the id word where the depth is the one the first pass left: the same buffer bit for
    /// bit (no precision is given up) at twice the coverage work.
    Narrow,
}

impl Atomics {
    /// [`Atomics::Wide`] where the device has 64-bit atomic min, else [`Atomics::Narrow`].
    pub fn best(device: &wgpu::Device) -> Self {
        if device.features().contains(WIDE_FEATURES) {
            Self::Wide
        } else {
            Self::Narrow
        }
    }

    /// The shader variant: the depth pass (or the only one), or the narrow id pass.
    fn specialisation(self, id_pass: bool) -> Specialisation {
        match self {
            Self::Wide => Specialisation::default(),
            Self::Narrow => Specialisation::default()
                .set("VisibilityWord", "atomic<u32>")
                .set("VisibilityValue", "u32")
                .set("WIDE_ATOMICS", "false")
                .set("DEPTH_SHIFT", "0u")
                .set("ID_PASS", id_pass),
        }
    }
}

/// Every variant of the shaders the kernels build (for validation without a GPU): the
/// rasteriser and the hardware rasteriser's draw, wide, and narrow in both passes.
pub fn shader_variants() -> Vec<(&'static str, Specialisation)> {
    let variants = [
        Atomics::Wide.specialisation(false),
        Atomics::Narrow.specialisation(false),
        Atomics::Narrow.specialisation(true),
    ];
    ["visibility.wgsl", "visibility_hardware.wgsl"]
        .into_iter()
        .flat_map(|file| variants.iter().map(move |v| (file, v.clone())))
        .collect()
}

/// One variant's pipelines: the compute rasteriser's and the hardware rasteriser's draw's.
struct Pipelines {
    small: wgpu::ComputePipeline,
    tiles: wgpu::ComputePipeline,
    /// Two-sided, one-sided (back faces culled).
    hardware: [wgpu::RenderPipeline; 2],
}

/// The visibility buffer's kernels (phase `new`).
pub struct VisibilityPass {
    layout: Layout,
    /// `prepare`'s groups: the counts and lists it reads (bindings 5, 6 and 8 of group 0),
    /// the indirect dispatch sizes (group 1).
    prepare_layouts: [Layout; 2],
    /// The hardware draw's group 0: frame, meshes, positions, attributes, the visibility
    /// buffer (fragment stage), indices; the material is group 1.
    hardware_layout: Layout,
    capacity: Capacity,
    atomics: Atomics,
    clear: wgpu::ComputePipeline,
    prepare: wgpu::ComputePipeline,
    setup_large: wgpu::ComputePipeline,
    /// The wide merge's or the narrow depth pass's.
    first: Pipelines,
    /// The narrow id pass's.
    ids: Option<Pipelines>,
}

/// The hardware rasteriser's draws of one binding (alpha-tested meshes and those asked for).
struct HardwareDraws {
    group: wgpu::BindGroup,
    /// Per mesh: its index slots, its index (the instance drawn), its material's group, and
    /// whether it is one-sided.
    draws: Vec<(std::ops::Range<u32>, u32, wgpu::BindGroup, bool)>,
}

/// The passes writing one scene's visibility buffer (phase `bind`); recorded by
/// [`Visibility::encode`].
pub struct Visibility {
    /// Clear, the per-triangle rasterisation, the deferred triangles' setup and their blocks
    /// (the narrow merge's depth pass).
    passes: Passes,
    /// The narrow merge's id pass: per triangle again, and the depth pass's blocks.
    id_passes: Option<Passes>,
    hardware_draws: Option<HardwareDraws>,
    /// The hardware draw's pipelines, per pass.
    hardware_pipelines: Vec<[wgpu::RenderPipeline; 2]>,
    /// The names the passes are timed under ([`Visibility::pass_names`]).
    names: Vec<String>,
    /// Meshes (indices in the uploaded scene's meshes) drawn with the hardware rasteriser:
    /// those whose material discards fragments by alpha, and those
    /// [`VisibilityPass::bind_split`] was given.
    pub hardware: Vec<usize>,
    /// Deferred triangles, setups and blocks appended, and entries that did not fit (four
    /// `u32`s; `COPY_SRC`).
    pub counts: wgpu::Buffer,
    /// The materials drawn (indices in the uploaded scene's materials), in the resolve's
    /// slot order.
    pub materials: Vec<usize>,
    /// The buffer written and its size, the mesh table: what [`ResolvePass::bind`] reads.
    buffer: wgpu::Buffer,
    size: (u32, u32),
    meshes: wgpu::Buffer,
}

impl Visibility {
    /// How many list entries the last frame could not hold (0 when nothing was lost); waits
    /// for the GPU.
    pub fn overflow(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<u32, GBufferError> {
        let counts: Vec<u32> = transfer::read_pod(device, queue, &self.counts)?;
        Ok(counts[3])
    }

    /// These passes timed under names starting with `prefix` (`"ss "`: `ss visibility`, …).
    pub fn named(mut self, prefix: &str) -> Self {
        for name in &mut self.names {
            name.insert_str(0, prefix);
        }
        self.passes = self.passes.named(&self.names[0]);
        if let Some(ids) = self.id_passes.take() {
            let at = if self.hardware_draws.is_some() { 2 } else { 1 };
            self.id_passes = Some(ids.named(&self.names[at]));
        }
        self
    }

    /// The same passes with each compute dispatch timed on its own, as `<name> <stage>` for
    /// the stages of [`RASTER_STAGES`] (the narrow merge's id passes: `small`, `tiles`): a
    /// profile for benchmarks, at the cost of a pass boundary between dispatches.
    pub fn profiled(mut self) -> Self {
        let stages = |name: String, stages: &'static [&'static str]| {
            move |i: usize| format!("{name} {}", stages[i.min(stages.len() - 1)])
        };
        self.passes = self
            .passes
            .per_dispatch(stages(self.names[0].clone(), &RASTER_STAGES));
        if let Some(ids) = self.id_passes.take() {
            let at = if self.hardware_draws.is_some() { 2 } else { 1 };
            let name = self.names[at].clone();
            self.id_passes = Some(ids.per_dispatch(stages(name, &["small", "tiles"])));
        }
        self
    }

    /// The names the passes are timed under, in order: `visibility`, `visibility hardware`
    /// (with meshes drawn by the hardware rasteriser), and for the narrow merge `visibility
    /// ids`, `visibility hardware ids` ([`Visibility::named`] puts a prefix before each).
    pub fn pass_names(&self) -> &[String] {
        &self.names
    }

    /// Records the frame's visibility buffer: the compute passes and, with meshes for the
    /// hardware rasteriser ([`Visibility::hardware`]), its draw of them, whose depth attachment `depth` (a
    /// [`crate::DEPTH_FORMAT`] render target of the buffer's size, e.g. the G-buffer's depth
    /// target) is cleared and not stored; then the narrow merge's id passes. Fails, recording
    /// nothing, when those meshes have no fitting `depth`.
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        depth: Option<&wgpu::Texture>,
        timer: Option<&PassTimer>,
    ) -> Result<(), GBufferError> {
        let attachment = match (&self.hardware_draws, depth) {
            (None, _) => None,
            (Some(_), None) => {
                return Err(GBufferError::InvalidOptions(format!(
                    "meshes {:?} are drawn by the hardware rasteriser: their draw into the visibility buffer needs a depth attachment",
                    self.hardware
                )));
            }
            (Some(_), Some(depth)) => {
                ::gpu::kernel::check_texture(
                    "the hardware draw's depth attachment",
                    depth,
                    self.size,
                    crate::DEPTH_FORMAT,
                    wgpu::TextureUsages::RENDER_ATTACHMENT,
                )?;
                Some(depth.create_view(&Default::default()))
            }
        };
        // Each phase's compute passes carry their name; its hardware draw's follows it.
        let mut hardware_names = self.names.iter().skip(1).step_by(2);
        let phases = std::iter::once(&self.passes).chain(&self.id_passes);
        for (passes, pipelines) in phases.zip(&self.hardware_pipelines) {
            passes.encode(encoder, timer);
            if let (Some(draws), Some(view), Some(name)) =
                (&self.hardware_draws, &attachment, hardware_names.next())
            {
                draw_hardware(
                    encoder,
                    draws,
                    pipelines,
                    view,
                    timer.and_then(|t| t.render_pass(name)),
                );
            }
        }
        Ok(())
    }
}

/// The compute rasteriser's dispatches in order ([`Visibility::profiled`]): the buffer's
/// clear, one invocation per triangle (`raster_small`), the indirect sizes, the deferred
/// triangles' set-up, the sizes again, and the blocks (`raster_tiles`).
pub const RASTER_STAGES: [&str; 6] = [
    "clear",
    "small",
    "prepare",
    "setup large",
    "prepare",
    "tiles",
];

/// The passes' names: `visibility`, then the hardware rasteriser's draw's (`hardware`), and
/// the narrow merge's id passes and their draw (`narrow`).
fn pass_names(hardware: bool, narrow: bool) -> Vec<String> {
    let phases: &[&str] = if narrow { &["", " ids"] } else { &[""] };
    phases
        .iter()
        .flat_map(|phase| {
            let compute = format!("visibility{phase}");
            let draw = hardware.then(|| format!("visibility hardware{phase}"));
            std::iter::once(compute).chain(draw)
        })
        .collect()
}

/// The hardware rasteriser's pass drawing its meshes into the visibility buffer.
fn draw_hardware(
    encoder: &mut wgpu::CommandEncoder,
    draws: &HardwareDraws,
    pipelines: &[wgpu::RenderPipeline; 2],
    depth: &wgpu::TextureView,
    timestamps: Option<wgpu::RenderPassTimestampWrites<'_>>,
) {
    let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("visibility hardware"),
        color_attachments: &[],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: depth,
            depth_ops: Some(wgpu::Operations {
                load: wgpu::LoadOp::Clear(1.0),
                store: wgpu::StoreOp::Discard,
            }),
            stencil_ops: None,
        }),
        timestamp_writes: timestamps,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    pass.set_bind_group(0, &draws.group, &[]);
    for (slots, mesh, material, one_sided) in &draws.draws {
        pass.set_pipeline(&pipelines[usize::from(*one_sided)]);
        pass.set_bind_group(1, material, &[]);
        pass.draw(slots.clone(), *mesh..*mesh + 1);
    }
}

impl VisibilityPass {
    /// Builds the kernels with the default [`Capacity`] and the [best](Atomics::best) merge;
    /// materials bind as `gpass` binds them (the hardware rasteriser's draw). The device must
    /// have [`FEATURES`].
    pub fn new(device: &wgpu::Device, gpass: &super::GBufferPass) -> Result<Self, GBufferError> {
        Self::with(device, gpass, Capacity::default(), Atomics::best(device))
    }

    /// [`VisibilityPass::new`] with the deferred path's lists sized as `capacity` says and
    /// pixels merged as `atomics` says ([`Atomics::Wide`] needs [`WIDE_FEATURES`]).
    pub fn with(
        device: &wgpu::Device,
        gpass: &super::GBufferPass,
        capacity: Capacity,
        atomics: Atomics,
    ) -> Result<Self, GBufferError> {
        let needed = match atomics {
            Atomics::Wide => FEATURES | WIDE_FEATURES,
            Atomics::Narrow => FEATURES,
        };
        let missing = needed - device.features();
        if !missing.is_empty() {
            return Err(GBufferError::InvalidOptions(format!(
                "the visibility buffer ({atomics:?} atomics) needs device features {missing:?}"
            )));
        }
        let mut bindings = vec![Binding::Uniform];
        bindings.extend([Binding::StorageRead; 3]);
        bindings.extend([Binding::Storage; 5]);
        bindings.push(Binding::Uniform);
        let layout = Layout::compute(device, "visibility", &bindings);
        let prepare_layouts = [
            Layout::compute_numbered(
                device,
                "visibility lists",
                &[
                    (5, Binding::Storage),
                    (6, Binding::Storage),
                    (8, Binding::Storage),
                ],
            ),
            Layout::compute(device, "visibility dispatch", &[Binding::Storage]),
        ];
        let both = wgpu::ShaderStages::VERTEX_FRAGMENT;
        let vertex = wgpu::ShaderStages::VERTEX;
        let hardware_layout = Layout::staged(
            device,
            "visibility hardware",
            &[
                (0, both, Binding::Uniform),
                (1, vertex, Binding::StorageRead),
                (2, vertex, Binding::StorageRead),
                (3, vertex, Binding::StorageRead),
                (4, wgpu::ShaderStages::FRAGMENT, Binding::Storage),
                (5, vertex, Binding::StorageRead),
            ],
        );
        let hardware_pipeline_layout = kernel::pipeline_layout(
            device,
            "visibility hardware",
            &[&hardware_layout, &gpass.material_layout],
        );
        let module = |id_pass| {
            crate::SHADERS.module_with(device, "visibility.wgsl", &atomics.specialisation(id_pass))
        };
        let pipelines = |id_pass| -> Result<(wgpu::ShaderModule, Pipelines), GBufferError> {
            let compute = module(id_pass)?;
            let draw = crate::SHADERS.module_with(
                device,
                "visibility_hardware.wgsl",
                &atomics.specialisation(id_pass),
            )?;
            let pipeline = |entry| kernel::pipeline(device, &compute, entry, &[&layout], &[]);
            let built = Pipelines {
                small: pipeline("raster_small"),
                tiles: pipeline("raster_tiles"),
                hardware: [None, Some(wgpu::Face::Back)]
                    .map(|cull| hardware_pipeline(device, &hardware_pipeline_layout, &draw, cull)),
            };
            Ok((compute, built))
        };
        let (first_module, first) = pipelines(false)?;
        let ids = match atomics {
            Atomics::Wide => None,
            Atomics::Narrow => Some(pipelines(true)?.1),
        };
        Ok(Self {
            clear: kernel::pipeline(device, &first_module, "clear", &[&layout], &[]),
            setup_large: kernel::pipeline(device, &first_module, "setup_large", &[&layout], &[]),
            prepare: kernel::pipeline(
                device,
                &first_module,
                "prepare",
                &[&prepare_layouts[0], &prepare_layouts[1]],
                &[],
            ),
            prepare_layouts,
            hardware_layout,
            layout,
            capacity,
            atomics,
            first,
            ids,
        })
    }

    /// How this pass merges covered pixels.
    pub fn atomics(&self) -> Atomics {
        self.atomics
    }

    /// The deferred path's list capacities (at most: [`VisibilityPass::bind`] sizes them to
    /// what the scene can append).
    pub fn capacity(&self) -> Capacity {
        self.capacity
    }

    /// A visibility buffer for `width × height` pixels (8 bytes each, row-major; `STORAGE |
    /// COPY_SRC`).
    pub fn buffer(
        device: &wgpu::Device,
        width: u32,
        height: u32,
    ) -> Result<wgpu::Buffer, GBufferError> {
        crate::validate_size(width, height)?;
        Ok(transfer::buffer(
            device,
            "visibility buffer",
            u64::from(width) * u64::from(height) * 8,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        )?)
    }

    /// The passes writing `visibility` (a [`VisibilityPass::buffer`] of `size`) for the
    /// `uploaded` scene seen through `frame`, a [`Frame`](crate::Frame) uniform of that size (the G-buffer
    /// pass's [`GBufferPass::frame_buffer`](super::GBufferPass::frame_buffer): the passes
    /// follow the camera it is written with). Alpha-tested meshes are drawn by the hardware
    /// rasteriser, the others by the compute rasteriser.
    pub fn bind(
        &self,
        device: &wgpu::Device,
        uploaded: &GpuScene,
        frame: &wgpu::Buffer,
        size: (u32, u32),
        visibility: &wgpu::Buffer,
    ) -> Result<Visibility, GBufferError> {
        self.bind_split(device, uploaded, frame, size, visibility, &[])
    }

    /// [`VisibilityPass::bind`] with the meshes `hardware` (indices in the uploaded scene's
    /// meshes) drawn by the hardware rasteriser too, into the same buffer: the same ids and
    /// depths but on triangle edges, where coverage follows the hardware's rules. Fails on
    /// an index past the scene's meshes.
    pub fn bind_split(
        &self,
        device: &wgpu::Device,
        uploaded: &GpuScene,
        frame: &wgpu::Buffer,
        size: (u32, u32),
        visibility: &wgpu::Buffer,
        hardware: &[usize],
    ) -> Result<Visibility, GBufferError> {
        check_buffer(visibility, size)?;
        if let Some(m) = hardware.iter().find(|&&m| m >= uploaded.draws.len()) {
            return Err(GBufferError::InvalidOptions(format!(
                "mesh {m} cannot be drawn by the hardware rasteriser: the scene has {} meshes",
                uploaded.draws.len()
            )));
        }
        let table = mesh_table(uploaded, hardware);
        let triangle_count = table.triangle_count;
        let storage = wgpu::BufferUsages::STORAGE;
        let list =
            |label, bytes: u64, usage| transfer::buffer(device, label, bytes, storage | usage);
        let none = wgpu::BufferUsages::empty();
        let meshes = transfer::buffer_init(
            device,
            "visibility meshes",
            bytemuck::cast_slice(&table.entries),
            storage,
        )?;
        let uniform = transfer::buffer_init(
            device,
            "visibility raster",
            bytemuck::bytes_of(&RasterUniform {
                triangle_count,
                _pad: [0; 3],
            }),
            wgpu::BufferUsages::UNIFORM,
        )?;
        // No list needs more entries than the scene can append: each triangle is deferred at
        // most once, clips into at most seven fan triangles, each covering at most the image.
        let image_blocks = u64::from(size.0.div_ceil(32)) * u64::from(size.1.div_ceil(32));
        let fan = u64::from(triangle_count.max(1)) * 7;
        let c = Capacity {
            deferred: self.capacity.deferred.min(triangle_count.max(1)),
            setups: u64::from(self.capacity.setups).min(fan) as u32,
            blocks: u64::from(self.capacity.blocks).min(fan.saturating_mul(image_blocks)) as u32,
        };
        let counts = list("visibility counts", 16, wgpu::BufferUsages::COPY_SRC)?;
        let dispatch = list("visibility dispatch", 24, wgpu::BufferUsages::INDIRECT)?;
        let deferred = list("visibility deferred", u64::from(c.deferred) * 4, none)?;
        let setups = list("visibility setups", u64::from(c.setups) * SETUP_BYTES, none)?;
        let blocks = list("visibility blocks", u64::from(c.blocks) * 8, none)?;
        let prepare_groups = vec![
            self.prepare_layouts[0].bind(
                device,
                &[&counts, &deferred, &blocks].map(|b| b.as_entire_binding()),
            ),
            self.prepare_layouts[1].bind_buffers(device, &[&dispatch]),
        ];
        let group = self.layout.bind_buffers(
            device,
            &[
                frame,
                &meshes,
                &uploaded.positions,
                &uploaded.indices,
                visibility,
                &counts,
                &deferred,
                &setups,
                &blocks,
                &uniform,
            ],
        );
        let one = |pipeline: &wgpu::ComputePipeline, workgroups| Dispatch {
            pipeline: pipeline.clone(),
            groups: vec![group.clone()],
            workgroups,
        };
        let prepare = || Dispatch {
            pipeline: self.prepare.clone(),
            groups: prepare_groups.clone(),
            workgroups: Workgroups::Direct([1, 1, 1]),
        };
        let per_triangle = Workgroups::linear(triangle_count, WORKGROUP);
        let tiles = Workgroups::Indirect(dispatch.clone(), 12);
        // One 64-bit word per pixel, as two 32-bit words for the narrow merge.
        let words = (visibility.size() / 8) as u32 * if self.ids.is_some() { 2 } else { 1 };
        let dispatches = vec![
            one(&self.clear, Workgroups::linear(words, WORKGROUP)),
            one(&self.first.small, per_triangle.clone()),
            prepare(),
            one(&self.setup_large, Workgroups::Indirect(dispatch.clone(), 0)),
            prepare(),
            one(&self.first.tiles, tiles.clone()),
        ];
        let id_passes = self.ids.as_ref().map(|ids| {
            Passes::new().pass(
                "visibility ids",
                vec![one(&ids.small, per_triangle), one(&ids.tiles, tiles)],
            )
        });
        let hardware_draws = (!table.hardware.is_empty()).then(|| HardwareDraws {
            group: self.hardware_layout.bind_buffers(
                device,
                &[
                    frame,
                    &meshes,
                    &uploaded.positions,
                    &uploaded.attributes,
                    visibility,
                    &uploaded.indices,
                ],
            ),
            draws: table
                .hardware
                .iter()
                .map(|&m| {
                    let d = &uploaded.draws[m];
                    (
                        d.first_index..d.first_index + d.index_count,
                        m as u32,
                        uploaded.material_groups[d.material].clone(),
                        d.state.cull,
                    )
                })
                .collect(),
        });
        Ok(Visibility {
            passes: Passes::new().pass("visibility", dispatches),
            id_passes,
            hardware_draws,
            hardware_pipelines: std::iter::once(&self.first)
                .chain(&self.ids)
                .map(|p| p.hardware.clone())
                .collect(),
            names: pass_names(!table.hardware.is_empty(), self.ids.is_some()),
            hardware: table.hardware,
            counts,
            materials: table.materials,
            buffer: visibility.clone(),
            size,
            meshes,
        })
    }
}

/// The hardware rasteriser's render pipeline (`visibility_hardware.wgsl`) culling `cull`: the
/// G-buffer pass's winding, no colour target, a depth attachment neither tested nor written.
fn hardware_pipeline(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    cull_mode: Option<wgpu::Face>,
) -> wgpu::RenderPipeline {
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("visibility hardware"),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some("vs_hardware"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState {
            front_face: wgpu::FrontFace::Ccw,
            cull_mode,
            ..Default::default()
        },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: crate::DEPTH_FORMAT,
            depth_write_enabled: Some(false),
            depth_compare: Some(wgpu::CompareFunction::Always),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some("fs_hardware"),
            compilation_options: Default::default(),
            targets: &[],
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// A read-back visibility buffer's triangle ids ([`NO_TRIANGLE`] where none), row-major.
pub fn triangle_ids(words: &[u64]) -> Vec<u32> {
    words.iter().map(|&w| w as u32).collect()
}

/// Uniform block `Resolve` of `resolve.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ResolveUniform {
    slot: u32,
    slots: u32,
    tiles_x: u32,
    _pad: u32,
}

/// How [`ResolvePass::bind`] reaches the materials.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ResolvePath {
    /// Pixels classified by 8 × 8 tile into a list per material, then one indirect dispatch
    /// per material with its bind group: runs on every device.
    Classified,
    /// One dispatch over every pixel, each reading its material from one table and its
    /// textures from binding arrays (`resolve_bindless.wgsl`): no classification and no
    /// dispatch per material. Needs [`BINDLESS_FEATURES`] and binding arrays as large as the
    /// scene's textures ([`bindless_needs`]); [`ResolvePass::bind`] falls back to
    /// [`ResolvePath::Classified`] elsewhere.
    OneDispatch,
}

/// The side of the tiles the resolve classifies pixels by.
const RESOLVE_TILE: u32 = 8;

/// The visibility buffer resolved into the G-buffer layout (`resolve.wgsl`): per pixel the
/// triangle is fetched again, its attributes interpolated with perspective-correct
/// barycentrics at the pixel centre and their derivatives taken analytically towards the
/// 2 × 2 quad's other pixels (what `dpdxFine`/`dpdyFine` and the CPU rasteriser take), and its
/// material evaluated as the G-buffer pass's fragment shader does. Pixels are classified once
/// by 8 × 8 tile (a list of tiles per material, on the GPU); then one indirect dispatch per
/// material covers its tiles alone. It writes the linear depth, normal, albedo, material and
/// emission targets; the hardware depth target is drawn by [`ResolvePass::encode_depth`].
pub struct ResolvePass {
    layout: Layout,
    /// `classify_scan`'s second group: the dispatch sizes (binding 11).
    dispatch_layout: Layout,
    material: wgpu::ComputePipeline,
    classify_count: wgpu::ComputePipeline,
    classify_scan: wgpu::ComputePipeline,
    classify_write: wgpu::ComputePipeline,
    /// The depth target's pass: the frame (binding 0) and the visibility buffer (binding 2).
    depth_layout: Layout,
    depth: wgpu::RenderPipeline,
    /// Whether [`ResolvePath::OneDispatch`] was asked for and the device has
    /// [`BINDLESS_FEATURES`] (its kernel is built per scene, its arrays sized to the scene's
    /// textures).
    bindless: bool,
    /// The one-dispatch kernel and its group-1 layout last built, for this many textures: a
    /// rebind with as many (the split rule moving a mesh, a resize) reuses them.
    one_dispatch_kernel: Mutex<Option<(u32, wgpu::ComputePipeline, Layout)>>,
}

/// [`ResolvePass::bind`]'s result: the compute passes writing the colour targets, and what
/// [`ResolvePass::encode_depth`] draws the depth target with.
pub struct Resolve {
    /// [`ResolvePath::Classified`]: the classification (three dispatches), then one dispatch
    /// per material; [`ResolvePath::OneDispatch`]: one dispatch.
    pub passes: Passes,
    /// The path bound.
    pub path: ResolvePath,
    depth_group: wgpu::BindGroup,
}

/// The classified resolve's dispatches in order ([`Resolve::profiled`]): the classification's
/// three, then the materials' (timed together).
pub const RESOLVE_STAGES: [&str; 4] = ["count", "scan", "write", "materials"];

impl Resolve {
    /// The resolve's passes with each stage of [`RESOLVE_STAGES`] timed on its own, as
    /// `visibility resolve <stage>` (the one dispatch of [`ResolvePath::OneDispatch`] as
    /// `visibility resolve one dispatch`): a profile for benchmarks.
    pub fn profiled(&self) -> Passes {
        let last = RESOLVE_STAGES.len() - 1;
        let path = self.path;
        self.passes.per_dispatch(|i| match path {
            ResolvePath::Classified => {
                format!("visibility resolve {}", RESOLVE_STAGES[i.min(last)])
            }
            ResolvePath::OneDispatch => "visibility resolve one dispatch".into(),
        })
    }
}

impl ResolvePass {
    /// Builds the kernels; materials bind as `gpass` binds them. The device must allow
    /// [`STORAGE_TEXTURES`] storage textures per stage. [`ResolvePass::bind`] resolves in one
    /// dispatch where the device allows it ([`ResolvePath::OneDispatch`]).
    pub fn new(device: &wgpu::Device, gpass: &super::GBufferPass) -> Result<Self, GBufferError> {
        Self::with(device, gpass, ResolvePath::OneDispatch)
    }

    /// [`ResolvePass::new`] with the path `bind` prefers: [`ResolvePath::Classified`] binds the
    /// classified path whatever the device.
    pub fn with(
        device: &wgpu::Device,
        gpass: &super::GBufferPass,
        path: ResolvePath,
    ) -> Result<Self, GBufferError> {
        let allowed = device.limits().max_storage_textures_per_shader_stage;
        if allowed < STORAGE_TEXTURES {
            return Err(GBufferError::InvalidOptions(format!(
                "the visibility buffer's resolve writes {STORAGE_TEXTURES} storage textures; the device allows {allowed}"
            )));
        }
        let module = crate::SHADERS.module(device, "resolve.wgsl")?;
        // Frame, meshes, visibility, the slot's uniform, positions, attributes, indices, the
        // five targets, the classes and the tile lists.
        let mut bindings = vec![Binding::Uniform, Binding::StorageRead, Binding::StorageRead];
        bindings.push(Binding::Uniform);
        bindings.extend([Binding::StorageRead; 3]);
        bindings.extend(
            [
                crate::LINEAR_DEPTH_FORMAT,
                crate::NORMAL_FORMAT,
                crate::ALBEDO_FORMAT,
                crate::MATERIAL_FORMAT,
                crate::EMISSION_FORMAT,
            ]
            .map(Binding::StorageTexture),
        );
        bindings.extend([Binding::Storage; 2]);
        let layout = Layout::compute(device, "visibility resolve", &bindings);
        let dispatch_layout = Layout::compute_numbered(
            device,
            "visibility resolve dispatch",
            &[(11, Binding::Storage)],
        );
        let classify = |entry| kernel::pipeline(device, &module, entry, &[&layout], &[]);
        let material = kernel::pipeline(
            device,
            &module,
            "resolve_material",
            &[&layout, &gpass.material_layout],
            &[],
        );
        let classify_count = classify("classify_count");
        let classify_write = classify("classify_write");
        let classify_scan = kernel::pipeline(
            device,
            &module,
            "classify_scan",
            &[&layout, &dispatch_layout],
            &[],
        );
        let depth_layout = Layout::numbered(
            device,
            "visibility depth",
            wgpu::ShaderStages::FRAGMENT,
            &[(0, Binding::Uniform), (2, Binding::StorageRead)],
        );
        let depth = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("visibility depth"),
            layout: Some(&kernel::pipeline_layout(
                device,
                "visibility depth",
                &[&depth_layout],
            )),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_depth_fullscreen"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: Default::default(),
            depth_stencil: Some(wgpu::DepthStencilState {
                format: crate::DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Always),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_depth"),
                compilation_options: Default::default(),
                targets: &[],
            }),
            multiview_mask: None,
            cache: None,
        });
        let bindless =
            path == ResolvePath::OneDispatch && device.features().contains(BINDLESS_FEATURES);
        Ok(Self {
            layout,
            dispatch_layout,
            material,
            classify_count,
            classify_scan,
            classify_write,
            depth_layout,
            depth,
            bindless,
            one_dispatch_kernel: Mutex::new(None),
        })
    }

    /// The one-dispatch resolve's kernel and its group 1 for `uploaded`'s materials, where
    /// the device's binding arrays hold every texture of the scene.
    fn bind_one_dispatch(
        &self,
        device: &wgpu::Device,
        uploaded: &GpuScene,
    ) -> Result<Option<(wgpu::ComputePipeline, wgpu::BindGroup)>, GBufferError> {
        if !self.bindless {
            return Ok(None);
        }
        let textures = uploaded.textures.all();
        let limits = device.limits();
        let count = u32::try_from(textures.len()).unwrap_or(u32::MAX);
        let Some(n) = std::num::NonZeroU32::new(count).filter(|_| {
            count <= limits.max_binding_array_elements_per_shader_stage
                && count <= limits.max_binding_array_sampler_elements_per_shader_stage
        }) else {
            return Ok(None);
        };
        let mut cached = self
            .one_dispatch_kernel
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner());
        let (pipeline, layout) = match &*cached {
            Some((built, pipeline, layout)) if *built == count => {
                (pipeline.clone(), layout.clone())
            }
            _ => {
                let module = crate::SHADERS.module_with(
                    device,
                    "resolve_bindless.wgsl",
                    &Specialisation::default().set("MATERIAL_TEXTURES", format!("{count}u")),
                )?;
                let layout = Layout::compute_numbered(
                    device,
                    "visibility resolve materials",
                    &[
                        (12, Binding::StorageRead),
                        (14, Binding::Textures(n)),
                        (15, Binding::Samplers(n)),
                    ],
                );
                let pipeline = kernel::pipeline(
                    device,
                    &module,
                    "resolve_bindless",
                    &[&self.layout, &layout],
                    &[],
                );
                *cached = Some((count, pipeline.clone(), layout.clone()));
                (pipeline, layout)
            }
        };
        let views: Vec<&wgpu::TextureView> = textures.iter().map(|t| &t.view).collect();
        let samplers: Vec<&wgpu::Sampler> = textures.iter().map(|t| &t.sampler).collect();
        let group = layout.bind(
            device,
            &[
                uploaded.material_table.as_entire_binding(),
                wgpu::BindingResource::TextureViewArray(&views),
                wgpu::BindingResource::SamplerArray(&samplers),
            ],
        );
        Ok(Some((pipeline, group)))
    }

    /// Records the pass writing `depth` (the G-buffer's [`crate::DEPTH_FORMAT`] target, of the
    /// visibility buffer's size) from the visibility buffer `resolve` was bound to: z/w where
    /// a triangle is, 1 elsewhere, for the passes that test against the hardware depth.
    pub fn encode_depth(
        &self,
        resolve: &Resolve,
        encoder: &mut wgpu::CommandEncoder,
        depth: &wgpu::Texture,
        timestamps: Option<wgpu::RenderPassTimestampWrites<'_>>,
    ) {
        let view = depth.create_view(&Default::default());
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("visibility depth"),
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: timestamps,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.depth);
        pass.set_bind_group(0, &resolve.depth_group, &[]);
        pass.draw(0..3, 0..1);
    }

    /// The passes resolving the visibility buffer `visibility`'s passes write (for the same
    /// `uploaded` scene and `frame`, a [`Frame`](crate::Frame) uniform) into `targets` (of its
    /// size).
    pub fn bind(
        &self,
        device: &wgpu::Device,
        uploaded: &GpuScene,
        frame: &wgpu::Buffer,
        visibility: &Visibility,
        targets: &super::GBufferTargets,
    ) -> Result<Resolve, GBufferError> {
        let (width, height) = (targets.width, targets.height);
        if visibility.size != (width, height) {
            return Err(GBufferError::InvalidOptions(format!(
                "G-buffer targets of {width}×{height} for a visibility buffer of {}×{}",
                visibility.size.0, visibility.size.1
            )));
        }
        let slots = visibility.materials.len() as u32;
        let tiles_x = width.div_ceil(RESOLVE_TILE);
        let tile_count = u64::from(tiles_x) * u64::from(height.div_ceil(RESOLVE_TILE));
        let one_dispatch = self.bind_one_dispatch(device, uploaded)?;
        // A tile holds at most one entry per slot, and at most 64 slots (one per pixel); the
        // one dispatch lists no tiles.
        let entries = match one_dispatch {
            Some(_) => 1,
            None => tile_count * u64::from(slots.clamp(1, RESOLVE_TILE * RESOLVE_TILE)),
        };
        let storage = wgpu::BufferUsages::STORAGE;
        let classes = transfer::buffer(
            device,
            "visibility resolve classes",
            u64::from(slots.max(1)) * 12,
            storage,
        )?;
        let tiles = transfer::buffer(device, "visibility resolve tiles", entries * 4, storage)?;
        let dispatch = transfer::buffer(
            device,
            "visibility resolve dispatch",
            u64::from(slots.max(1)) * 12,
            storage | wgpu::BufferUsages::INDIRECT,
        )?;
        let views = [
            &targets.linear_depth,
            &targets.normal,
            &targets.albedo,
            &targets.material,
            &targets.emission,
        ]
        .map(|t| t.create_view(&Default::default()));
        let group = |slot: u32| -> Result<wgpu::BindGroup, GBufferError> {
            let uniform = transfer::buffer_init(
                device,
                "visibility resolve",
                bytemuck::bytes_of(&ResolveUniform {
                    slot,
                    slots,
                    tiles_x,
                    _pad: 0,
                }),
                wgpu::BufferUsages::UNIFORM,
            )?;
            let mut resources = vec![
                frame.as_entire_binding(),
                visibility.meshes.as_entire_binding(),
                visibility.buffer.as_entire_binding(),
                uniform.as_entire_binding(),
                uploaded.positions.as_entire_binding(),
                uploaded.attributes.as_entire_binding(),
                uploaded.indices.as_entire_binding(),
            ];
            resources.extend(views.iter().map(wgpu::BindingResource::TextureView));
            resources.extend([classes.as_entire_binding(), tiles.as_entire_binding()]);
            Ok(self.layout.bind(device, &resources))
        };
        let first = group(0)?;
        let covering = Workgroups::covering(width, height, RESOLVE_TILE);
        let depth_group = self.depth_layout.bind(
            device,
            &[
                frame.as_entire_binding(),
                visibility.buffer.as_entire_binding(),
            ],
        );
        if let Some((pipeline, materials)) = one_dispatch {
            let one = Dispatch {
                pipeline,
                groups: vec![first, materials],
                workgroups: covering,
            };
            return Ok(Resolve {
                passes: Passes::new().pass("visibility resolve", vec![one]),
                path: ResolvePath::OneDispatch,
                depth_group,
            });
        }
        let on_first = |pipeline: &wgpu::ComputePipeline, groups, workgroups| Dispatch {
            pipeline: pipeline.clone(),
            groups,
            workgroups,
        };
        let mut dispatches = vec![
            on_first(&self.classify_count, vec![first.clone()], covering.clone()),
            on_first(
                &self.classify_scan,
                vec![
                    first.clone(),
                    self.dispatch_layout.bind_buffers(device, &[&dispatch]),
                ],
                Workgroups::Direct([1, 1, 1]),
            ),
            on_first(&self.classify_write, vec![first.clone()], covering),
        ];
        for (slot, &m) in visibility.materials.iter().enumerate() {
            let bound = if slot == 0 {
                first.clone()
            } else {
                group(slot as u32)?
            };
            dispatches.push(Dispatch {
                pipeline: self.material.clone(),
                groups: vec![bound, uploaded.material_groups[m].clone()],
                workgroups: Workgroups::Indirect(dispatch.clone(), slot as u64 * 12),
            });
        }
        Ok(Resolve {
            passes: Passes::new().pass("visibility resolve", dispatches),
            path: ResolvePath::Classified,
            depth_group,
        })
    }
}
