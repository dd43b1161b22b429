//! VPL visibility from ManyLoDs (Holländer 2013 §3.6, the paper's SSM mode): the scene is
//! sampled into surfels with a bounding-sphere hierarchy, every VPL is a paraboloid view
//! ([`vpl_views`]), and the cut's splats give one small shadow map per VPL in an atlas; the
//! VPL shading then looks its pixel up there. The imperfect-shadow-map baseline splats a fixed
//! random subset of the surfels instead; the exact mode rasterises every VPL's hemicube and
//! reindexes it into the same atlas (Segovia 2006's SSM, [`crate::ssm`]).

use ::gpu::{PassTimer, transfer};
use glam::Vec3;
use manylod::gpu::GpuRefit;
use manylod::{
    AtlasLayout, Bsh, View,
    gpu::{CutKind, GpuIsm, GpuManyLod},
    lookup::AtlasParams,
    splat, surfels,
};
use scene::Scene;

use crate::IndirectError;
use crate::cpu::Visibility;
use crate::rays::RayBvh;
use crate::ssm::RasterisedMaps;
use crate::vpl::{GpuVpl, VplSet};
use tiled_shading::gpu::shadows::GpuRays;
use tiled_shading::rays::RayParams;
pub use tiled_shading::rays::scene_mesh;

/// Which VPL shadow maps the indirect light uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VplShadows {
    /// ManyLoDs: a cut per VPL each frame (from the last frame's cut), splatted into the atlas.
    ManyLod,
    /// Imperfect shadow maps: a fixed random point subset per VPL.
    Ism,
    /// Exact: every VPL's hemicube rasterised from the scene's triangles (Segovia 2006 §4.3,
    /// [`crate::ssm`]); the surfel settings are unused.
    Rasterised,
    /// Exact without maps: a ray per (receiver, VPL) pair through a BVH of the scene's
    /// triangles ([`crate::rays`]); the map settings are unused.
    Rays,
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
    /// Receivers move off their surface by this many atlas pixels at their distance before
    /// the lookup (normal-offset shadows): without it, a surface's own splats shadow it.
    pub normal_offset: f32,
    /// Slope-scaled depth tolerance: atlas pixels per unit of tan θ of the receiver
    /// ([`AtlasParams::slope`]).
    pub slope: f32,
    /// The most bytes of one node-view list (ManyLoD's active and cut lists, the ISM list),
    /// or of the hemicube face atlas ([`VplShadows::Rasterised`]); `None`: the device's
    /// storage-binding, buffer and texture limits. Views are split into batches that fit, all
    /// writing into one atlas, so the atlas is the same either way.
    pub list_bytes: Option<u64>,
    /// ManyLoD and ISM: keep the surfels and a refit (Holländer 2013 §3.5.3) so that
    /// [`VplShadowMaps::set_positions`] can move the hierarchy (and the ISM points) with
    /// deforming meshes.
    pub refit: bool,
}

impl Default for ShadowConfig {
    /// 2^20 surfels, ε = 2 px, 32×32 micro-views, 8 k ISM points, bias 1 % of the diagonal,
    /// a normal offset of one atlas pixel and no slope tolerance (the splats' discs need the
    /// offset), lists as large as the device allows.
    fn default() -> Self {
        Self {
            points_log2: 20,
            epsilon: 2.0,
            tile: 32,
            ism_points: 8192,
            bias: 0.01,
            normal_offset: 1.0,
            slope: 0.0,
            list_bytes: None,
            refit: false,
        }
    }
}

impl ShadowConfig {
    /// The defaults for `mode`: [`Default`] for the splatted maps (and rays, which use none of
    /// it); for the rasterised
    /// hemicubes, whose depths are the surfaces' own, no normal offset, a bias of 0.1 % of the
    /// diagonal and 1.5 pixels of tolerance per unit of tan θ. Against a ray per (receiver,
    /// VPL) pair (`CornellBox-Original.obj`, 1024 VPLs, 64² tiles, 64² pixels), the relative
    /// RMS of one frame's visible VPL light away from the lamp's 1 cm gap falls from 1.9 % to
    /// 1.2 % (the offset and the 1 % bias carry receivers past occluders at contacts).
    pub fn for_mode(mode: VplShadows) -> Self {
        match mode {
            VplShadows::ManyLod | VplShadows::Ism | VplShadows::Rays => Self::default(),
            VplShadows::Rasterised => Self {
                bias: 0.001,
                normal_offset: 0.0,
                slope: 1.5,
                ..Self::default()
            },
        }
    }

