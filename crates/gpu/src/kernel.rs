//! The kernel vocabulary every crate uses: explicit bind-group layouts written as a sequential
//! list of binding kinds, compute pipelines on those layouts, bind groups checked against
//! them, and [`Passes`] — recorded dispatches (direct or indirect, optionally timed).
//!
//! A kernel has three phases: `new(device, config)` builds its [`Layout`]s and pipelines once;
//! `bind(device, inputs, outputs)` makes bind groups over the caller's resources and returns
//! a bound set (bad inputs are an `Err` there); `encode(&bound, encoder, timer)` only records.
//!
//! ```no_run
//! use gpu::kernel::{Binding, Layout, Passes, Workgroups};
//! # let gpu = gpu::Gpu::from_env()?;
//! # let module: gpu::wgpu::ShaderModule = todo!();
//! # let (params, data): (gpu::wgpu::Buffer, gpu::wgpu::Buffer) = todo!();
//! let layout = Layout::compute(&gpu.device, "scale", &[Binding::Uniform, Binding::Storage]);
//! let pipeline = gpu::kernel::pipeline(&gpu.device, &module, "scale", &[&layout], &[]);
//! let group = layout.bind(&gpu.device, &[params.as_entire_binding(), data.as_entire_binding()]);
//! let passes = Passes::one("scale", &pipeline, vec![group], Workgroups::Direct([64, 1, 1]));
//! let mut encoder = gpu.device.create_command_encoder(&Default::default());
//! passes.encode(&mut encoder, None);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use crate::{GpuError, PassTimer};

/// One binding of a layout; bindings are numbered 0, 1, … in list order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Binding {
    /// `var<uniform>` buffer.
    Uniform,
    /// `var<storage, read_write>` buffer.
    Storage,
    /// `var<storage, read>` buffer.
    StorageRead,
    /// `texture_2d<f32>`, filterable.
    Texture,
    /// `texture_2d<f32>` read with `textureLoad` only (e.g. `Rgba32Float` without filtering).
    TextureUnfilterable,
    /// `texture_2d<u32>`.
    TextureUint,
    /// `texture_2d<i32>`.
    TextureSint,
    /// `texture_depth_2d`.
    TextureDepth,
    /// `texture_2d_array<f32>`, filterable.
    TextureArray,
    /// `texture_depth_2d_array`.
    TextureDepthArray,
    /// `texture_storage_2d<format, write>`.
    StorageTexture(wgpu::TextureFormat),
    /// `texture_storage_2d<format, read_write>`.
    StorageTextureReadWrite(wgpu::TextureFormat),
    /// `sampler` (filtering).
    Sampler,
    /// `sampler` (non-filtering).
    SamplerNonFiltering,
    /// `binding_array<texture_2d<f32>>` of this many filterable textures (needs
    /// `wgpu::Features::TEXTURE_BINDING_ARRAY`).
    Textures(std::num::NonZeroU32),
    /// `binding_array<sampler>` of this many filtering samplers (as [`Binding::Textures`]).
    Samplers(std::num::NonZeroU32),
}

impl Binding {
    /// A 2D texture of `sample_type` (what a format's texels read as in WGSL).
    pub fn texture_of(sample_type: wgpu::TextureSampleType) -> Self {
        use wgpu::TextureSampleType as S;
        match sample_type {
            S::Float { filterable: true } => Self::Texture,
            S::Float { filterable: false } => Self::TextureUnfilterable,
            S::Uint => Self::TextureUint,
            S::Sint => Self::TextureSint,
            S::Depth => Self::TextureDepth,
        }
    }

    fn ty(self) -> wgpu::BindingType {
        use wgpu::{BindingType as T, TextureSampleType as S};
        let buffer = |ty| T::Buffer {
            ty,
            has_dynamic_offset: false,
            min_binding_size: None,
        };
        let texture = |sample_type, view_dimension| T::Texture {
            sample_type,
            view_dimension,
            multisampled: false,
        };
        let storage = |format, access| T::StorageTexture {
            access,
            format,
            view_dimension: wgpu::TextureViewDimension::D2,
        };
        let d2 = wgpu::TextureViewDimension::D2;
        match self {
            Self::Uniform => buffer(wgpu::BufferBindingType::Uniform),
            Self::Storage => buffer(wgpu::BufferBindingType::Storage { read_only: false }),
            Self::StorageRead => buffer(wgpu::BufferBindingType::Storage { read_only: true }),
            Self::Texture | Self::Textures(_) => texture(S::Float { filterable: true }, d2),
            Self::TextureUnfilterable => texture(S::Float { filterable: false }, d2),
            Self::TextureUint => texture(S::Uint, d2),
            Self::TextureSint => texture(S::Sint, d2),
            Self::TextureDepth => texture(S::Depth, d2),
            Self::TextureArray => texture(
                S::Float { filterable: true },
                wgpu::TextureViewDimension::D2Array,
            ),
            Self::TextureDepthArray => texture(S::Depth, wgpu::TextureViewDimension::D2Array),
            Self::StorageTexture(f) => storage(f, wgpu::StorageTextureAccess::WriteOnly),
            Self::StorageTextureReadWrite(f) => storage(f, wgpu::StorageTextureAccess::ReadWrite),
            Self::Sampler | Self::Samplers(_) => T::Sampler(wgpu::SamplerBindingType::Filtering),
            Self::SamplerNonFiltering => T::Sampler(wgpu::SamplerBindingType::NonFiltering),
        }
    }

