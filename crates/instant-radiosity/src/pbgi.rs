//! Point-based global illumination through many-view cuts (Holländer 2013 §3.6.1, after
//! Christensen 2008 and Ritschel et al. 2009): one diffuse bounce gathered from surfels that
//! carry the direct light they receive.
//!
//! 1. **Surfels** sample the scene uniformly by area (`manylod::surfels`), each with the exit
//!    radiance of a Lambertian surface, `L = ρ/π · E_direct`, its direct irradiance from every
//!    light by a shadow ray ([`crate::near_field::direct_irradiance`]); the bounding-sphere
//!    hierarchy over them carries each node's mean radiance (its leaves cover equal areas).
//! 2. **Receivers** (back-projected pixels) each get an indirect-lighting view: a paraboloid
//!    over their hemisphere, `tile × tile` texels.
//! 3. The **many-view cut** (`manylod::cut`, threshold ε pixels) picks the nodes every view
//!    draws; the splat keeps the nearest node per texel (`manylod::splat::nearest_nodes`).
//! 4. The **convolution with the BRDF**: the receiver's irradiance is the sum over texels of
//!    `L · cos θ · dω`; for the paraboloid `(u, v) = (d_x, d_y) / (1 + d_z)` a texel at radius
//!    `r` spans `dω = 4 dA / (1 + r²)²` and `cos θ = (1 − r²) / (1 + r²)` (both integrate
//!    exactly over the disc: 2π and π). The diffuse indirect radiance is `ρ/π · E`.
//!
//! [`LitPoints::gather`] is the CPU reference, tested against the path tracer's one-bounce
//! light and the brute-force gather over the same surfels; [`GpuGather`] runs steps 2–4 on the
//! GPU (the ManyLoD cut, `manylod/nearest.wgsl`, `pbgi.wgsl`) and is tested against it
//! (`tests/pbgi.rs`). Not yet on the GPU: the surfels' direct light (uploaded from the CPU),
//! receivers from the G-buffer, the edge-aware upsampling to the frame.

use ::gpu::kernel::{Binding, Kernel, Passes, Workgroups};
use ::gpu::{PassTimer, transfer, wgpu};
use glam::Vec3;
use manylod::gpu::{CutKind, GpuManyLod};
use manylod::{AtlasLayout, Bsh, CutProblem, View, splat::NO_NODE};
use rayon::prelude::*;
use scene::Scene;
use tiled_shading::{GpuLight, rays::RayBvh, rays::scene_mesh};

use crate::IndirectError;

/// How finely PBGI gathers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PbgiConfig {
    /// Side of each receiver's paraboloid view in texels.
    pub tile: u32,
    /// The cut threshold ε: nodes are drawn once their projected diameter is below ε texels.
    pub epsilon: f32,
    /// `2^points_log2` surfels.
    pub points_log2: u32,
}

impl Default for PbgiConfig {
    /// 32² texels, ε = 1 texel, 2^16 surfels (a small scene's; Fig. 3.18 used 1 M).
    fn default() -> Self {
        Self {
            tile: 32,
            epsilon: 1.0,
            points_log2: 16,
        }
    }
}

impl PbgiConfig {
    /// Checks the settings.
    pub fn validate(&self) -> Result<(), IndirectError> {
        let bad = |m: String| Err(IndirectError::Config(m));
        if !(4..=256).contains(&self.tile) {
            return bad(format!("PBGI tile {} outside 4..=256", self.tile));
        }
        if !(self.epsilon.is_finite() && self.epsilon > 0.0) {
            return bad(format!("PBGI ε {} must be positive", self.epsilon));
        }
        if !(4..=24).contains(&self.points_log2) {
            return bad(format!(
                "2^{} PBGI surfels outside 2^4..=2^24",
                self.points_log2
            ));
        }
        Ok(())
    }
}

/// The lit point hierarchy PBGI gathers from.
#[derive(Clone, Debug)]
pub struct LitPoints {
    /// The hierarchy over the surfels.
    pub bsh: Bsh,
    /// Exit radiance of every node (heap order): its leaves' mean.
    pub radiance: Vec<Vec3>,
    /// Distance mapped to depth 1 in the views (the scene's diagonal).
    pub far: f32,
    /// Packed linear albedo (`pack4x8unorm`) of each leaf slot's surfel, for lighting them
    /// ([`LitPoints::light`], [`GpuGather::light_on_gpu`]); empty for
    /// [`LitPoints::from_hierarchy`].
    pub leaf_albedos: Vec<u32>,
    config: PbgiConfig,
}

