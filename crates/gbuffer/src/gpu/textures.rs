//! The scene's textures on the GPU for the G-buffer: one texture per scene texture and colour
//! space a material reads it in (`Rgba8UnormSrgb` for base colour and emissive, `Rgba8Unorm`
//! for the rest), with full mip chains drawn on the GPU at load (`shaders/gbuffer/mips.wgsl`)
//! and a sampler per texture from its glTF sampler, anisotropic where it filters linearly.
//! The CPU twin is [`scene::SceneTextures`] built with mip maps.

use ::gpu::kernel::{Binding, Layout};
use ::gpu::{GpuError, transfer};
use ::scene::{ColorSpace, Scene, Wrap};

use crate::TextureOptions;

/// One uploaded texture: its view (all mips) and sampler.
pub struct GpuTexture {
    /// The texture (all mip levels).
    pub texture: wgpu::Texture,
    /// A view of every level.
    pub view: wgpu::TextureView,
    /// The texture's sampler.
    pub sampler: wgpu::Sampler,
    /// What the sampler was made from (the glTF sampler).
    pub sampling: ::scene::Sampler,
}

/// Every texture some material reads, per colour space, plus a white 1 × 1 for absent ones:
/// the one texture store of a scene. Passes that must reach every texture from one binding
/// (the supersampled G-buffer's shading, Holländer 2013 §4.3.3) take a resampled array of it
/// ([`MaterialTextures::array`]).
pub struct MaterialTextures {
    srgb: Vec<Option<GpuTexture>>,
    linear: Vec<Option<GpuTexture>>,
    white: GpuTexture,
    mips: Mips,
}

/// The texture format of `space`.
pub fn format_of(space: ColorSpace) -> wgpu::TextureFormat {
    match space {
        ColorSpace::Srgb => wgpu::TextureFormat::Rgba8UnormSrgb,
        ColorSpace::Linear => wgpu::TextureFormat::Rgba8Unorm,
    }
}

impl MaterialTextures {
    /// Uploads the textures `scene`'s materials read and draws their mip chains (one command
    /// buffer, submitted here). A texture larger than the device's limit is an error naming it.
    pub fn upload(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: &Scene,
        options: &TextureOptions,
    ) -> Result<Self, GpuError> {
        let used = ::scene::texture_spaces(scene);
        let mips = Mips::new(device)?;
        let mut encoder = device.create_command_encoder(&Default::default());
        let mut upload =
            |space: ColorSpace, k: usize| -> Result<Vec<Option<GpuTexture>>, GpuError> {
                scene
                    .textures
                    .iter()
                    .zip(&used)
                    .map(|(t, u)| {
                        u[k].then(|| {
                            upload_texture(device, queue, &mips, &mut encoder, t, space, options)
                        })
                        .transpose()
                    })
                    .collect()
            };
        let srgb = upload(ColorSpace::Srgb, 0)?;
        let linear = upload(ColorSpace::Linear, 1)?;
        let white = ::scene::Texture {
            name: "white".into(),
            width: 1,
            height: 1,
            rgba8: vec![255; 4],
            sampler: Default::default(),
        };
        let white = upload_texture(
            device,
            queue,
            &mips,
            &mut encoder,
            &white,
            ColorSpace::Linear,
            options,
        )?;
        queue.submit([encoder.finish()]);
        Ok(Self {
            srgb,
            linear,
            white,
            mips,
        })
    }

