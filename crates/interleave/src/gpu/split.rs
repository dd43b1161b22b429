//! Split and gather (Segovia 2006 §3, §5.1): `one_pass.wgsl`, `two_pass.wgsl` and
//! `tiled.wgsl` over the texel declarations of `texel.wgsl`, for any splittable format.

use ::gpu::kernel::{self, Binding, Layout};
use ::gpu::shader::Specialisation;
use ::gpu::{transfer, wgpu};

use super::{Passes, READ, USAGE, WRITE, compute_kernel, groups, pass, view};
use crate::cpu::BlockGeometry;
use crate::{InterleaveError, Pattern, SplitLayout, SplitVariant};

/// WGSL storage format name and texel scalar type of a splittable format.
pub fn texel_format(
    format: wgpu::TextureFormat,
) -> Result<(&'static str, &'static str), InterleaveError> {
    use wgpu::TextureFormat as F;
    Ok(match format {
        F::R32Uint => ("r32uint", "u32"),
        F::Rg32Uint => ("rg32uint", "u32"),
        F::Rgba32Uint => ("rgba32uint", "u32"),
        F::Rgba16Uint => ("rgba16uint", "u32"),
        F::Rgba8Uint => ("rgba8uint", "u32"),
        F::R32Sint => ("r32sint", "i32"),
        F::Rg32Sint => ("rg32sint", "i32"),
        F::Rgba32Sint => ("rgba32sint", "i32"),
        F::Rgba16Sint => ("rgba16sint", "i32"),
        F::Rgba8Sint => ("rgba8sint", "i32"),
        F::R32Float => ("r32float", "f32"),
        F::Rg32Float => ("rg32float", "f32"),
        F::Rgba32Float => ("rgba32float", "f32"),
        F::Rgba16Float => ("rgba16float", "f32"),
        F::Rgba8Unorm => ("rgba8unorm", "f32"),
        other => return Err(InterleaveError::Format(other)),
    })
}

/// The specialisation of `texel.wgsl`'s `Texel`, `Source` and `Destination` declarations
/// for `format`, so one kernel moves any supported format bit for bit.
pub fn texel_specialisation(
    format: wgpu::TextureFormat,
) -> Result<Specialisation, InterleaveError> {
    let (storage, scalar) = texel_format(format)?;
    Ok(Specialisation::default()
        .set("Texel", format!("vec4<{scalar}>"))
        .set("Source", format!("texture_2d<{scalar}>"))
        .set(
            "Destination",
            format!("texture_storage_2d<{storage}, write>"),
        ))
}

/// The source texture's binding kind of a splittable format (read with `textureLoad` only).
fn texel_binding(format: wgpu::TextureFormat) -> Result<Binding, InterleaveError> {
    Ok(match texel_format(format)?.1 {
        "u32" => Binding::TextureUint,
        "i32" => Binding::TextureSint,
        _ => Binding::TextureUnfilterable,
    })
}

/// Every splittable format.
pub const SPLIT_FORMATS: [wgpu::TextureFormat; 15] = {
    use wgpu::TextureFormat as F;
    [
        F::R32Uint,
        F::Rg32Uint,
        F::Rgba32Uint,
        F::Rgba16Uint,
        F::Rgba8Uint,
        F::R32Sint,
        F::Rg32Sint,
        F::Rgba32Sint,
        F::Rgba16Sint,
        F::Rgba8Sint,
        F::R32Float,
        F::Rg32Float,
        F::Rgba32Float,
        F::Rgba16Float,
        F::Rgba8Unorm,
    ]
};

/// Each split/gather file for each format.
pub(super) fn shader_variants() -> Vec<(&'static str, Specialisation)> {
    ["one_pass.wgsl", "two_pass.wgsl", "tiled.wgsl"]
        .into_iter()
        .flat_map(|file| {
            SPLIT_FORMATS
                .iter()
                .filter_map(move |&f| texel_specialisation(f).ok().map(|s| (file, s)))
        })
        .collect()
}

