//! Per-object reflection and refraction maps through many-view cuts (Holländer 2013 §3.6.1,
//! Fig. 3.19: "an environment map per object by finding cuts in the BVH in parallel"). Every
//! mesh with a mirror ([`is_mirror`]) or glass ([`is_glass`]) material gets a probe at the
//! centre of its bounds; each probe is a
//! dual-paraboloid map — two paraboloid views of `tile²` texels around +Y and −Y — of the lit
//! surfels of point-based GI ([`LitPoints`]): the views' cut, the splat with nearest nodes,
//! then each texel takes its nearest node's exit radiance. The probe's own object is not in
//! its maps when it is convex: seen from inside, all its surfaces face away and the cut culls
//! them (a concave object sees its own inner faces).
//!
//! In the frame, every pixel of a probed material reflects its view ray about its normal and
//! reads the map of the nearest probe of its material (one probe per mesh, so give objects
//! that share a material their own meshes): Schlick's Fresnel `F` times that radiance is the
//! pixel's reflection. Glass adds what it transmits: `(1 − F) · transmission · tint` times the
//! map's radiance along the view ray refracted into the surface (`refract(−v, n, 1/ior)`, the
//! classic environment-mapped refraction through one interface: the ray's way out of the
//! object is not traced). The composition adds both to the indirect specular light.
//!
//! [`LitPoints::reflection_maps`] and [`reflect`] are the CPU twins of `reflections.wgsl`.

use ::gpu::PassTimer;
use ::gpu::kernel::{Binding, Kernel, Passes, Workgroups};
use ::gpu::transfer;
use bytemuck::Zeroable;
use glam::{Vec2, Vec3};
use manylod::{
    AtlasLayout, CutProblem, View,
    gpu::{CutKind, GpuManyLod},
    splat::NO_NODE,
};
use rayon::prelude::*;
use scene::{Material, Scene};

use crate::{IndirectError, pbgi::LitPoints};

/// A material reflects through probes when it is this metallic or more…
pub const MIRROR_METALLIC: f32 = 0.9;
/// …and this rough or less.
pub const MIRROR_ROUGHNESS: f32 = 0.2;

/// Whether `m` is a mirror: metallic ≥ [`MIRROR_METALLIC`], roughness ≤ [`MIRROR_ROUGHNESS`].
pub fn is_mirror(m: &Material) -> bool {
    m.metallic >= MIRROR_METALLIC && m.roughness <= MIRROR_ROUGHNESS
}

/// Whether `m` is glass: it transmits ([`Material::transmission`] > 0) and is no rougher than
/// [`MIRROR_ROUGHNESS`].
pub fn is_glass(m: &Material) -> bool {
    m.transmission > 0.0 && m.roughness <= MIRROR_ROUGHNESS
}

/// Whether meshes of `m` get probes: mirrors and glass.
pub fn has_probes(m: &Material) -> bool {
    is_mirror(m) || is_glass(m)
}

/// A material's row in the probes' table (`reflections.wgsl`'s `ProbeMaterial`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ProbeMaterial {
    /// Its first probe in [`Probes::centers`].
    pub first: u32,
    /// Its number of probes (0: neither mirror nor glass).
    pub count: u32,
    /// [`Material::transmission`] (0 unless glass).
    pub transmission: f32,
    /// [`Material::ior`].
    pub ior: f32,
    /// The base colour (RGB, then 0): the tint of the light glass transmits.
    pub tint: [f32; 4],
}

/// The reflection probes of a scene: one per mesh with a mirror or glass material, grouped by
/// material.
#[derive(Clone, Debug, PartialEq)]
pub struct Probes {
    /// Probe centres (the meshes' bounds' centres), material by material.
    pub centers: Vec<Vec3>,
    /// Per material index, its probes and what the reflect pass needs of it.
    pub materials: Vec<ProbeMaterial>,
}