    /// The elements of a binding array; `None` for a single resource.
    fn count(self) -> Option<std::num::NonZeroU32> {
        match self {
            Self::Textures(n) | Self::Samplers(n) => Some(n),
            _ => None,
        }
    }
}

/// An explicit bind-group layout and the (numbered) binding kinds it was made from.
#[derive(Clone, Debug)]
pub struct Layout {
    layout: wgpu::BindGroupLayout,
    bindings: Vec<(u32, Binding)>,
    label: String,
}

impl Layout {
    /// A layout visible to compute shaders with `bindings` at 0, 1, ….
    pub fn compute(device: &wgpu::Device, label: &str, bindings: &[Binding]) -> Self {
        Self::new(device, label, wgpu::ShaderStages::COMPUTE, bindings)
    }

    /// A layout visible to `stages` with `bindings` at 0, 1, ….
    pub fn new(
        device: &wgpu::Device,
        label: &str,
        stages: wgpu::ShaderStages,
        bindings: &[Binding],
    ) -> Self {
        let numbered: Vec<(u32, Binding)> = bindings
            .iter()
            .enumerate()
            .map(|(i, b)| (i as u32, *b))
            .collect();
        Self::numbered(device, label, stages, &numbered)
    }

    /// A compute layout of the bindings one entry point of a shader uses when it shares its
    /// module's binding numbers with other entry points (e.g. `[(2, Uniform), (8, Storage)]`).
    pub fn compute_numbered(
        device: &wgpu::Device,
        label: &str,
        bindings: &[(u32, Binding)],
    ) -> Self {
        Self::numbered(device, label, wgpu::ShaderStages::COMPUTE, bindings)
    }

    /// A layout visible to `stages` of the numbered `bindings` (as [`Layout::compute_numbered`]
    /// for other stages).
    pub fn numbered(
        device: &wgpu::Device,
        label: &str,
        stages: wgpu::ShaderStages,
        bindings: &[(u32, Binding)],
    ) -> Self {
        let staged: Vec<_> = bindings.iter().map(|&(n, b)| (n, stages, b)).collect();
        Self::staged(device, label, &staged)
    }

    /// A layout of numbered bindings each visible to its own stages (e.g. a buffer the
    /// vertex stage reads beside one only the fragment stage may write).
    pub fn staged(
        device: &wgpu::Device,
        label: &str,
        bindings: &[(u32, wgpu::ShaderStages, Binding)],
    ) -> Self {
        let entries: Vec<_> = bindings
            .iter()
            .map(|&(binding, visibility, b)| wgpu::BindGroupLayoutEntry {
                binding,
                visibility,
                ty: b.ty(),
                count: b.count(),
            })
            .collect();
        Self {
            layout: device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some(label),
                entries: &entries,
            }),
            bindings: bindings.iter().map(|&(n, _, b)| (n, b)).collect(),
            label: label.to_owned(),
        }
    }

    /// The wgpu layout.
    pub fn raw(&self) -> &wgpu::BindGroupLayout {
        &self.layout
    }

    /// The binding numbers and kinds, in order.
    pub fn bindings(&self) -> &[(u32, Binding)] {
        &self.bindings
    }

    /// A bind group with `resources` at the layout's bindings, in order (one per binding).
    pub fn bind(
        &self,
        device: &wgpu::Device,
        resources: &[wgpu::BindingResource<'_>],
    ) -> wgpu::BindGroup {
        debug_assert_eq!(
            resources.len(),
            self.bindings.len(),
            "{}: one resource per binding",
            self.label
        );
        let entries: Vec<_> = resources
            .iter()
            .zip(&self.bindings)
            .map(|(r, &(binding, _))| wgpu::BindGroupEntry {
                binding,
                resource: r.clone(),
            })
            .collect();
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(&self.label),
            layout: &self.layout,
            entries: &entries,
        })
    }

    /// A bind group of whole buffers at the layout's bindings, in order.
    pub fn bind_buffers(
        &self,
        device: &wgpu::Device,
        buffers: &[&wgpu::Buffer],
    ) -> wgpu::BindGroup {
        let resources: Vec<_> = buffers.iter().map(|b| b.as_entire_binding()).collect();
        self.bind(device, &resources)
    }
}