impl LitPoints {
    /// Surfels of `scene` lit by `lights` (shadow rays through the scene's triangles):
    /// [`LitPoints::sampled`], then [`LitPoints::light`].
    pub fn new(
        scene: &Scene,
        lights: &[GpuLight],
        config: &PbgiConfig,
    ) -> Result<Self, IndirectError> {
        let mut lit = Self::sampled(scene, config)?;
        lit.light(scene, lights)?;
        Ok(lit)
    }

    /// `2^points_log2` surfels of `scene` (uniform by area) and their hierarchy, not lit yet
    /// (zero radiance): what [`GpuGather::light_on_gpu`] lights every frame.
    pub fn sampled(scene: &Scene, config: &PbgiConfig) -> Result<Self, IndirectError> {
        config.validate()?;
        let (positions, indices) = scene_mesh(scene);
        let count = 1usize << config.points_log2;
        let surfels = manylod::surfels::sample(&positions, &indices, count, 1)?;
        let (points, normals) = manylod::surfels::evaluate(&surfels, &positions, &indices);
        let albedos = crate::near_field::triangle_albedos(scene);
        let leaf_radius = manylod::surfels::disc_radius(&positions, &indices, count);
        let bsh = Bsh::build(&points, &normals, leaf_radius)?;
        let leaf_albedos = bsh
            .order
            .iter()
            .map(|&i| albedos[surfels[i as usize].triangle as usize])
            .collect();
        let unlit = vec![Vec3::ZERO; count];
        Ok(Self {
            leaf_albedos,
            ..Self::from_hierarchy(bsh, &unlit, scene.bounds().diagonal(), *config)
        })
    }

    /// Lights the surfels by `lights`: every leaf leaves `ρ/π · E`, its direct irradiance by
    /// shadow rays through `scene`'s triangles, every node the mean of its children
    /// (`pbgi_lighting.wgsl`'s twin).
    pub fn light(&mut self, scene: &Scene, lights: &[GpuLight]) -> Result<(), IndirectError> {
        let n = self.bsh.leaf_count();
        if self.leaf_albedos.len() != n {
            return Err(IndirectError::Config(
                "lighting needs the surfels' albedos (points from LitPoints::sampled)".into(),
            ));
        }
        let (positions, indices) = scene_mesh(scene);
        let bvh = RayBvh::new((&positions, &indices))?;
        let reach = 2.0 * scene.bounds().diagonal().max(1e-6);
        let leaves = &self.bsh.nodes[n - 1..];
        self.radiance[n - 1..]
            .par_iter_mut()
            .zip(leaves.par_iter().zip(&self.leaf_albedos))
            .for_each(|(radiance, (leaf, &albedo))| {
                let rho = crate::near_field::unpack_rgb(albedo);
                let e = crate::near_field::direct_irradiance(
                    &bvh,
                    lights,
                    reach,
                    (leaf.center, leaf.axis),
                );
                *radiance = rho * e * std::f32::consts::FRAC_1_PI;
            });
        average_nodes(&mut self.radiance, n);
        Ok(())
    }

    /// The hierarchy `bsh` over points whose exit radiance is `leaf_radiance` (in the points'
    /// order, before the tree's), views reaching `far`.
    pub fn from_hierarchy(bsh: Bsh, leaf_radiance: &[Vec3], far: f32, config: PbgiConfig) -> Self {
        let n = bsh.leaf_count();
        let mut radiance = vec![Vec3::ZERO; 2 * n - 1];
        for (slot, &i) in bsh.order.iter().enumerate() {
            radiance[n - 1 + slot] = leaf_radiance[i as usize];
        }
        average_nodes(&mut radiance, n);
        Self {
            bsh,
            radiance,
            far: far.max(1e-6),
            leaf_albedos: Vec::new(),
            config,
        }
    }

    /// The same lit points gathered with `config`'s tile and ε (its point count must be
    /// theirs).
    pub fn reconfigured(&self, config: PbgiConfig) -> Result<Self, IndirectError> {
        config.validate()?;
        if config.points_log2 != self.config.points_log2 {
            return Err(IndirectError::Config(format!(
                "2^{} points configured for 2^{} lit points",
                config.points_log2, self.config.points_log2
            )));
        }
        Ok(Self {
            config,
            ..self.clone()
        })
    }

    /// The settings.
    pub fn config(&self) -> &PbgiConfig {
        &self.config
    }