impl Probes {
    /// The probes of `scene`'s mirror and glass meshes.
    pub fn of_scene(scene: &Scene) -> Self {
        let mut centers = Vec::new();
        let mut materials = Vec::with_capacity(scene.materials.len());
        for (m, material) in scene.materials.iter().enumerate() {
            let first = centers.len() as u32;
            let glass = is_glass(material);
            materials.push(ProbeMaterial {
                first,
                count: 0,
                transmission: if glass { material.transmission } else { 0.0 },
                ior: material.ior,
                tint: material.base_color.truncate().extend(0.0).to_array(),
            });
            if !(glass || is_mirror(material)) {
                continue;
            }
            for mesh in scene
                .meshes
                .iter()
                .filter(|mesh| mesh.material as usize == m)
            {
                let bounds = mesh
                    .positions
                    .iter()
                    .fold(scene::Aabb::EMPTY, |b, &p| b.grow(p));
                if !mesh.positions.is_empty() {
                    centers.push(bounds.center());
                }
            }
            materials[m].count = centers.len() as u32 - first;
        }
        Self { centers, materials }
    }

    /// The number of probes.
    pub fn len(&self) -> usize {
        self.centers.len()
    }

    /// Whether there is none.
    pub fn is_empty(&self) -> bool {
        self.centers.is_empty()
    }

    /// The probe a point of material `material` reflects from: the nearest of its material's.
    pub fn nearest(&self, material: u32, p: Vec3) -> Option<usize> {
        let ProbeMaterial { first, count, .. } = *self.materials.get(material as usize)?;
        (first..first + count).map(|i| i as usize).min_by(|&a, &b| {
            p.distance_squared(self.centers[a])
                .total_cmp(&p.distance_squared(self.centers[b]))
        })
    }
}

/// The two paraboloid views of every probe: around +Y (view `2i`) and −Y (view `2i + 1`).
pub fn probe_views(centers: &[Vec3], tile: u32) -> Vec<View> {
    centers
        .iter()
        .flat_map(|&position| {
            [Vec3::Y, Vec3::NEG_Y].map(|normal| View::Paraboloid {
                position,
                normal,
                size: tile,
            })
        })
        .collect()
}

/// Where direction `d` (unit) lands in a probe's dual-paraboloid map: the view (0: around +Y,
/// 1: around −Y) and the texel position in pixels — the projection [`View::splat`] uses.
pub fn map_texel(d: Vec3, tile: u32) -> (usize, Vec2) {
    let half = usize::from(d.y < 0.0);
    let normal = if half == 0 { Vec3::Y } else { Vec3::NEG_Y };
    let (t, b) = manylod::view::paraboloid_frame(normal);
    let z = d.dot(normal).max(0.0);
    let uv = Vec2::new(d.dot(t), d.dot(b)) / (1.0 + z);
    (half, (uv * 0.5 + 0.5) * tile as f32)
}