/// Split and gather of one texture format for one [`SplitLayout`] and [`SplitVariant`].
pub struct Splitter {
    layout: SplitLayout,
    format: wgpu::TextureFormat,
    split_pipelines: Vec<(&'static str, (wgpu::ComputePipeline, Layout))>,
    gather_pipelines: Vec<(&'static str, (wgpu::ComputePipeline, Layout))>,
    /// Two-pass only: the block-split texture between the passes, and its geometry.
    intermediate: Option<(wgpu::Texture, BlockGeometry)>,
    tile: (u32, u32),
    variant: SplitVariant,
}

impl Splitter {
    /// Builds the pipelines (and the two-pass intermediate texture) for `format`.
    pub fn new(
        device: &wgpu::Device,
        layout: &SplitLayout,
        variant: SplitVariant,
        format: wgpu::TextureFormat,
    ) -> Result<Self, InterleaveError> {
        variant.validate(layout.pattern)?;
        transfer::check_texture_size(
            device,
            "split texture",
            layout.split_width(),
            layout.split_height(),
        )?;
        let Pattern { n, m } = layout.pattern;
        let (file, split_entries, gather_entries, (a, b)): (
            _,
            &[&'static str],
            &[&'static str],
            _,
        ) = match variant {
            SplitVariant::OnePass => (
                "one_pass.wgsl",
                &["split_one_pass"],
                &["gather_one_pass"],
                (1, 1),
            ),
            SplitVariant::TwoPass(block) => (
                "two_pass.wgsl",
                &["split_block_splitting", "split_block_translation"],
                &["gather_block_translation", "gather_block_gathering"],
                (block.p / n, block.q / m),
            ),
            SplitVariant::Tiled => (
                "tiled.wgsl",
                &["split_tiled"],
                &["gather_tiled"],
                crate::tile(layout.pattern)?,
            ),
        };
        let module = crate::SHADERS.module_with(device, file, &texel_specialisation(format)?)?;
        let bindings = [texel_binding(format)?, Binding::StorageTexture(format)];
        let constants = [
            ("width", f64::from(layout.width)),
            ("height", f64::from(layout.height)),
            ("n", f64::from(n)),
            ("m", f64::from(m)),
            ("sub_width", f64::from(layout.sub_width)),
            ("sub_height", f64::from(layout.sub_height)),
            ("a", f64::from(a)),
            ("b", f64::from(b)),
        ];
        let build = |entries: &[&'static str]| {
            entries
                .iter()
                .map(|e| {
                    (
                        *e,
                        compute_kernel(device, &module, e, &bindings, &constants),
                    )
                })
                .collect()
        };
        let intermediate = match variant {
            SplitVariant::TwoPass(block) => {
                let g = BlockGeometry::new(layout, block);
                let (w, h) = g.intermediate_size();
                transfer::check_texture_size(device, "block-split texture", w, h)?;
                Some((
                    transfer::texture_2d(device, "block-split texture", w, h, format, USAGE),
                    g,
                ))
            }
            _ => None,
        };
        Ok(Self {
            layout: *layout,
            format,
            split_pipelines: build(split_entries),
            gather_pipelines: build(gather_entries),
            intermediate,
            tile: (a, b),
            variant,
        })
    }

    /// The layout.
    pub fn layout(&self) -> &SplitLayout {
        &self.layout
    }

    /// A texture of the image's size and this splitter's format, usable by every kernel.
    pub fn image_texture(&self, device: &wgpu::Device, label: &str) -> wgpu::Texture {
        transfer::texture_2d(
            device,
            label,
            self.layout.width,
            self.layout.height,
            self.format,
            USAGE,
        )
    }

    /// A texture of the split size and this splitter's format.
    pub fn split_texture(&self, device: &wgpu::Device, label: &str) -> wgpu::Texture {
        let l = &self.layout;
        transfer::texture_2d(
            device,
            label,
            l.split_width(),
            l.split_height(),
            self.format,
            USAGE,
        )
    }

    fn split_size(&self) -> (u32, u32) {
        (self.layout.split_width(), self.layout.split_height())
    }

    fn image_size(&self) -> (u32, u32) {
        (self.layout.width, self.layout.height)
    }

    fn tiles(&self) -> (u32, u32) {
        (
            self.layout.sub_width.div_ceil(self.tile.0),
            self.layout.sub_height.div_ceil(self.tile.1),
        )
    }

    /// Passes that split `image` into `split`.
    pub fn split(
        &self,
        device: &wgpu::Device,
        image: &wgpu::Texture,
        split: &wgpu::Texture,
    ) -> Result<Passes, InterleaveError> {
        kernel::check_texture("image", image, self.image_size(), self.format, READ)?;
        kernel::check_texture(
            "split texture",
            split,
            self.split_size(),
            self.format,
            WRITE,
        )?;
        self.passes(
            device,
            &self.split_pipelines,
            (image, split),
            self.split_size(),
        )
    }

    /// Passes that gather `split` back into `image`.
    pub fn gather(
        &self,
        device: &wgpu::Device,
        split: &wgpu::Texture,
        image: &wgpu::Texture,
    ) -> Result<Passes, InterleaveError> {
        kernel::check_texture("split texture", split, self.split_size(), self.format, READ)?;
        kernel::check_texture("image", image, self.image_size(), self.format, WRITE)?;
        self.passes(
            device,
            &self.gather_pipelines,
            (split, image),
            self.image_size(),
        )
    }

    /// The passes from `textures.0` to `textures.1`, whose size is `to_size`.
    fn passes(
        &self,
        device: &wgpu::Device,
        pipelines: &[(&'static str, (wgpu::ComputePipeline, Layout))],
        (from, to): (&wgpu::Texture, &wgpu::Texture),
        to_size: (u32, u32),
    ) -> Result<Passes, InterleaveError> {
        let res = wgpu::BindingResource::TextureView;
        let (from_view, to_view) = (view(from), view(to));
        let passes = match (self.variant, &self.intermediate, pipelines) {
            (SplitVariant::TwoPass(_), Some((mid, g)), [(first, p1), (second, p2)]) => {
                let mid_view = view(mid);
                pass(
                    device,
                    first,
                    p1,
                    &[res(&from_view), res(&mid_view)],
                    groups(g.intermediate_size(), 16),
                )
                .then(pass(
                    device,
                    second,
                    p2,
                    &[res(&mid_view), res(&to_view)],
                    groups(to_size, 16),
                ))
            }
            (SplitVariant::Tiled, _, [(name, p)]) => pass(
                device,
                name,
                p,
                &[res(&from_view), res(&to_view)],
                self.tiles(),
            ),
            (_, _, [(name, p)]) => pass(
                device,
                name,
                p,
                &[res(&from_view), res(&to_view)],
                groups(to_size, 16),
            ),
            _ => unreachable!("pipelines are built per variant in Splitter::new"),
        };
        Ok(passes)
    }
}