    /// The irradiance at each receiver `(position, unit normal)`: its paraboloid view's texels
    /// (nearest drawn node each) weighted by [`texel_weight`].
    pub fn gather(&self, receivers: &[(Vec3, Vec3)]) -> Result<Vec<Vec3>, IndirectError> {
        let tile = self.config.tile;
        let views = gather_views(receivers, tile);
        let problem = CutProblem {
            bsh: &self.bsh,
            views: &views,
            epsilon: self.config.epsilon,
        };
        problem.check()?;
        let cut = manylod::cut::basic(&problem)?;
        let mut drawn: Vec<Vec<u32>> = vec![Vec::new(); views.len()];
        for nv in &cut.node_views {
            if problem.is_drawn(*nv) {
                drawn[nv.view as usize].push(nv.node);
            }
        }
        let layout = AtlasLayout::new(1, tile, self.far);
        let weights: Vec<f32> = (0..tile * tile)
            .map(|i| texel_weight(i % tile, i / tile, tile))
            .collect();
        Ok(views
            .par_iter()
            .zip(&drawn)
            .map(|(view, drawn)| {
                manylod::splat::nearest_nodes(&self.bsh.nodes, view, drawn, &layout)
                    .iter()
                    .zip(&weights)
                    .filter(|(n, _)| **n != NO_NODE)
                    .map(|(&n, &w)| self.radiance[n as usize] * w)
                    .sum()
            })
            .collect())
    }
}

/// Every inner node's radiance the mean of its two children's, from the deepest level up
/// (`n` leaves at the heap's end).
fn average_nodes(radiance: &mut [Vec3], n: usize) {
    for i in (0..n - 1).rev() {
        let c = manylod::bsh::first_child(i as u32) as usize;
        radiance[i] = (radiance[c] + radiance[c + 1]) * 0.5;
    }
}

/// The indirect-lighting view of each receiver `(position, unit normal)`: a paraboloid of
/// `tile` texels over its hemisphere, lifted off the surface by [`crate::rays::ray_lift`].
pub fn gather_views(receivers: &[(Vec3, Vec3)], tile: u32) -> Vec<View> {
    receivers
        .iter()
        .map(|&(p, n)| View::Paraboloid {
            position: p + n * crate::rays::ray_lift(p),
            normal: n,
            size: tile,
        })
        .collect()
}

/// Receivers on a grid over a frame: the centre pixel of every `stride × stride` cell
/// (clamped to the frame), row by row.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ReceiverGrid {
    /// Cell side in pixels.
    pub stride: u32,
    /// Cells across.
    pub columns: u32,
    /// Cells down.
    pub rows: u32,
    /// The frame's size.
    pub size: (u32, u32),
}

impl ReceiverGrid {
    /// The grid of `stride`-pixel cells over a `size` frame.
    pub fn new(size: (u32, u32), stride: u32) -> Result<Self, IndirectError> {
        if stride == 0 || size.0 == 0 || size.1 == 0 {
            return Err(IndirectError::Config(format!(
                "a receiver grid of {stride}-pixel cells over {}×{} pixels",
                size.0, size.1
            )));
        }
        Ok(Self {
            stride,
            columns: size.0.div_ceil(stride),
            rows: size.1.div_ceil(stride),
            size,
        })
    }

    /// Number of receivers.
    pub fn len(&self) -> usize {
        (self.columns * self.rows) as usize
    }

    /// Whether the grid has no receivers (never, for a valid grid).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The pixel of receiver `i`.
    pub fn pixel(&self, i: usize) -> (u32, u32) {
        let (cx, cy) = (i as u32 % self.columns, i as u32 / self.columns);
        (
            (cx * self.stride + self.stride / 2).min(self.size.0 - 1),
            (cy * self.stride + self.stride / 2).min(self.size.1 - 1),
        )
    }
}

/// The receivers of `grid` in a CPU G-buffer (`pbgi_receivers.wgsl`'s twin): each cell's pixel
/// position and normal, or where it shows no surface the eye and +Y (unused irradiance).
pub fn grid_receivers(
    gb: &gbuffer::GBuffer,
    frame: &gbuffer::Frame,
    grid: &ReceiverGrid,
) -> Vec<(Vec3, Vec3)> {
    (0..grid.len())
        .map(|i| {
            let (x, y) = grid.pixel(i);
            let depth = gb.linear_depth.get(x, y);
            if depth > 0.0 {
                (
                    gbuffer::position::from_view_ray(frame, x, y, depth),
                    gbuffer::normal::unpack_octahedral(gb.normal.get(x, y)),
                )
            } else {
                (frame.eye.truncate(), Vec3::Y)
            }
        })
        .collect()
}