impl LitPoints {
    /// The reflection maps of probes at `centers`: `2 · tile²` texels per probe (its two views,
    /// row-major), each its nearest node's exit radiance, zero where no node lands.
    pub fn reflection_maps(&self, centers: &[Vec3], tile: u32) -> Result<Vec<Vec3>, IndirectError> {
        let views = probe_views(centers, tile);
        let problem = CutProblem {
            bsh: &self.bsh,
            views: &views,
            epsilon: self.config().epsilon,
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
        Ok(views
            .par_iter()
            .zip(&drawn)
            .flat_map_iter(|(view, drawn)| {
                manylod::splat::nearest_nodes(&self.bsh.nodes, view, drawn, &layout)
                    .into_iter()
                    .map(|n| match n {
                        NO_NODE => Vec3::ZERO,
                        n => self.radiance[n as usize],
                    })
            })
            .collect())
    }
}

/// A map's radiance in direction `d`: its texel's (nearest texel, clamped to the tile).
pub fn map_lookup(maps: &[Vec3], probe: usize, d: Vec3, tile: u32) -> Vec3 {
    let (half, p) = map_texel(d, tile);
    let last = tile as f32 - 1.0;
    let (x, y) = (p.x.floor().clamp(0.0, last), p.y.floor().clamp(0.0, last));
    maps[(2 * probe + half) * (tile * tile) as usize + (y as u32 * tile + x as u32) as usize]
}

/// Schlick's Fresnel of a surface of `albedo`, `metallic`, specular factor `specular` and
/// index of refraction `ior` seen under `cos_theta`: `F0 = mix(((ior − 1)/(ior + 1))² ·
/// specular, albedo, metallic)` (glTF's dielectric; 0.04 · specular at the default ior 1.5).
pub fn fresnel(albedo: Vec3, metallic: f32, (specular, ior): (f32, f32), cos_theta: f32) -> Vec3 {
    let q = (ior - 1.0) / (ior + 1.0);
    let dielectric = q * q * specular;
    let f0 = Vec3::splat(dielectric).lerp(albedo, metallic);
    f0 + (Vec3::ONE - f0) * (1.0 - cos_theta.clamp(0.0, 1.0)).powi(5)
}

/// The reflection (and, on glass, transmission) of one G-buffer pixel (CPU twin of
/// `reflections.wgsl`'s `reflect`): zero unless its material has probes; else Fresnel × the
/// nearest probe's map in the mirrored view direction, plus on glass `(1 − F) · transmission
/// · tint` × the map in the refracted view direction. `(position, normal, eye)` in world
/// space.
pub fn reflect(
    probes: &Probes,
    maps: &[Vec3],
    tile: u32,
    (material, albedo, metallic, specular): (u32, Vec3, f32, f32),
    (position, normal, eye): (Vec3, Vec3, Vec3),
) -> Vec3 {
    let Some(probe) = probes.nearest(material, position) else {
        return Vec3::ZERO;
    };
    let m = probes.materials[material as usize];
    let v = (eye - position).normalize_or_zero();
    let r = (2.0 * normal.dot(v) * normal - v).normalize_or_zero();
    let f = fresnel(albedo, metallic, (specular, m.ior), normal.dot(v));
    let mut out = f * map_lookup(maps, probe, r, tile);
    let t = (-v).refract(normal, 1.0 / m.ior);
    if m.transmission > 0.0 && t != Vec3::ZERO {
        let tint = Vec3::from_slice(&m.tint[..3]);
        out += (Vec3::ONE - f) * m.transmission * tint * map_lookup(maps, probe, t, tile);
    }
    out
}

#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct MapParams {
    width: u32,
    tile: u32,
    columns: u32,
    views: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct ReflectParams {
    tile: u32,
    materials: u32,
    _pad: [u32; 2],
}

/// The GPU reflection maps ([`LitPoints::reflection_maps`]' twin): the probes' views' cut and
/// nearest-node splat (`manylod::gpu::GpuManyLod`), then `reflections.wgsl`'s `resolve`: one
/// `vec4<f32>` of radiance per texel, probe by probe.
pub struct GpuReflections {
    manylod: GpuManyLod,
    resolve: (Kernel, wgpu::BindGroup),
    maps: wgpu::Buffer,
    probes: Probes,
    tile: u32,
    texels: u32,
    /// The `reflect` kernel bound to a frame ([`GpuReflections::bind_frame`]) and its size.
    frame: Option<(Kernel, wgpu::BindGroup, (u32, u32))>,
}

impl GpuReflections {
    /// Maps of `tile²` texels per view for `probes` over `lit`'s hierarchy, reading the
    /// nodes' exit radiance from `radiance` (`vec4<f32>` per node, RGB: `lit`'s uploaded, or
    /// what a `pbgi::GpuGather` lights on the GPU), with room for `capacity` node-views per
    /// cut list.
    pub fn new(
        device: &wgpu::Device,
        lit: &LitPoints,
        radiance: &wgpu::Buffer,
        (probes, tile): (&Probes, u32),
        capacity: usize,
    ) -> Result<Self, IndirectError> {
        if probes.is_empty() {
            return Err(IndirectError::Config(
                "no reflection probes: the scene has no mirror (metallic ≥ 0.9) or glass \
                 (transmission > 0) material of roughness ≤ 0.2"
                    .into(),
            ));
        }
        let views = probe_views(&probes.centers, tile);
        let layout = AtlasLayout::new(views.len(), tile, lit.far);
        let mut manylod = GpuManyLod::new(
            device,
            &lit.bsh,
            &views,
            lit.config().epsilon,
            layout,
            capacity,
            None,
        )?;
        manylod.enable_nearest_nodes(device)?;
        ::gpu::kernel::check_buffer(
            "the nodes' radiance",
            radiance,
            lit.bsh.nodes.len() as u64 * 16,
            wgpu::BufferUsages::STORAGE,
        )?;
        let texels = views.len() as u32 * tile * tile;
        let maps = transfer::buffer(
            device,
            "reflection maps",
            u64::from(texels) * 16,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        )?;
        let params = MapParams {
            width: layout.size().0,
            tile,
            columns: layout.columns,
            views: views.len() as u32,
        };
        let params = transfer::buffer_init(
            device,
            "reflection maps",
            bytemuck::bytes_of(&params),
            wgpu::BufferUsages::UNIFORM,
        )?;
        let module = crate::SHADERS.module(device, "reflections.wgsl")?;
        use Binding::{Storage as Rw, StorageRead as R, Uniform as U};
        let resolve = Kernel::numbered(
            device,
            &module,
            "resolve",
            &[(0, U), (1, R), (2, R), (3, Rw)],
        );
        let ids = manylod
            .nearest_nodes()
            .ok_or_else(|| IndirectError::Config("the nearest-node pass is not enabled".into()))?;
        let bind = resolve.bind_buffers(device, &[&params, ids, radiance, &maps]);
        Ok(Self {
            manylod,
            resolve: (resolve, bind),
            maps,
            probes: probes.clone(),
            tile,
            texels,
            frame: None,
        })
    }

