//! A scene uploaded for the G-buffer pass.

use ::gpu::{GpuError, transfer};
use ::scene::{AlphaMode, Scene};

use super::{GBufferPass, GpuAttributes, GpuMaterial, MaterialTextures};
use crate::{GBufferError, TextureOptions};

/// The fixed-function state a draw needs from its material.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(super) struct DrawState {
    /// Back faces culled (a one-sided material, glTF `doubleSided: false`).
    pub(super) cull: bool,
    /// Fragments discarded by alpha (`MASK` or `BLEND`): the z-prepass needs a fragment stage.
    pub(super) alpha_tested: bool,
    /// An alpha-blended material (`BLEND`).
    pub(super) blended: bool,
}

/// How the G-buffer passes draw alpha-blended (`BLEND`) materials.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BlendedSurfaces {
    /// Into the G-buffer, each fragment kept with probability alpha by a 4 × 4 ordered dither
    /// (stochastic transparency: right on average over a pixel block, in every stage).
    #[default]
    Dithered,
    /// Not at all: a forward pass draws them over the composed frame
    /// ([`GBufferPass::draw_blended`]).
    Forward,
}

impl BlendedSurfaces {
    /// The command-line name (`dithered`, `forward`).
    pub fn name(self) -> &'static str {
        match self {
            Self::Dithered => "dithered",
            Self::Forward => "forward",
        }
    }
}

impl std::fmt::Display for BlendedSurfaces {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for BlendedSurfaces {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        [Self::Dithered, Self::Forward]
            .into_iter()
            .find(|b| b.name() == s)
            .ok_or_else(|| {
                format!("unknown way to draw blended surfaces {s:?} (dithered, forward)")
            })
    }
}

pub(super) struct Draw {
    pub(super) first_index: u32,
    pub(super) index_count: u32,
    pub(super) base_vertex: i32,
    pub(super) material: usize,
    pub(super) state: DrawState,
    /// The mesh's bounding box at upload, lower and upper corner (the order of blended
    /// draws, [`GpuScene::pixels_per_triangle`]).
    pub(super) bounds: [glam::Vec3; 2],
    /// `DrawIndexedIndirect` arguments the G-buffer passes draw this mesh with instead
    /// ([`GpuScene::draw_indirect`]).
    pub(super) indirect: Option<wgpu::Buffer>,
}

/// A material and the indices in [`MaterialTextures::all`] of its five textures (WGSL
/// `MaterialEntry` of `gbuffer/resolve_bindless.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(super) struct MaterialEntry {
    material: GpuMaterial,
    /// Base colour, metallic-roughness, normal, occlusion, emissive.
    textures: [u32; 5],
    _pad: [u32; 3],
}

/// A scene uploaded for the G-buffer pass: positions (vertex buffer slot 0) and the other
/// attributes ([`GpuAttributes`], slot 1), one index buffer, the textures with their mip
/// chains ([`MaterialTextures`]) and a bind group per material.
pub struct GpuScene {
    pub(super) positions: wgpu::Buffer,
    pub(super) attributes: wgpu::Buffer,
    pub(super) indices: wgpu::Buffer,
    pub(super) draws: Vec<Draw>,
    pub(super) material_groups: Vec<wgpu::BindGroup>,
    /// Every material in one binding ([`MaterialEntry`] per material, storage): what
    /// reaches every material from one kernel (the visibility buffer's one-dispatch resolve).
    pub(super) material_table: wgpu::Buffer,
    pub(super) blended: BlendedSurfaces,
    /// The textures the materials read.
    pub textures: MaterialTextures,
    /// Number of triangles.
    pub triangle_count: u64,
}