/// The edge-aware upsampling's "same surface": normals whose dot product exceeds this (~25°).
pub const SAME_NORMAL: f32 = 0.9;
/// … and a receiver within this fraction of the pixel's view depth of its tangent plane.
pub const SAME_PLANE: f32 = 0.02;

/// The frame's indirect diffuse `E/π` from the receivers' irradiance (`pbgi_upsample.wgsl`'s
/// twin): each pixel's bilinear mean of its four nearest receivers over those on its own
/// surface ([`SAME_NORMAL`], [`SAME_PLANE`]), else over those on any surface; 0 where the
/// pixel shows none.
pub fn upsample(
    gb: &gbuffer::GBuffer,
    frame: &gbuffer::Frame,
    grid: &ReceiverGrid,
    irradiance: &[Vec3],
) -> Result<gbuffer::Image<[f32; 4]>, IndirectError> {
    let (w, h) = grid.size;
    if irradiance.len() != grid.len()
        || gb.linear_depth.width() != w
        || gb.linear_depth.height() != h
    {
        return Err(IndirectError::Config(format!(
            "{} irradiances and a {}×{} G-buffer for a grid of {} receivers over {w}×{h}",
            irradiance.len(),
            gb.linear_depth.width(),
            gb.linear_depth.height(),
            grid.len()
        )));
    }
    let at = |x: u32, y: u32| {
        let depth = gb.linear_depth.get(x, y);
        (
            depth,
            gbuffer::position::from_view_ray(frame, x, y, depth),
            gbuffer::normal::unpack_octahedral(gb.normal.get(x, y)),
        )
    };
    let pixels: Vec<[f32; 4]> = (0..w * h)
        .into_par_iter()
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let (depth, p, n) = at(x, y);
            if depth <= 0.0 {
                return [0.0, 0.0, 0.0, 1.0];
            }
            let half = (grid.stride / 2) as f32;
            let g = (glam::Vec2::new(x as f32, y as f32) - half) / grid.stride as f32;
            let c0 = g.floor();
            let f = g - c0;
            let (mut same, mut any) = ((Vec3::ZERO, 0.0f32), (Vec3::ZERO, 0.0f32));
            for k in 0..4u32 {
                let o = glam::Vec2::new((k & 1) as f32, (k >> 1) as f32);
                let cell = (c0 + o).clamp(
                    glam::Vec2::ZERO,
                    glam::Vec2::new((grid.columns - 1) as f32, (grid.rows - 1) as f32),
                );
                let (cx, cy) = (cell.x as u32, cell.y as u32);
                let weight =
                    (1.0 - f.x + o.x * (2.0 * f.x - 1.0)) * (1.0 - f.y + o.y * (2.0 * f.y - 1.0));
                let (rx, ry) = grid.pixel((cy * grid.columns + cx) as usize);
                let (rd, q, m) = at(rx, ry);
                if rd <= 0.0 {
                    continue;
                }
                let e = irradiance[(cy * grid.columns + cx) as usize];
                any = (any.0 + e * weight, any.1 + weight);
                if n.dot(m) > SAME_NORMAL && n.dot(q - p).abs() < SAME_PLANE * depth {
                    same = (same.0 + e * weight, same.1 + weight);
                }
            }
            let e = if same.1 > 1e-6 {
                same.0 / same.1
            } else if any.1 > 1e-6 {
                any.0 / any.1
            } else {
                Vec3::ZERO
            };
            (e * std::f32::consts::FRAC_1_PI).extend(1.0).to_array()
        })
        .collect();
    gbuffer::Image::from_vec(w, h, pixels).map_err(|e| IndirectError::Config(e.to_string()))
}

/// `Grid` of `pbgi_receivers.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct GridParams {
    stride: u32,
    columns: u32,
    rows: u32,
    tile: u32,
}

/// `Gather` of `pbgi.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct GatherParams {
    width: u32,
    tile: u32,
    columns: u32,
    views: u32,
}

