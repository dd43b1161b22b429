//! VPL visibility from ManyLoDs (Holländer 2013 §3.6, the paper's SSM mode): the scene is
//! sampled into surfels with a bounding-sphere hierarchy, every VPL is a paraboloid view
//! ([`vpl_views`]), and the cut's splats give one small shadow map per VPL in an atlas; the
//! VPL shading then looks its pixel up there. The imperfect-shadow-map baseline splats a fixed
//! random subset of the surfels instead.

use ::gpu::{PassTimer, transfer};
use glam::Vec3;
use manylod::{
    AtlasLayout, Bsh, View,
    gpu::{CutKind, GpuIsm, GpuManyLod},
    splat, surfels,
};
use scene::Scene;

use crate::IndirectError;
use crate::vpl::VplSet;

/// Which VPL shadow maps the indirect light uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VplShadows {
    /// ManyLoDs: a cut per VPL each frame (from the last frame's cut), splatted into the atlas.
    ManyLod,
    /// Imperfect shadow maps: a fixed random point subset per VPL.
    Ism,
}

/// Settings of the VPL shadow maps.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowConfig {
    /// Surfels: `2^points_log2`.
    pub points_log2: u32,
    /// Cut threshold ε in micro-view pixels.
    pub epsilon: f32,
    /// Micro-view side in pixels.
    pub tile: u32,
    /// ISM points per VPL.
    pub ism_points: usize,
    /// Depth bias as a fraction of the scene diagonal.
    pub bias: f32,
}

impl Default for ShadowConfig {
    /// 2^20 surfels, ε = 2 px, 32×32 micro-views, 8 k ISM points, bias 1 % of the diagonal.
    fn default() -> Self {
        Self {
            points_log2: 20,
            epsilon: 2.0,
            tile: 32,
            ism_points: 8192,
            bias: 0.01,
        }
    }
}

/// Uniform block `ShadowParams` of `vpl_shading.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ShadowParams {
    enabled: u32,
    tile: u32,
    columns: u32,
    width: u32,
    far: f32,
    lift: f32,
    bias: f32,
    _pad: u32,
}

/// The VPL shadow maps on the GPU: the hierarchy, the cut and the atlas (and the ISM points).
pub struct VplShadowMaps {
    manylod: GpuManyLod,
    ism: Option<GpuIsm>,
    params: wgpu::Buffer,
    frames: u32,
}

impl VplShadowMaps {
    /// Samples `scene`, builds the hierarchy and one paraboloid view per VPL of `set`.
    pub fn new(
        device: &wgpu::Device,
        scene: &Scene,
        set: &VplSet,
        mode: VplShadows,
        config: &ShadowConfig,
    ) -> Result<Self, IndirectError> {
        let (positions, indices) = scene_mesh(scene);
        let count = 1usize << config.points_log2.min(26);
        let s = surfels::sample(&positions, &indices, count, 1)?;
        let (p, n) = surfels::evaluate(&s, &positions, &indices);
        let bsh = Bsh::build(&p, &n, surfels::disc_radius(&positions, &indices, count))?;
        let diagonal = scene.bounds().diagonal();
        let lift = 1e-3 * diagonal;
        let views = vpl_views(set, config.tile, lift);
        let layout = vpl_atlas(views.len(), config.tile, diagonal);
        // Cuts hold culled node-views too: Sponza's ε = 2 px cuts are ~8 per micro-view pixel.
        let capacity = views.len() * (config.tile * config.tile) as usize * 24;
        let manylod =
            GpuManyLod::new(device, &bsh, &views, config.epsilon, layout, capacity, None)?;
        let ism = match mode {
            VplShadows::ManyLod => None,
            VplShadows::Ism => {
                let leaves = &bsh.nodes[bsh.leaf_count() - 1..];
                let per_view = config.ism_points.min(leaves.len());
                let (points, list) = splat::ism(leaves, views.len(), per_view, 1)?;
                Some(GpuIsm::new(device, &manylod, &points, &list)?)
            }
        };
        let (width, _) = layout.size();
        let params = ShadowParams {
            enabled: 1,
            tile: layout.tile,
            columns: layout.columns,
            width,
            far: layout.far,
            lift,
            bias: config.bias,
            _pad: 0,
        };
        let params = transfer::buffer_init(
            device,
            "vpl shadow params",
            bytemuck::bytes_of(&params),
            wgpu::BufferUsages::UNIFORM,
        )?;
        Ok(Self {
            manylod,
            ism,
            params,
            frames: 0,
        })
    }

    /// Records this frame's shadow maps: the cut (basic on the first frame, incremental after)
    /// and its splat, or the ISM splat.
    pub fn encode(&mut self, encoder: &mut wgpu::CommandEncoder, timer: Option<&PassTimer>) {
        match &self.ism {
            Some(ism) => ism.encode(encoder, &self.manylod, timer),
            None => {
                let kind = if self.frames == 0 {
                    CutKind::Basic
                } else {
                    CutKind::Incremental
                };
                self.manylod.encode_cut(encoder, kind, timer);
                self.manylod.encode_splat(encoder, timer);
            }
        }
        self.frames += 1;
    }

    /// The atlas and parameter buffers the VPL shading binds.
    pub fn bindings(&self) -> (&wgpu::Buffer, &wgpu::Buffer) {
        (&self.manylod.atlas, &self.params)
    }

    /// The GPU ManyLoDs set-up (for reading the cut or the atlas back).
    pub fn manylod(&self) -> &GpuManyLod {
        &self.manylod
    }
}

/// Stand-ins for the shading's shadow bindings when no shadow maps are used (visibility 1).
pub fn disabled_bindings(
    device: &wgpu::Device,
) -> Result<(wgpu::Buffer, wgpu::Buffer), IndirectError> {
    let atlas = transfer::buffer(device, "no vpl shadows", 16, wgpu::BufferUsages::STORAGE)?;
    let params = transfer::buffer_init(
        device,
        "no vpl shadow params",
        bytemuck::bytes_of(&ShadowParams::default()),
        wgpu::BufferUsages::UNIFORM,
    )?;
    Ok((atlas, params))
}

/// All meshes of `scene` as one triangle list (world-space positions, indices).
pub fn scene_mesh(scene: &Scene) -> (Vec<Vec3>, Vec<u32>) {
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    for m in &scene.meshes {
        let base = positions.len() as u32;
        positions.extend_from_slice(&m.positions);
        indices.extend(m.indices.iter().map(|i| base + i));
    }
    (positions, indices)
}

/// One `tile × tile` paraboloid view per VPL, on its hemisphere, lifted off the surface by
/// `lift` so the VPL's own surface does not shadow it.
pub fn vpl_views(set: &VplSet, tile: u32, lift: f32) -> Vec<View> {
    set.vpls
        .iter()
        .map(|v| View::Paraboloid {
            position: v.position + v.normal * lift,
            normal: v.normal,
            size: tile,
        })
        .collect()
}

/// The atlas for the VPL views of a scene of `diagonal`: depth 1 at the diagonal.
pub fn vpl_atlas(views: usize, tile: u32, diagonal: f32) -> AtlasLayout {
    AtlasLayout::new(views, tile, diagonal)
}