impl GpuScene {
    /// Draws every triangle, positions only (vertex buffer slot 0, no bind groups), with
    /// `instances`: for depth-only passes whose pipeline sets its own groups (shadow maps
    /// draw view `v` as instance `v`). Every surface is drawn, whatever its material's
    /// sides and alpha.
    pub fn draw_geometry(&self, pass: &mut wgpu::RenderPass<'_>, instances: std::ops::Range<u32>) {
        pass.set_vertex_buffer(0, self.positions.slice(..));
        pass.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint32);
        for d in &self.draws {
            pass.draw_indexed(
                d.first_index..d.first_index + d.index_count,
                d.base_vertex,
                instances.clone(),
            );
        }
    }

    /// Sets how the G-buffer passes draw alpha-blended materials (dithered by default).
    pub fn set_blended(&mut self, blended: BlendedSurfaces) {
        self.blended = blended;
    }

    /// How the G-buffer passes draw alpha-blended materials.
    pub fn blended(&self) -> BlendedSurfaces {
        self.blended
    }

    /// Whether some drawn mesh has an alpha-blended material.
    pub fn has_blended(&self) -> bool {
        self.draws
            .iter()
            .any(|d| d.state.blended && d.index_count > 0)
    }

    /// The vertex buffers: positions (`[f32; 3]` a vertex) and [`GpuAttributes`], with
    /// `STORAGE | COPY_SRC` usage too, for kernels that move them (skinning, subdivision).
    pub fn vertex_buffers(&self) -> [&wgpu::Buffer; 2] {
        [&self.positions, &self.attributes]
    }

    /// The index buffer (`u32`, `INDEX | COPY_DST | STORAGE`) and mesh `mesh`'s range in it (first
    /// index, index count): kernels that rewrite its triangles copy them there.
    pub fn indices(&self, mesh: usize) -> Option<(&wgpu::Buffer, u32, u32)> {
        self.draws
            .get(mesh)
            .map(|d| (&self.indices, d.first_index, d.index_count))
    }

    /// Makes the G-buffer passes draw mesh `mesh` with `draw_indexed_indirect` from `args`
    /// (`INDIRECT`; index count, 1, its first index, its base vertex, 0 — a kernel writes the
    /// count): a mesh whose triangles a kernel appends each frame (adaptive subdivision).
    /// Instanced geometry passes (shadow maps) still draw all its index slots, so the slots
    /// past the count must be degenerate.
    pub fn draw_indirect(&mut self, mesh: usize, args: wgpu::Buffer) {
        if let Some(d) = self.draws.get_mut(mesh) {
            d.indirect = Some(args);
        }
    }

    /// Stops drawing mesh `mesh` (its index in [`Scene::meshes`]) in every pass: a control
    /// mesh whose subdivision surface is drawn instead. Its vertices stay (kernels read them).
    pub fn hide(&mut self, mesh: usize) {
        if let Some(d) = self.draws.get_mut(mesh) {
            self.triangle_count -= u64::from(d.index_count / 3);
            d.index_count = 0;
        }
    }

    /// Per mesh (in [`Scene::meshes`]' order), the pixels its triangles cover on average seen
    /// through `frame`: the screen rectangle of its bounding box at upload, clipped to the
    /// viewport, over its triangle count (a whole viewport where the box reaches behind the
    /// eye; 0 for a hidden mesh). An estimate, first of all for ranking meshes — large
    /// triangles suit the hardware rasteriser, small ones the compute rasteriser — that
    /// ignores occlusion and the mesh's shape within its box; the box of meshes a kernel moves
    /// (skinning, subdivision) is the one at upload.
    pub fn pixels_per_triangle(&self, frame: &crate::Frame) -> Vec<f32> {
        let (width, height) = (frame.viewport.x, frame.viewport.y);
        self.draws
            .iter()
            .map(|d| {
                let triangles = d.index_count / 3;
                if triangles == 0 {
                    return 0.0;
                }
                let [lo, hi] = d.bounds;
                let mut screen = [glam::Vec2::splat(f32::MAX), glam::Vec2::splat(f32::MIN)];
                for corner in 0..8 {
                    let p = glam::Vec3::select(
                        glam::BVec3::new(corner & 1 != 0, corner & 2 != 0, corner & 4 != 0),
                        hi,
                        lo,
                    );
                    let clip = frame.view_proj * p.extend(1.0);
                    if clip.w <= 0.0 {
                        return width * height / triangles as f32;
                    }
                    let ndc = glam::Vec2::new(clip.x, clip.y) / clip.w;
                    screen[0] = screen[0].min(ndc);
                    screen[1] = screen[1].max(ndc);
                }
                let lo = (screen[0].max(glam::Vec2::NEG_ONE) + 1.0) * 0.5;
                let hi = (screen[1].min(glam::Vec2::ONE) + 1.0) * 0.5;
                let extent = (hi - lo).max(glam::Vec2::ZERO) * glam::Vec2::new(width, height);
                extent.x * extent.y / triangles as f32
            })
            .collect()
    }

    /// The first vertex of mesh `mesh` (its index in [`Scene::meshes`]) in the vertex buffers.
    pub fn base_vertex(&self, mesh: usize) -> Option<u32> {
        self.draws.get(mesh).map(|d| d.base_vertex as u32)
    }

    /// Uploads `scene` for `pass` with the default [`TextureOptions`].
    pub fn upload(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: &Scene,
        pass: &GBufferPass,
    ) -> Result<Self, GBufferError> {
        Self::upload_with(device, queue, scene, pass, &TextureOptions::default())
    }

    /// Uploads `scene` for `pass`, its textures filtered as `options` say.
    pub fn upload_with(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: &Scene,
        pass: &GBufferPass,
        options: &TextureOptions,
    ) -> Result<Self, GBufferError> {
        crate::validate_scene(scene)?;
        options.validate()?;
        let mut positions = Vec::new();
        let mut attributes = Vec::new();
        let mut indices = Vec::new();
        let mut draws = Vec::new();
        for m in &scene.meshes {
            let material = &scene.materials[m.material as usize];
            draws.push(Draw {
                first_index: indices.len() as u32,
                index_count: m.indices.len() as u32,
                base_vertex: positions.len() as i32,
                material: m.material as usize,
                state: DrawState {
                    cull: !material.double_sided,
                    alpha_tested: material.alpha_mode != AlphaMode::Opaque,
                    blended: material.alpha_mode == AlphaMode::Blend,
                },
                bounds: bounding_box(&m.positions),
                indirect: None,
            });
            indices.extend_from_slice(&m.indices);
            positions.extend(m.positions.iter().map(|p| p.to_array()));
            attributes.extend((0..m.positions.len()).map(|i| GpuAttributes {
                normal: m.normals[i].to_array(),
                uv0: m.uvs[i].to_array(),
                uv1: m.uvs1.get(i).map_or([0.0; 2], |uv| uv.to_array()),
                tangent: m.tangents.get(i).map_or([0.0; 4], |t| t.to_array()),
                color: m.colors.get(i).map_or([1.0; 4], |c| c.to_array()),
            }));
        }
        // Kernels may move the vertices: the skinning of a scene with a rig, the per-frame
        // subdivision (and their tests read them back).
        let usage =
            wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
        let vertex_buffer =
            |label, bytes: &[u8]| transfer::buffer_init(device, label, bytes, usage);
        let positions = vertex_buffer("scene positions", bytemuck::cast_slice(&positions))?;
        let attributes = vertex_buffer("scene attributes", bytemuck::cast_slice(&attributes))?;
        let indices = transfer::buffer_init(
            device,
            "scene indices",
            bytemuck::cast_slice(&indices),
            // Kernels may rewrite a mesh's triangles (adaptive subdivision) and read them (the
            // visibility buffer's rasteriser).
            wgpu::BufferUsages::INDEX | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::STORAGE,
        )?;
        let textures = MaterialTextures::upload(device, queue, scene, options)?;
        let materials: Vec<GpuMaterial> = (scene.materials.iter().enumerate())
            .map(|(i, m)| GpuMaterial::new(m, i as u32))
            .collect();
        let mut entries: Vec<MaterialEntry> = (scene.materials.iter().zip(&materials))
            .map(|(m, &material)| MaterialEntry {
                material,
                textures: textures.indices_of(m),
                _pad: [0; 3],
            })
            .collect();
        // A binding is never empty: a scene without materials gets one zeroed entry.
        if entries.is_empty() {
            entries.push(bytemuck::Zeroable::zeroed());
        }
        let material_table = transfer::buffer_init(
            device,
            "materials",
            bytemuck::cast_slice(&entries),
            wgpu::BufferUsages::STORAGE,
        )?;
        let material_groups = scene
            .materials
            .iter()
            .zip(&materials)
            .map(|(m, gpu_material)| {
                let uniform = transfer::buffer_init(
                    device,
                    "material",
                    bytemuck::bytes_of(gpu_material),
                    wgpu::BufferUsages::UNIFORM,
                )?;
                let mut resources = vec![uniform.as_entire_binding()];
                for (role, t) in m.roles() {
                    let t = textures.for_role(role, t);
                    resources.push(wgpu::BindingResource::TextureView(&t.view));
                    resources.push(wgpu::BindingResource::Sampler(&t.sampler));
                }
                Ok(pass.material_layout.bind(device, &resources))
            })
            .collect::<Result<Vec<_>, GpuError>>()?;
        Ok(Self {
            positions,
            attributes,
            indices,
            draws,
            material_groups,
            material_table,
            blended: BlendedSurfaces::Dithered,
            textures,
            triangle_count: scene.triangle_count() as u64,
        })
    }
}

/// The lower and upper corner of the bounding box of `points` (the origin for none).
fn bounding_box(points: &[glam::Vec3]) -> [glam::Vec3; 2] {
    let Some(&first) = points.first() else {
        return [glam::Vec3::ZERO; 2];
    };
    let (lo, hi) = points
        .iter()
        .fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    [lo, hi]
}

impl Draw {
    /// The centre of the mesh's bounding box at upload.
    pub(super) fn center(&self) -> glam::Vec3 {
        (self.bounds[0] + self.bounds[1]) * 0.5
    }
}