/// The GPU gather ([`LitPoints::gather`]'s twin): the many-view cut of every receiver's view
/// and its nearest-node splat (`manylod::gpu::GpuManyLod`), then the convolution (`pbgi.wgsl`,
/// one workgroup per view) into one irradiance (`vec4<f32>`, RGB) per receiver.
pub struct GpuGather {
    manylod: GpuManyLod,
    convolve: Kernel,
    bind: wgpu::BindGroup,
    irradiance: wgpu::Buffer,
    views: u32,
    tile: u32,
    /// The receivers and upsampling kernels bound to a frame ([`GpuGather::bind_frame`]).
    frame: Option<BoundFrame>,
    /// Every node's exit radiance (`vec4<f32>`, RGB), uploaded or lit on the GPU.
    radiance: wgpu::Buffer,
    /// The surfels' lighting on the GPU ([`GpuGather::light_on_gpu`]).
    lighting: Option<GpuLighting>,
}

/// The surfels' direct light on the GPU (`pbgi_lighting.wgsl`): the scene's BVH, the lights,
/// the leaves' kernel and one averaging dispatch per level of the hierarchy.
struct GpuLighting {
    /// Bound in `leaves`; kept alive here.
    _rays: tiled_shading::gpu::shadows::GpuRays,
    lights: wgpu::Buffer,
    light_capacity: usize,
    /// `Lighting` of every dispatch: the leaves', then each level's from the deepest up.
    params: Vec<(wgpu::Buffer, LightingParams)>,
    leaves: (Kernel, wgpu::BindGroup),
    average: (Kernel, Vec<wgpu::BindGroup>),
}

/// `Lighting` of `pbgi_lighting.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct LightingParams {
    first: u32,
    count: u32,
    lights: u32,
    reach: f32,
}

/// [`GpuGather`]'s kernels bound to a frame's G-buffer and output.
struct BoundFrame {
    receivers: (Kernel, wgpu::BindGroup),
    upsample: (Kernel, wgpu::BindGroup),
    size: (u32, u32),
}

impl GpuGather {
    /// Uploads `lit`'s hierarchy and radiance and the views of `receivers`, with room for
    /// `capacity` node-views in each cut list (a cut that does not fit is an error on read:
    /// raise it).
    pub fn new(
        device: &wgpu::Device,
        lit: &LitPoints,
        receivers: &[(Vec3, Vec3)],
        capacity: usize,
    ) -> Result<Self, IndirectError> {
        let tile = lit.config.tile;
        let views = gather_views(receivers, tile);
        let layout = AtlasLayout::new(views.len(), tile, lit.far);
        let mut manylod = GpuManyLod::new(
            device,
            &lit.bsh,
            &views,
            lit.config.epsilon,
            layout,
            capacity,
            None,
        )?;
        manylod.enable_nearest_nodes(device)?;
        let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
        let radiance: Vec<[f32; 4]> = lit
            .radiance
            .iter()
            .map(|r| r.extend(0.0).to_array())
            .collect();
        let radiance = transfer::buffer_init(
            device,
            "pbgi radiance",
            bytemuck::cast_slice(&radiance),
            storage,
        )?;
        let irradiance =
            transfer::buffer(device, "pbgi irradiance", views.len() as u64 * 16, storage)?;
        let params = GatherParams {
            width: layout.size().0,
            tile,
            columns: layout.columns,
            views: views.len() as u32,
        };
        let params = transfer::buffer_init(
            device,
            "pbgi gather",
            bytemuck::bytes_of(&params),
            wgpu::BufferUsages::UNIFORM,
        )?;
        let module = crate::SHADERS.module(device, "pbgi.wgsl")?;
        let convolve = Kernel::new(
            device,
            &module,
            "convolve",
            &[
                Binding::Uniform,
                Binding::StorageRead,
                Binding::StorageRead,
                Binding::Storage,
            ],
            &[],
        );
        let ids = manylod
            .nearest_nodes()
            .ok_or_else(|| IndirectError::Config("the nearest-node pass is not enabled".into()))?;
        let bind = convolve.bind_buffers(device, &[&params, ids, &radiance, &irradiance]);
        Ok(Self {
            manylod,
            convolve,
            bind,
            irradiance,
            views: views.len() as u32,
            tile,
            frame: None,
            radiance,
            lighting: None,
        })
    }