/// A pipeline layout over `layouts` (groups 0, 1, …).
pub fn pipeline_layout(
    device: &wgpu::Device,
    label: &str,
    layouts: &[&Layout],
) -> wgpu::PipelineLayout {
    let raw: Vec<Option<&wgpu::BindGroupLayout>> = layouts.iter().map(|l| Some(l.raw())).collect();
    device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts: &raw,
        immediate_size: 0,
    })
}

/// A compute pipeline for `entry` of `module` over the explicit `layouts`, with the given
/// values of the shader's `override` constants.
pub fn pipeline(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    entry: &str,
    layouts: &[&Layout],
    constants: &[(&str, f64)],
) -> wgpu::ComputePipeline {
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(entry),
        layout: Some(&pipeline_layout(device, entry, layouts)),
        module,
        entry_point: Some(entry),
        compilation_options: wgpu::PipelineCompilationOptions {
            constants,
            ..Default::default()
        },
        cache: None,
    })
}

/// A compute pipeline with the one explicit bind-group layout it was built on.
#[derive(Clone, Debug)]
pub struct Kernel {
    /// The pipeline.
    pub pipeline: wgpu::ComputePipeline,
    /// Its group-0 layout.
    pub layout: Layout,
}

impl Kernel {
    /// `entry` of `module` with `bindings` at 0, 1, … of group 0.
    pub fn new(
        device: &wgpu::Device,
        module: &wgpu::ShaderModule,
        entry: &str,
        bindings: &[Binding],
        constants: &[(&str, f64)],
    ) -> Self {
        Self::with_layout(
            device,
            module,
            entry,
            Layout::compute(device, entry, bindings),
            constants,
        )
    }

    /// `entry` of `module` with the numbered `bindings` of group 0 it uses.
    pub fn numbered(
        device: &wgpu::Device,
        module: &wgpu::ShaderModule,
        entry: &str,
        bindings: &[(u32, Binding)],
    ) -> Self {
        let layout = Layout::compute_numbered(device, entry, bindings);
        Self::with_layout(device, module, entry, layout, &[])
    }

    fn with_layout(
        device: &wgpu::Device,
        module: &wgpu::ShaderModule,
        entry: &str,
        layout: Layout,
        constants: &[(&str, f64)],
    ) -> Self {
        Self {
            pipeline: pipeline(device, module, entry, &[&layout], constants),
            layout,
        }
    }

    /// A bind group of whole buffers for this kernel's layout.
    pub fn bind_buffers(
        &self,
        device: &wgpu::Device,
        buffers: &[&wgpu::Buffer],
    ) -> wgpu::BindGroup {
        self.layout.bind_buffers(device, buffers)
    }

    /// A bind group of `resources` for this kernel's layout.
    pub fn bind(
        &self,
        device: &wgpu::Device,
        resources: &[wgpu::BindingResource<'_>],
    ) -> wgpu::BindGroup {
        self.layout.bind(device, resources)
    }

    /// A dispatch of this kernel with `group` over `workgroups`.
    pub fn dispatch(&self, group: &wgpu::BindGroup, workgroups: Workgroups) -> Dispatch {
        Dispatch {
            pipeline: self.pipeline.clone(),
            groups: vec![group.clone()],
            workgroups,
        }
    }
}

/// How many workgroups a dispatch runs.
#[derive(Clone, Debug)]
pub enum Workgroups {
    /// A fixed count.
    Direct([u32; 3]),
    /// Read by the GPU from `DispatchIndirectArgs` in a buffer at a byte offset.
    Indirect(wgpu::Buffer, u64),
}

impl Workgroups {
    /// Enough `size`-wide square workgroups to cover `width × height`.
    pub fn covering(width: u32, height: u32, size: u32) -> Self {
        Self::Direct([width.div_ceil(size), height.div_ceil(size), 1])
    }