    /// An error naming the first bias, normal offset or slope tolerance that is negative or
    /// not finite.
    pub fn validate(&self) -> Result<(), IndirectError> {
        for (what, value) in [
            ("bias", self.bias),
            ("normal offset", self.normal_offset),
            ("slope tolerance", self.slope),
        ] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(IndirectError::ShadowLookup { what, value });
            }
        }
        Ok(())
    }
}

/// Visibility of `p` (normal `n`) from VPL `k` in `atlas`: [`manylod::lookup::visibility`]
/// from the VPL's position and normal (`atlas_visibility` in `vpl_shading.wgsl`).
pub fn vpl_visibility(
    atlas: &[u32],
    params: &AtlasParams,
    k: u32,
    vpl: &GpuVpl,
    p: Vec3,
    n: Vec3,
) -> f32 {
    let view = (Vec3::from(vpl.position), Vec3::from(vpl.normal));
    manylod::lookup::visibility(atlas, params, k, view, p, n)
}

/// Node-views a ManyLoD cut list holds per micro-view pixel: cuts hold culled node-views too,
/// and Sponza's ε = 2 px cuts are ~8 per pixel.
const NODE_VIEWS_PER_PIXEL: usize = 24;

/// Bytes of one node-view in a list.
const NODE_VIEW_BYTES: u64 = 8;

/// One batch of VPL views: its cut (or ISM list) splatting into the shared atlas.
struct Batch {
    manylod: GpuManyLod,
    ism: Option<GpuIsm>,
    /// The refit of this batch's copy of the hierarchy ([`ShadowConfig::refit`]).
    refit: Option<GpuRefit>,
    views: usize,
}

/// What fills the atlas: cut batches (ManyLoD, ISM) or rasterised hemicubes; or no atlas but
/// the scene's BVH for rays.
enum Source {
    Cuts(Vec<Batch>),
    Rasterised(Box<RasterisedMaps>),
    Rays(Box<RayBvh>),
}

/// What the VPL shading binds for visibility (`vpl_shading.wgsl`'s bindings 9–12): the atlas
/// and its parameters, the BVH's nodes and triangles, and the rays' offset off both surfaces
/// (0: no rays).
pub struct VisibilityBindings<'a> {
    /// Packed depths.
    pub atlas: &'a wgpu::Buffer,
    /// Uniform `AtlasParams`.
    pub params: &'a wgpu::Buffer,
    /// [`crate::rays::RayNode`]s.
    pub ray_nodes: &'a wgpu::Buffer,
    /// [`crate::rays::RayTriangle`]s.
    pub ray_triangles: &'a wgpu::Buffer,
    /// Factor on [`crate::rays::ray_lift`] by which the rays' ends leave their surfaces (1);
    /// 0 looks the atlas up instead.
    pub ray_offset: f32,
}

/// The VPL shadow maps on the GPU: the hierarchy, the cuts and the atlas (and the ISM points),
/// in as many batches of views as the device's binding limits need; or the rasterised
/// hemicubes ([`VplShadows::Rasterised`]).
pub struct VplShadowMaps {
    source: Source,
    atlas: wgpu::Buffer,
    layout: AtlasLayout,
    params: wgpu::Buffer,
    shadow_params: AtlasParams,
    rays: GpuRays,
    ray_offset: f32,
    mode: VplShadows,
    frames: u32,
    /// New positions were set: the next frame refits before its cuts.
    moved: bool,
}

impl VplShadowMaps {
    /// Samples `scene`, builds the hierarchy and one paraboloid view per VPL of `set`, split
    /// into batches whose node-view lists fit `config.list_bytes` or the device.
    pub fn new(
        device: &wgpu::Device,
        scene: &Scene,
        set: &VplSet,
        mode: VplShadows,
        config: &ShadowConfig,
    ) -> Result<Self, IndirectError> {
        let diagonal = scene.bounds().diagonal();
        let lift = 1e-3 * diagonal;
        let (positions, indices) = scene_mesh(scene);
        let mesh = (&positions[..], &indices[..]);
        if mode == VplShadows::Rays {
            return Self::rays(device, mesh, 1.0);
        }
        let views = vpl_views(set, config.tile, lift);
        Self::from_views(device, mesh, diagonal, views, lift, mode, config)
    }