    /// From now on each [`GpuGather::encode`] lights the surfels on the GPU first (the
    /// radiance of `lit` was for the lights at set-up): every leaf's direct light from
    /// `lights` by shadow rays through `scene`'s triangles, then the nodes' means, level by
    /// level (`pbgi_lighting.wgsl`, [`LitPoints::new`]'s twin). Move the lights with
    /// [`GpuGather::set_lights`].
    pub fn light_on_gpu(
        &mut self,
        device: &wgpu::Device,
        scene: &Scene,
        lit: &LitPoints,
        lights: &[GpuLight],
    ) -> Result<(), IndirectError> {
        let n = lit.bsh.leaf_count();
        if lit.leaf_albedos.len() != n {
            return Err(IndirectError::Config(
                "lighting on the GPU needs the surfels' albedos (points from LitPoints::new)"
                    .into(),
            ));
        }
        let (positions, indices) = scene_mesh(scene);
        let rays = tiled_shading::gpu::shadows::GpuRays::new(
            device,
            &RayBvh::new((&positions, &indices))?,
            tiled_shading::rays::RayParams::default(),
        )?;
        let light_capacity = lights.len().max(1);
        let lights_buffer = transfer::buffer_init(
            device,
            "pbgi lights",
            bytemuck::cast_slice(&pad_lights(lights, light_capacity)),
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        )?;
        let albedos = transfer::buffer_init(
            device,
            "pbgi leaf albedos",
            bytemuck::cast_slice(&lit.leaf_albedos),
            wgpu::BufferUsages::STORAGE,
        )?;
        let reach = 2.0 * scene.bounds().diagonal().max(1e-6);
        // The leaves, then levels depth − 1 .. 0 (level l: nodes 2^l − 1 .. 2^(l+1) − 1).
        let ranges: Vec<(u32, u32)> = std::iter::once((n as u32 - 1, n as u32))
            .chain(
                (0..lit.bsh.depth)
                    .rev()
                    .map(|l| ((1u32 << l) - 1, 1u32 << l)),
            )
            .collect();
        let params = ranges
            .iter()
            .map(|&(first, count)| {
                let p = LightingParams {
                    first,
                    count,
                    lights: lights.len() as u32,
                    reach,
                };
                let buffer = transfer::buffer_init(
                    device,
                    "pbgi lighting",
                    bytemuck::bytes_of(&p),
                    wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                )?;
                Ok((buffer, p))
            })
            .collect::<Result<Vec<_>, IndirectError>>()?;
        let specialisation = ::gpu::shader::Specialisation::default()
            .set("RAY_GROUP", "0u")
            .set("RAY_NODES", "5u")
            .set("RAY_TRIANGLES", "6u");
        let module = crate::SHADERS.module_with(device, "pbgi_lighting.wgsl", &specialisation)?;
        let leaves = Kernel::new(
            device,
            &module,
            "light_leaves",
            &[
                Binding::Uniform,
                Binding::StorageRead,
                Binding::StorageRead,
                Binding::StorageRead,
                Binding::Storage,
                Binding::StorageRead,
                Binding::StorageRead,
            ],
            &[],
        );
        let leaves_bind = leaves.bind_buffers(
            device,
            &[
                &params[0].0,
                &self.manylod.nodes,
                &albedos,
                &lights_buffer,
                &self.radiance,
                &rays.nodes,
                &rays.triangles,
            ],
        );
        let average = Kernel::numbered(
            device,
            &module,
            "average",
            &[(0, Binding::Uniform), (4, Binding::Storage)],
        );
        let average_binds = params[1..]
            .iter()
            .map(|(buffer, _)| average.bind_buffers(device, &[buffer, &self.radiance]))
            .collect();
        self.lighting = Some(GpuLighting {
            _rays: rays,
            lights: lights_buffer,
            light_capacity,
            params,
            leaves: (leaves, leaves_bind),
            average: (average, average_binds),
        });
        Ok(())
    }

    /// Replaces the lights the surfels are lit by on the GPU (at most as many as at
    /// [`GpuGather::light_on_gpu`]).
    pub fn set_lights(
        &self,
        queue: &wgpu::Queue,
        lights: &[GpuLight],
    ) -> Result<(), IndirectError> {
        let Some(l) = &self.lighting else {
            return Err(IndirectError::Config(
                "the surfels are not lit on the GPU (light_on_gpu)".into(),
            ));
        };
        if lights.len() > l.light_capacity {
            return Err(IndirectError::Config(format!(
                "{} lights for surfels lit by at most {}",
                lights.len(),
                l.light_capacity
            )));
        }
        queue.write_buffer(
            &l.lights,
            0,
            bytemuck::cast_slice(&pad_lights(lights, l.light_capacity)),
        );
        for (buffer, p) in &l.params {
            let p = LightingParams {
                lights: lights.len() as u32,
                ..*p
            };
            queue.write_buffer(buffer, 0, bytemuck::bytes_of(&p));
        }
        Ok(())
    }