    /// Enough `size`-wide workgroups for `n` threads, in rows of at most 32 768 (under
    /// `Limits::default().max_compute_workgroups_per_dimension`): thread
    /// `gid.x + gid.y · num_workgroups.x · size` (the kernel skips those ≥ `n`).
    pub fn linear(n: u32, size: u32) -> Self {
        const ROW: u32 = 32_768;
        let g = n.div_ceil(size).max(1);
        Self::Direct([g.min(ROW), g.div_ceil(ROW), 1])
    }
}

/// One dispatch: a pipeline, its bind groups (groups 0, 1, …) and its workgroups.
#[derive(Clone, Debug)]
pub struct Dispatch {
    /// The pipeline.
    pub pipeline: wgpu::ComputePipeline,
    /// Bind groups in group order.
    pub groups: Vec<wgpu::BindGroup>,
    /// Workgroup count.
    pub workgroups: Workgroups,
}

/// One compute pass: dispatches recorded in order, timed as a whole under `name`.
#[derive(Clone, Debug)]
struct Pass {
    name: String,
    dispatches: Vec<Dispatch>,
}

/// Compute passes ready to record into any encoder, any number of times.
#[derive(Clone, Debug, Default)]
pub struct Passes(Vec<Pass>);

impl Passes {
    /// No passes.
    pub fn new() -> Self {
        Self::default()
    }

    /// A pass of one dispatch.
    pub fn one(
        name: &str,
        pipeline: &wgpu::ComputePipeline,
        groups: Vec<wgpu::BindGroup>,
        workgroups: Workgroups,
    ) -> Self {
        Self::new().pass(
            name,
            vec![Dispatch {
                pipeline: pipeline.clone(),
                groups,
                workgroups,
            }],
        )
    }

    /// These passes followed by a pass named `name` recording `dispatches` in order.
    pub fn pass(mut self, name: &str, dispatches: Vec<Dispatch>) -> Self {
        self.0.push(Pass {
            name: name.to_owned(),
            dispatches,
        });
        self
    }

    /// These passes followed by `other`.
    pub fn then(mut self, other: Passes) -> Self {
        self.0.extend(other.0);
        self
    }

    /// The same passes, all timed under `name` (a stage of a larger pipeline).
    pub fn named(mut self, name: &str) -> Self {
        for p in &mut self.0 {
            p.name = name.to_owned();
        }
        self
    }

    /// The same dispatches, each in a pass of its own named `name(i)` for the i-th dispatch
    /// (counted across passes): a profile of a stage's dispatches (passes of one name are
    /// summed by [`PassTimer`]'s readers that group by name).
    pub fn per_dispatch(&self, mut name: impl FnMut(usize) -> String) -> Self {
        let dispatches = self.0.iter().flat_map(|p| p.dispatches.iter().cloned());
        Self(
            dispatches
                .enumerate()
                .map(|(i, d)| Pass {
                    name: name(i),
                    dispatches: vec![d],
                })
                .collect(),
        )
    }

    /// The pass names, in order.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.0.iter().map(|p| p.name.as_str())
    }

    /// Records every pass; with a timer, each is timed under its name.
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&PassTimer>) {
        for pass in &self.0 {
            let mut cp = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(&pass.name),
                timestamp_writes: timer.and_then(|t| t.compute_pass(&pass.name)),
            });
            for d in &pass.dispatches {
                cp.set_pipeline(&d.pipeline);
                for (i, g) in d.groups.iter().enumerate() {
                    cp.set_bind_group(i as u32, g, &[]);
                }
                match &d.workgroups {
                    Workgroups::Direct([x, y, z]) => cp.dispatch_workgroups(*x, *y, *z),
                    Workgroups::Indirect(buffer, offset) => {
                        cp.dispatch_workgroups_indirect(buffer, *offset)
                    }
                }
            }
        }
    }
}

/// Fails with [`GpuError::Resource`] unless `texture` is `size`, of `format` and has `usage`:
/// what a kernel's `bind` checks of each texture it is given.
pub fn check_texture(
    what: &str,
    texture: &wgpu::Texture,
    size: (u32, u32),
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> Result<(), GpuError> {
    let problem = if (texture.width(), texture.height()) != size {
        format!(
            "is {}×{}, {}×{} expected",
            texture.width(),
            texture.height(),
            size.0,
            size.1
        )
    } else if texture.format() != format {
        format!("has format {:?}, {format:?} expected", texture.format())
    } else if !texture.usage().contains(usage) {
        format!("lacks usage {:?}", usage - texture.usage())
    } else {
        return Ok(());
    };
    Err(GpuError::Resource {
        what: what.to_owned(),
        problem,
    })
}

/// Fails with [`GpuError::Resource`] unless `buffer` holds at least `min_size` bytes and has
/// `usage`: what a kernel's `bind` checks of each buffer it is given.
pub fn check_buffer(
    what: &str,
    buffer: &wgpu::Buffer,
    min_size: u64,
    usage: wgpu::BufferUsages,
) -> Result<(), GpuError> {
    let problem = if buffer.size() < min_size {
        format!("holds {} bytes, {min_size} needed", buffer.size())
    } else if !buffer.usage().contains(usage) {
        format!("lacks usage {:?}", usage - buffer.usage())
    } else {
        return Ok(());
    };
    Err(GpuError::Resource {
        what: what.to_owned(),
        problem,
    })
}