    /// The store's textures as one `size × size` 2D array in `space`'s format with a full
    /// mip chain, drawn on the GPU: layer `i` is texture `layers[i]` read in `space`, resampled
    /// at level 0 with its own sampler (`fs_resample`), or white where `layers[i]` is `None`
    /// or no material reads that texture in `space`; the levels above are 2 × 2 box filters.
    /// The CPU twin resamples [`scene::LinearTexture::sample`] the same way.
    pub fn array(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        layers: &[Option<u32>],
        space: ColorSpace,
        size: u32,
    ) -> Result<wgpu::Texture, GpuError> {
        transfer::check_texture_size(device, "texture array", size, size)?;
        let limit = device.limits().max_texture_array_layers;
        if layers.is_empty() || layers.len() as u64 > u64::from(limit) {
            return Err(GpuError::DataSize(format!(
                "a texture array of {} layers (the device allows 1..={limit})",
                layers.len()
            )));
        }
        let texture = transfer::allocation(device, "texture array", || {
            Ok::<_, GpuError>(device.create_texture(&wgpu::TextureDescriptor {
                label: Some("texture array"),
                size: wgpu::Extent3d {
                    width: size,
                    height: size,
                    depth_or_array_layers: layers.len() as u32,
                },
                mip_level_count: size.max(1).ilog2() + 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: format_of(space),
                usage: wgpu::TextureUsages::TEXTURE_BINDING
                    | wgpu::TextureUsages::RENDER_ATTACHMENT
                    | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            }))
        })?;
        let mut encoder = device.create_command_encoder(&Default::default());
        for (layer, t) in layers.iter().enumerate() {
            let source = t.and_then(|t| self.get(t, space)).unwrap_or(&self.white);
            // Level 0 through the texture's wrap modes and magnification filter, without the
            // anisotropy (some drivers let an anisotropic sampler pick another level).
            let s = &source.sampling;
            let level0 = device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("resample"),
                address_mode_u: address(s.wrap_u),
                address_mode_v: address(s.wrap_v),
                mag_filter: filter(s.mag_linear),
                min_filter: filter(s.mag_linear),
                ..Default::default()
            });
            let target = layer_view(&texture, 0, layer as u32);
            let pipeline = &self.mips.resample[space as usize];
            self.mips.draw(
                device,
                &mut encoder,
                pipeline,
                (&source.view, &level0),
                &target,
            );
            self.mips
                .encode(device, &mut encoder, &texture, space, layer as u32);
        }
        queue.submit([encoder.finish()]);
        Ok(texture)
    }

    /// Texture `texture` as uploaded for `space`, if some material reads it so.
    pub fn get(&self, texture: u32, space: ColorSpace) -> Option<&GpuTexture> {
        let list = match space {
            ColorSpace::Srgb => &self.srgb,
            ColorSpace::Linear => &self.linear,
        };
        list.get(texture as usize).and_then(Option::as_ref)
    }

    /// The texture a material's role binds: its own, or white.
    pub(super) fn for_role(&self, role: &str, t: Option<::scene::TextureRef>) -> &GpuTexture {
        t.and_then(|t| self.get(t.texture, ::scene::role_space(role)))
            .unwrap_or(&self.white)
    }

    /// Every texture of the store once: the sRGB ones, the linear ones, then white (the
    /// entries of a binding array; a material's textures are indexed in it by role).
    pub fn all(&self) -> Vec<&GpuTexture> {
        self.srgb
            .iter()
            .chain(&self.linear)
            .flatten()
            .chain(std::iter::once(&self.white))
            .collect()
    }

    /// The indices in [`MaterialTextures::all`] of the textures `material`'s roles bind.
    pub(super) fn indices_of(&self, material: &::scene::Material) -> [u32; 5] {
        let all = self.all();
        material.roles().map(|(role, t)| {
            let wanted = self.for_role(role, t);
            all.iter()
                .position(|&g| std::ptr::eq(g, wanted))
                .expect("for_role returns a texture of the store") as u32
        })
    }
}

fn address(wrap: Wrap) -> wgpu::AddressMode {
    match wrap {
        Wrap::Repeat => wgpu::AddressMode::Repeat,
        Wrap::MirroredRepeat => wgpu::AddressMode::MirrorRepeat,
        Wrap::ClampToEdge => wgpu::AddressMode::ClampToEdge,
    }
}

fn filter(linear: bool) -> wgpu::FilterMode {
    if linear {
        wgpu::FilterMode::Linear
    } else {
        wgpu::FilterMode::Nearest
    }
}