    /// Visibility by rays through the BVH of `mesh`, whose ends leave their surfaces by
    /// `offset` × [`crate::rays::ray_lift`]: no atlas (a disabled one binds in its place).
    fn rays(
        device: &wgpu::Device,
        mesh: (&[Vec3], &[u32]),
        offset: f32,
    ) -> Result<Self, IndirectError> {
        let bvh = RayBvh::new(mesh)?;
        // The VPL shading takes its offset from its own parameters.
        let rays = GpuRays::new(device, &bvh, RayParams::default())?;
        let (atlas, params) = disabled_atlas(device)?;
        Ok(Self {
            source: Source::Rays(Box::new(bvh)),
            atlas,
            layout: vpl_atlas(0, 1, 1.0),
            params,
            shadow_params: AtlasParams::default(),
            rays,
            ray_offset: offset,
            mode: VplShadows::Rays,
            frames: 0,
            moved: false,
        })
    }

    /// The same for any paraboloid `views` (each `config.tile` pixels, set `lift` off its
    /// origin) of the triangle `mesh` ([`scene_mesh`]) of a scene of `diagonal`: the direct
    /// lights' ManyLoD shadows (`tiled_shading::shadows::paraboloid_views`).
    pub fn from_views(
        device: &wgpu::Device,
        mesh: (&[Vec3], &[u32]),
        diagonal: f32,
        views: Vec<View>,
        lift: f32,
        mode: VplShadows,
        config: &ShadowConfig,
    ) -> Result<Self, IndirectError> {
        config.validate()?;
        if mode == VplShadows::Rays {
            return Err(IndirectError::Rays(
                "rays need VPLs (VplShadowMaps::new), not views".into(),
            ));
        }
        let layout = vpl_atlas(views.len(), config.tile, diagonal);
        let (width, height) = layout.size();
        let atlas = transfer::buffer(
            device,
            "vpl shadow atlas",
            u64::from(width) * u64::from(height) * 4,
            wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
        )?;
        let source = match mode {
            VplShadows::Rasterised => Source::Rasterised(Box::new(RasterisedMaps::new(
                device,
                mesh,
                &views,
                layout,
                2 * config.tile,
                &atlas,
                config.list_bytes,
            )?)),
            VplShadows::ManyLod | VplShadows::Ism | VplShadows::Rays => Source::Cuts(cut_batches(
                device, mesh, &views, layout, &atlas, mode, config,
            )?),
        };
        let params = AtlasParams {
            enabled: 1,
            tile: layout.tile,
            columns: layout.columns,
            width,
            far: layout.far,
            lift,
            bias: config.bias,
            normal_offset: config.normal_offset,
            slope: config.slope,
        };
        let shadow_params = params;
        let params = transfer::buffer_init(
            device,
            "vpl shadow params",
            bytemuck::bytes_of(&params),
            wgpu::BufferUsages::UNIFORM,
        )?;
        Ok(Self {
            source,
            atlas,
            layout,
            params,
            shadow_params,
            rays: GpuRays::none(device)?,
            ray_offset: 0.0,
            mode,
            frames: 0,
            moved: false,
        })
    }

    /// Records this frame's shadow maps, batch after batch (the first clears the atlas): the
    /// cut (basic on the first frame, incremental after) and its splat, or the ISM splat.
    pub fn encode(&mut self, encoder: &mut wgpu::CommandEncoder, timer: Option<&PassTimer>) {
        let batches = match &mut self.source {
            Source::Cuts(batches) => batches,
            Source::Rasterised(maps) => {
                maps.encode(encoder, timer);
                return;
            }
            Source::Rays(_) => return,
        };
        for batch in batches.iter() {
            if let Some(refit) = batch.refit.as_ref().filter(|_| self.moved) {
                refit.encode(encoder, timer);
            }
        }
        self.moved = false;
        for batch in batches {
            match &batch.ism {
                Some(ism) => ism.encode(encoder, &batch.manylod, timer),
                None => {
                    let kind = if self.frames == 0 {
                        CutKind::Basic
                    } else {
                        CutKind::Incremental
                    };
                    batch.manylod.encode_cut(encoder, kind, timer);
                    batch.manylod.encode_splat(encoder, timer);
                }
            }
        }
        self.frames += 1;
    }