    /// Every node's exit radiance (`vec4<f32>`, RGB; heap order), e.g. to read back.
    pub fn radiance(&self) -> &wgpu::Buffer {
        &self.radiance
    }

    /// From now on each [`GpuGather::encode`] makes the views of `grid`'s receivers from the
    /// G-buffer first (`frame` the `gbuffer/frame.wgsl` uniform, `textures` its view depth and
    /// normals: no receiver crosses to the CPU), and after the convolution upsamples the
    /// irradiance into `output` (the frame's size, `interleave::gpu::IRRADIANCE_FORMAT`,
    /// `STORAGE_BINDING`): the indirect diffuse `E/π` ([`upsample`]'s twin). The gather must
    /// have been made for `grid.len()` receivers.
    pub fn bind_frame(
        &mut self,
        device: &wgpu::Device,
        grid: &ReceiverGrid,
        frame: &wgpu::Buffer,
        textures: gbuffer::gpu::GBufferTextures<'_>,
        output: &wgpu::Texture,
    ) -> Result<(), IndirectError> {
        if grid.len() != self.views as usize {
            return Err(IndirectError::Config(format!(
                "a grid of {} receivers for a gather of {}",
                grid.len(),
                self.views
            )));
        }
        let (w, h) = grid.size;
        ::gpu::kernel::check_texture(
            "the view depth",
            textures.linear_depth,
            (w, h),
            gbuffer::LINEAR_DEPTH_FORMAT,
            wgpu::TextureUsages::TEXTURE_BINDING,
        )?;
        ::gpu::kernel::check_texture(
            "the normals",
            textures.normal,
            (w, h),
            gbuffer::NORMAL_FORMAT,
            wgpu::TextureUsages::TEXTURE_BINDING,
        )?;
        ::gpu::kernel::check_texture(
            "the PBGI output",
            output,
            (w, h),
            interleave::gpu::IRRADIANCE_FORMAT,
            wgpu::TextureUsages::STORAGE_BINDING,
        )?;
        let params = GridParams {
            stride: grid.stride,
            columns: grid.columns,
            rows: grid.rows,
            tile: self.tile,
        };
        let params = transfer::buffer_init(
            device,
            "pbgi grid",
            bytemuck::bytes_of(&params),
            wgpu::BufferUsages::UNIFORM,
        )?;
        let view = |t: &wgpu::Texture| t.create_view(&Default::default());
        let (depth, normal, out) = (
            view(textures.linear_depth),
            view(textures.normal),
            view(output),
        );
        let gbuffer_bindings = [
            Binding::Uniform,
            Binding::Uniform,
            Binding::TextureUnfilterable,
            Binding::TextureUint,
        ];
        let kernel = |file: &str, entry: &str, last: &[Binding]| -> Result<Kernel, IndirectError> {
            let module = crate::SHADERS.module(device, file)?;
            let bindings: Vec<Binding> = gbuffer_bindings.iter().chain(last).copied().collect();
            Ok(Kernel::new(device, &module, entry, &bindings, &[]))
        };
        let common = [
            frame.as_entire_binding(),
            params.as_entire_binding(),
            wgpu::BindingResource::TextureView(&depth),
            wgpu::BindingResource::TextureView(&normal),
        ];
        let receivers = kernel("pbgi_receivers.wgsl", "receivers", &[Binding::Storage])?;
        let receivers_bind = receivers.bind(
            device,
            &[
                &common[..],
                &[self.manylod.views_buffer().as_entire_binding()],
            ]
            .concat(),
        );
        let upsample = kernel(
            "pbgi_upsample.wgsl",
            "upsample",
            &[
                Binding::StorageRead,
                Binding::StorageTexture(interleave::gpu::IRRADIANCE_FORMAT),
            ],
        )?;
        let upsample_bind = upsample.bind(
            device,
            &[
                &common[..],
                &[
                    self.irradiance.as_entire_binding(),
                    wgpu::BindingResource::TextureView(&out),
                ],
            ]
            .concat(),
        );
        self.frame = Some(BoundFrame {
            receivers: (receivers, receivers_bind),
            upsample: (upsample, upsample_bind),
            size: (w, h),
        });
        Ok(())
    }

    /// The views of the receivers (`manylod`'s `View` layout), e.g. to read back.
    pub fn views_buffer(&self) -> &wgpu::Buffer {
        self.manylod.views_buffer()
    }