    /// Binds the `reflect` pass to a frame: its camera (`frame`, the G-buffer pass's frame
    /// uniform), G-buffer and `output` (the frame's size, `rgba16float`, `STORAGE_BINDING`):
    /// every pixel's reflection ([`reflect`]'s twin), zero off mirrors.
    pub fn bind_frame(
        &mut self,
        device: &wgpu::Device,
        frame: &wgpu::Buffer,
        textures: gbuffer::gpu::GBufferTextures<'_>,
        output: &wgpu::Texture,
    ) -> Result<(), IndirectError> {
        let size = (output.width(), output.height());
        let check = |what, t: &wgpu::Texture, format, usage| {
            ::gpu::kernel::check_texture(what, t, size, format, usage)
        };
        let sampled = wgpu::TextureUsages::TEXTURE_BINDING;
        check(
            "the view depth",
            textures.linear_depth,
            gbuffer::LINEAR_DEPTH_FORMAT,
            sampled,
        )?;
        check(
            "the normals",
            textures.normal,
            gbuffer::NORMAL_FORMAT,
            sampled,
        )?;
        check(
            "the albedo",
            textures.albedo,
            gbuffer::ALBEDO_FORMAT,
            sampled,
        )?;
        check(
            "the material",
            textures.material,
            gbuffer::MATERIAL_FORMAT,
            sampled,
        )?;
        check(
            "the reflection output",
            output,
            REFLECTION_FORMAT,
            wgpu::TextureUsages::STORAGE_BINDING,
        )?;
        let probe_words: Vec<[f32; 4]> = self
            .probes
            .centers
            .iter()
            .map(|c| c.extend(0.0).to_array())
            .collect();
        let materials = &self.probes.materials;
        let none = [ProbeMaterial::zeroed()];
        let storage = wgpu::BufferUsages::STORAGE;
        let centers = transfer::buffer_init(
            device,
            "probe centres",
            bytemuck::cast_slice(&probe_words),
            storage,
        )?;
        let materials_buffer = transfer::buffer_init(
            device,
            "probe materials",
            bytemuck::cast_slice(if materials.is_empty() {
                &none
            } else {
                &materials[..]
            }),
            storage,
        )?;
        let params = ReflectParams {
            tile: self.tile,
            materials: materials.len() as u32,
            _pad: [0; 2],
        };
        let params = transfer::buffer_init(
            device,
            "reflect",
            bytemuck::bytes_of(&params),
            wgpu::BufferUsages::UNIFORM,
        )?;
        let module = crate::SHADERS.module(device, "reflections.wgsl")?;
        use Binding::{StorageRead as R, Uniform as U};
        let kernel = Kernel::numbered(
            device,
            &module,
            "reflect",
            &[
                (4, U),
                (5, U),
                (6, Binding::TextureUnfilterable),
                (7, Binding::TextureUint),
                (8, Binding::Texture),
                (9, Binding::TextureUint),
                (10, R),
                (11, R),
                (13, Binding::StorageRead),
                (12, Binding::StorageTexture(REFLECTION_FORMAT)),
            ],
        );
        let view = |t: &wgpu::Texture| t.create_view(&Default::default());
        let (depth, normal, albedo, material, out) = (
            view(textures.linear_depth),
            view(textures.normal),
            view(textures.albedo),
            view(textures.material),
            view(output),
        );
        let bind = kernel.bind(
            device,
            &[
                frame.as_entire_binding(),
                params.as_entire_binding(),
                wgpu::BindingResource::TextureView(&depth),
                wgpu::BindingResource::TextureView(&normal),
                wgpu::BindingResource::TextureView(&albedo),
                wgpu::BindingResource::TextureView(&material),
                centers.as_entire_binding(),
                materials_buffer.as_entire_binding(),
                self.maps.as_entire_binding(),
                wgpu::BindingResource::TextureView(&out),
            ],
        );
        self.frame = Some((kernel, bind, size));
        Ok(())
    }