    /// Moves the hierarchy with its deformed mesh: `positions` are the triangle mesh's
    /// ([`scene_mesh`] of the posed scene, as many as at set-up); the next frame refits every
    /// batch's hierarchy bottom-up (§3.5.3) before its (incremental) cut, and the ISM points
    /// with its leaves. Needs ManyLoD or ISM maps made with [`ShadowConfig::refit`].
    pub fn set_positions(
        &mut self,
        queue: &wgpu::Queue,
        positions: &[Vec3],
    ) -> Result<(), IndirectError> {
        let refits: Vec<&GpuRefit> = match &self.source {
            Source::Cuts(batches) => batches.iter().filter_map(|b| b.refit.as_ref()).collect(),
            _ => Vec::new(),
        };
        if refits.is_empty() {
            return Err(IndirectError::ManyLod(manylod::ManyLodError::Mismatch(
                format!(
                    "{:?} shadow maps made without refit cannot follow a deforming mesh (ManyLoD and ISM with ShadowConfig::refit can)",
                    self.mode
                ),
            )));
        }
        for r in refits {
            r.set_positions(queue, positions)?;
        }
        self.moved = true;
        Ok(())
    }

    /// Moves the maps to another VPL set of as many VPLs (a progressive frame's new set,
    /// VPLs that follow moving lights): only the views are rewritten; ManyLoD's next cut still
    /// starts from its last one.
    pub fn set_vpls(&self, queue: &wgpu::Queue, set: &VplSet) -> Result<(), IndirectError> {
        self.set_views(
            queue,
            &vpl_views(set, self.layout.tile, self.shadow_params.lift),
        )
    }

    /// The same for any paraboloid `views` (as many as made, `lift` as made).
    pub fn set_views(&self, queue: &wgpu::Queue, views: &[View]) -> Result<(), IndirectError> {
        match &self.source {
            Source::Rasterised(maps) => maps.set_views(queue, views),
            Source::Rays(_) => Ok(()),
            Source::Cuts(batches) => {
                let made: usize = batches.iter().map(|b| b.views).sum();
                if views.len() != made {
                    return Err(IndirectError::ManyLod(manylod::ManyLodError::Mismatch(
                        format!("{} views for shadow maps made for {made}", views.len()),
                    )));
                }
                let mut first = 0;
                for b in batches {
                    b.manylod.set_views(queue, &views[first..first + b.views])?;
                    first += b.views;
                }
                Ok(())
            }
        }
    }

    /// Which visibility these are.
    pub fn mode(&self) -> VplShadows {
        self.mode
    }

    /// What the VPL shading binds.
    pub fn bindings(&self) -> VisibilityBindings<'_> {
        VisibilityBindings {
            atlas: &self.atlas,
            params: &self.params,
            ray_nodes: &self.rays.nodes,
            ray_triangles: &self.rays.triangles,
            ray_offset: self.ray_offset,
        }
    }

    /// The CPU twin's visibility: the rays' BVH, or `atlas` (read back by
    /// [`Self::read_atlas`]) with [`Self::params`].
    pub fn cpu_visibility<'a>(&'a self, atlas: &'a [u32]) -> Visibility<'a> {
        match &self.source {
            Source::Rays(bvh) => Visibility::Rays(bvh, self.ray_offset),
            _ => Visibility::Atlas(atlas, self.shadow_params),
        }
    }

    /// What the shading's lookup needs ([`vpl_visibility`]).
    pub fn params(&self) -> AtlasParams {
        self.shadow_params
    }

    /// The atlas layout (every VPL's tile).
    pub fn layout(&self) -> AtlasLayout {
        self.layout
    }

    /// How many batches of views the lists (or the rasterised hemicubes) were split into
    /// (1 where the device's bindings and textures hold every view).
    pub fn batch_count(&self) -> usize {
        match &self.source {
            Source::Cuts(batches) => batches.len(),
            Source::Rasterised(maps) => maps.batch_count(),
            Source::Rays(_) => 1,
        }
    }

    /// Reads the atlas back (row-major packed depths; empty for rays, which have none); an
    /// error when a batch's lists overflowed (the atlas then misses splats).
    pub fn read_atlas(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<Vec<u32>, IndirectError> {
        match &self.source {
            Source::Cuts(batches) => {
                for batch in batches {
                    batch.manylod.check_lists(device, queue)?;
                }
            }
            Source::Rays(_) => return Ok(Vec::new()),
            Source::Rasterised(_) => {}
        }
        Ok(transfer::read_pod(device, queue, &self.atlas)?)
    }
}