    /// Moves the receivers (the same count).
    pub fn set_receivers(
        &self,
        queue: &wgpu::Queue,
        receivers: &[(Vec3, Vec3)],
    ) -> Result<(), IndirectError> {
        Ok(self
            .manylod
            .set_views(queue, &gather_views(receivers, self.tile))?)
    }

    /// Records the surfels' lighting where it runs on the GPU (timed `pbgi lighting`), the
    /// receivers' views where a frame is bound (`pbgi receivers`), the cut
    /// (`cut`), the splat with nearest nodes (`splat`), the convolution (`pbgi convolve`) and
    /// the upsampling into the frame's output (`pbgi upsample`).
    pub fn encode(&mut self, encoder: &mut wgpu::CommandEncoder, timer: Option<&PassTimer>) {
        if let Some(l) = &self.lighting {
            let groups = |count: u32| Workgroups::linear(count, 64);
            let mut dispatches = vec![
                l.leaves
                    .0
                    .dispatch(&l.leaves.1, groups(l.params[0].1.count)),
            ];
            for (bind, (_, p)) in l.average.1.iter().zip(&l.params[1..]) {
                dispatches.push(l.average.0.dispatch(bind, groups(p.count)));
            }
            Passes::new()
                .pass("pbgi lighting", dispatches)
                .encode(encoder, timer);
        }
        if let Some(f) = &self.frame {
            let (kernel, bind) = &f.receivers;
            Passes::one(
                "pbgi receivers",
                &kernel.pipeline,
                vec![bind.clone()],
                Workgroups::Direct([self.views.div_ceil(64), 1, 1]),
            )
            .encode(encoder, timer);
        }
        self.manylod.encode_cut(encoder, CutKind::Basic, timer);
        self.manylod.encode_splat(encoder, timer);
        Passes::one(
            "pbgi convolve",
            &self.convolve.pipeline,
            vec![self.bind.clone()],
            Workgroups::linear(self.views, 1),
        )
        .encode(encoder, timer);
        if let Some(f) = &self.frame {
            let (kernel, bind) = &f.upsample;
            Passes::one(
                "pbgi upsample",
                &kernel.pipeline,
                vec![bind.clone()],
                Workgroups::covering(f.size.0, f.size.1, 8),
            )
            .encode(encoder, timer);
        }
    }

    /// The irradiance of every receiver (`vec4<f32>`, RGB), after [`Self::encode`].
    pub fn irradiance(&self) -> &wgpu::Buffer {
        &self.irradiance
    }

    /// Whether the last cut fitted its lists (an error naming the capacity when not).
    pub fn check(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> Result<(), IndirectError> {
        Ok(self.manylod.check_lists(device, queue)?)
    }

    /// Reads the irradiance back (after checking the cut lists held the cut).
    pub fn read_irradiance(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<Vec<Vec3>, IndirectError> {
        self.manylod.check_lists(device, queue)?;
        read_rgb(device, queue, &self.irradiance)
    }
}

/// The RGB of a buffer of `vec4<f32>`, read back.
pub(crate) fn read_rgb(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    buffer: &wgpu::Buffer,
) -> Result<Vec<Vec3>, IndirectError> {
    let words: Vec<[f32; 4]> = transfer::read_pod(device, queue, buffer)?;
    Ok(words.iter().map(|w| Vec3::new(w[0], w[1], w[2])).collect())
}

/// `lights` followed by zeroed lights up to `capacity` (a binding is never empty).
fn pad_lights(lights: &[GpuLight], capacity: usize) -> Vec<GpuLight> {
    let mut padded = lights.to_vec();
    padded.resize(capacity, bytemuck::Zeroable::zeroed());
    padded
}

/// `cos θ · dω` of texel `(x, y)` of a `tile`-texel paraboloid view (0 outside the disc):
/// `(1 − r²)/(1 + r²) · 4/(1 + r²)² · (2/tile)²` at the texel centre's radius `r`. The weights
/// of a tile sum to π as the tile grows (the cosine-weighted hemisphere).
pub fn texel_weight(x: u32, y: u32, tile: u32) -> f32 {
    let side = 2.0 / tile as f32;
    let u = (x as f32 + 0.5) * side - 1.0;
    let v = (y as f32 + 0.5) * side - 1.0;
    let r2 = u * u + v * v;
    if r2 >= 1.0 {
        return 0.0;
    }
    let k = 1.0 + r2;
    (1.0 - r2) / k * 4.0 / (k * k) * side * side
}