/// Uploads level 0 of `t`, records its mip chain into `encoder` and builds its sampler.
fn upload_texture(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    mips: &Mips,
    encoder: &mut wgpu::CommandEncoder,
    t: &::scene::Texture,
    space: ColorSpace,
    options: &TextureOptions,
) -> Result<GpuTexture, GpuError> {
    let what = format!("texture {:?}", t.name);
    transfer::check_texture_size(device, &what, t.width, t.height)?;
    let levels = t.width.max(t.height).ilog2() + 1;
    let format = format_of(space);
    let texture = transfer::allocation(device, &what, || {
        Ok::<_, GpuError>(device.create_texture(&wgpu::TextureDescriptor {
            label: Some(&t.name),
            size: wgpu::Extent3d {
                width: t.width,
                height: t.height,
                depth_or_array_layers: 1,
            },
            mip_level_count: levels,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::COPY_DST
                | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        }))
    })?;
    if t.rgba8.len() as u64 != u64::from(t.width) * u64::from(t.height) * 4 {
        return Err(GpuError::DataSize(format!(
            "{what}: {} bytes of texels, {}×{} RGBA8 needs {}",
            t.rgba8.len(),
            t.width,
            t.height,
            u64::from(t.width) * u64::from(t.height) * 4
        )));
    }
    transfer::write_level0(queue, &texture, &t.rgba8);
    mips.encode(device, encoder, &texture, space, 0);
    let s = &t.sampler;
    let trilinear = s.mag_linear && s.min_linear && s.mipmaps == Some(true);
    let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some(&t.name),
        address_mode_u: address(s.wrap_u),
        address_mode_v: address(s.wrap_v),
        mag_filter: filter(s.mag_linear),
        min_filter: filter(s.min_linear),
        mipmap_filter: if s.mipmaps == Some(true) {
            wgpu::MipmapFilterMode::Linear
        } else {
            wgpu::MipmapFilterMode::Nearest
        },
        // Without mip maps level 0 is read, minified with the minification filter: the
        // Vulkan specification's emulation (a clamp of 0.25 keeps λ > 0 minifying).
        lod_max_clamp: if s.mipmaps.is_some() { 32.0 } else { 0.25 },
        anisotropy_clamp: if trilinear {
            options.max_anisotropy.clamp(1, ::scene::MAX_ANISOTROPY) as u16
        } else {
            1
        },
        ..Default::default()
    });
    Ok(GpuTexture {
        view: texture.create_view(&Default::default()),
        texture,
        sampler,
        sampling: *s,
    })
}

/// A single-level, single-layer view of `texture`.
fn layer_view(texture: &wgpu::Texture, level: u32, layer: u32) -> wgpu::TextureView {
    texture.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2),
        base_mip_level: level,
        mip_level_count: Some(1),
        base_array_layer: layer,
        array_layer_count: Some(1),
        ..Default::default()
    })
}

/// The passes of `mips.wgsl`: a downsampling and a resampling pipeline per colour space
/// (indexed by `ColorSpace as usize`).
struct Mips {
    layout: Layout,
    downsample: [wgpu::RenderPipeline; 2],
    resample: [wgpu::RenderPipeline; 2],
    edge: wgpu::Sampler,
}

impl Mips {
    fn new(device: &wgpu::Device) -> Result<Self, GpuError> {
        let module = crate::SHADERS.module(device, "mips.wgsl")?;
        let layout = Layout::new(
            device,
            "mips",
            wgpu::ShaderStages::FRAGMENT,
            &[Binding::Texture, Binding::Sampler],
        );
        let pipeline_layout = ::gpu::kernel::pipeline_layout(device, "mips", &[&layout]);
        let pipeline = |(vertex, fragment), space| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(fragment),
                layout: Some(&pipeline_layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some(vertex),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                primitive: Default::default(),
                depth_stencil: None,
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some(fragment),
                    compilation_options: Default::default(),
                    targets: &[Some(format_of(space).into())],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let spaces = |stages| [ColorSpace::Srgb, ColorSpace::Linear].map(|s| pipeline(stages, s));
        let edge = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("mips"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        Ok(Self {
            downsample: spaces(("vs_fullscreen", "fs_downsample")),
            resample: spaces(("vs_resample", "fs_resample")),
            layout,
            edge,
        })
    }

    /// Draws `source` (a view and the sampler it is read with) into `target` with `pipeline`.
    fn draw(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        pipeline: &wgpu::RenderPipeline,
        (source, sampler): (&wgpu::TextureView, &wgpu::Sampler),
        target: &wgpu::TextureView,
    ) {
        let group = self.layout.bind(
            device,
            &[
                wgpu::BindingResource::TextureView(source),
                wgpu::BindingResource::Sampler(sampler),
            ],
        );
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("mips"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: target,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.draw(0..3, 0..1);
    }

    /// Draws levels 1.. of layer `layer` of `texture` from its level 0, each from the one
    /// before.
    fn encode(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        texture: &wgpu::Texture,
        space: ColorSpace,
        layer: u32,
    ) {
        for level in 1..texture.mip_level_count() {
            let source = layer_view(texture, level - 1, layer);
            let target = layer_view(texture, level, layer);
            let pipeline = &self.downsample[space as usize];
            self.draw(device, encoder, pipeline, (&source, &self.edge), &target);
        }
    }
}