/// The ManyLoD cuts (or ISM lists) of `views` over the surfels of `mesh`, splatting into
/// `atlas`, in batches whose node-view lists fit `config.list_bytes` or the device.
fn cut_batches(
    device: &wgpu::Device,
    (positions, indices): (&[Vec3], &[u32]),
    views: &[View],
    layout: AtlasLayout,
    atlas: &wgpu::Buffer,
    mode: VplShadows,
    config: &ShadowConfig,
) -> Result<Vec<Batch>, IndirectError> {
    let count = 1usize << config.points_log2.min(26);
    let s = surfels::sample(positions, indices, count, 1)?;
    let (p, n) = surfels::evaluate(&s, positions, indices);
    let bsh = Bsh::build(&p, &n, surfels::disc_radius(positions, indices, count))?;
    let limits = device.limits();
    let list_bytes = config.list_bytes.unwrap_or(
        limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size),
    );
    let ism = match mode {
        VplShadows::ManyLod | VplShadows::Rasterised | VplShadows::Rays => None,
        VplShadows::Ism => {
            let leaves = &bsh.nodes[bsh.leaf_count() - 1..];
            let per_view = config.ism_points.min(leaves.len());
            Some((per_view, splat::ism(leaves, views.len(), per_view, 1)?))
        }
    };
    // Node-views one view needs in a list: its share of a cut, or its ISM points.
    let per_view = match &ism {
        None => (config.tile * config.tile) as usize * NODE_VIEWS_PER_PIXEL,
        Some((per_view, _)) => *per_view,
    };
    let batch_views = (list_bytes / (per_view as u64 * NODE_VIEW_BYTES)).max(1) as usize;
    let mut batches = Vec::new();
    for (b, chunk) in views.chunks(batch_views).enumerate() {
        let first = b * batch_views;
        let batch_layout = layout.batch(first as u32);
        // ISM binds no cut lists: ManyLoD's smallest lists suffice.
        let capacity = match ism {
            None => chunk.len() * per_view,
            Some(_) => chunk.len().max(2),
        };
        let manylod = GpuManyLod::new(
            device,
            &bsh,
            chunk,
            config.epsilon,
            batch_layout,
            capacity,
            Some(atlas),
        )?;
        let gpu_ism = match &ism {
            None => None,
            Some((per_view, (points, list))) => {
                let own: Vec<_> = list[first * per_view..(first + chunk.len()) * per_view]
                    .iter()
                    .map(|nv| manylod::NodeView {
                        view: nv.view - first as u32,
                        ..*nv
                    })
                    .collect();
                Some(GpuIsm::new(device, &manylod, points, &own)?)
            }
        };
        let refit = if config.refit {
            let mut refit = GpuRefit::new(device, &manylod, &bsh, &s, positions, indices)?;
            // The ISM points are the leaves with grown discs: they follow the refit leaves.
            if let (Some(g), Some((_, (points, _)))) = (&gpu_ism, &ism) {
                let radius = points.first().map_or(bsh.leaf_radius, |p| p.radius);
                refit.follow_points(device, &g.points, radius)?;
            }
            Some(refit)
        } else {
            None
        };
        batches.push(Batch {
            manylod,
            ism: gpu_ism,
            refit,
            views: chunk.len(),
        });
    }
    Ok(batches)
}

/// The atlas and parameter buffers of shading without maps (the shading then ignores them).
fn disabled_atlas(device: &wgpu::Device) -> Result<(wgpu::Buffer, wgpu::Buffer), IndirectError> {
    let atlas = transfer::buffer(device, "no vpl shadows", 16, wgpu::BufferUsages::STORAGE)?;
    let params = transfer::buffer_init(
        device,
        "no vpl shadow params",
        bytemuck::bytes_of(&AtlasParams::default()),
        wgpu::BufferUsages::UNIFORM,
    )?;
    Ok((atlas, params))
}

/// What the VPL shading binds without visibility: a disabled atlas and no rays.
pub struct DisabledBindings {
    atlas: (wgpu::Buffer, wgpu::Buffer),
    rays: GpuRays,
}

impl DisabledBindings {
    /// The buffers.
    pub fn new(device: &wgpu::Device) -> Result<Self, IndirectError> {
        Ok(Self {
            atlas: disabled_atlas(device)?,
            rays: GpuRays::none(device)?,
        })
    }

    /// As [`VplShadowMaps::bindings`] gives them.
    pub fn bindings(&self) -> VisibilityBindings<'_> {
        VisibilityBindings {
            atlas: &self.atlas.0,
            params: &self.atlas.1,
            ray_nodes: &self.rays.nodes,
            ray_triangles: &self.rays.triangles,
            ray_offset: 0.0,
        }
    }
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