    /// Records the probes' cut (`cut`), the splat with nearest nodes (`splat`), the maps
    /// (`reflection maps`) and, where a frame is bound, every pixel's reflection (`reflect`).
    pub fn encode(&mut self, encoder: &mut wgpu::CommandEncoder, timer: Option<&PassTimer>) {
        self.manylod.encode_cut(encoder, CutKind::Basic, timer);
        self.manylod.encode_splat(encoder, timer);
        let (kernel, bind) = &self.resolve;
        Passes::one(
            "reflection maps",
            &kernel.pipeline,
            vec![bind.clone()],
            Workgroups::linear(self.texels, 256),
        )
        .encode(encoder, timer);
        if let Some((kernel, bind, (w, h))) = &self.frame {
            Passes::one(
                "reflect",
                &kernel.pipeline,
                vec![bind.clone()],
                Workgroups::covering(*w, *h, 8),
            )
            .encode(encoder, timer);
        }
    }

    /// The maps (`vec4<f32>` per texel, RGB radiance; probe by probe, its +Y view then its −Y
    /// view, row-major).
    pub fn maps(&self) -> &wgpu::Buffer {
        &self.maps
    }

    /// Whether the last cut fitted its lists (an error naming the capacity when not).
    pub fn check(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> Result<(), IndirectError> {
        Ok(self.manylod.check_lists(device, queue)?)
    }

    /// Reads the maps back (after checking the cut lists held the cut).
    pub fn read_maps(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<Vec<Vec3>, IndirectError> {
        self.check(device, queue)?;
        crate::pbgi::read_rgb(device, queue, &self.maps)
    }
}

/// The format of the frame's reflection texture.
pub const REFLECTION_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
