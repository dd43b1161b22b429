//! A scene uploaded for the G-buffer pass.

use ::gpu::{GpuError, transfer};
use ::scene::Scene;

use super::{GBufferPass, GpuMaterial, GpuVertex};
use crate::GBufferError;

pub(super) struct Draw {
    pub(super) first_index: u32,
    pub(super) index_count: u32,
    pub(super) base_vertex: i32,
    pub(super) material: usize,
}

/// A scene uploaded for the G-buffer pass: one vertex and one index buffer, a bind group per
/// material, and the materials as a storage buffer for later passes.
pub struct GpuScene {
    pub(super) vertices: wgpu::Buffer,
    pub(super) indices: wgpu::Buffer,
    pub(super) draws: Vec<Draw>,
    pub(super) material_groups: Vec<wgpu::BindGroup>,
    /// All materials ([`GpuMaterial`]), indexed by material id.
    pub materials: wgpu::Buffer,
    /// Number of triangles.
    pub triangle_count: u64,
}

impl GpuScene {
    /// Draws every triangle, positions only (vertex buffer slot 0, no bind groups), with
    /// `instances`: for depth-only passes whose pipeline sets its own groups (shadow maps
    /// draw view `v` as instance `v`).
    pub fn draw_geometry(&self, pass: &mut wgpu::RenderPass<'_>, instances: std::ops::Range<u32>) {
        pass.set_vertex_buffer(0, self.vertices.slice(..));
        pass.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint32);
        for d in &self.draws {
            pass.draw_indexed(
                d.first_index..d.first_index + d.index_count,
                d.base_vertex,
                instances.clone(),
            );
        }
    }

    /// Uploads `scene` (textures as `Rgba8UnormSrgb`, mip 0) for `pass`.
    pub fn upload(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: &Scene,
        pass: &GBufferPass,
    ) -> Result<Self, GBufferError> {
        crate::validate_scene(scene)?;
        let mut vertices = Vec::new();
        let mut indices = Vec::new();
        let mut draws = Vec::new();
        for m in &scene.meshes {
            draws.push(Draw {
                first_index: indices.len() as u32,
                index_count: m.indices.len() as u32,
                base_vertex: vertices.len() as i32,
                material: m.material as usize,
            });
            indices.extend_from_slice(&m.indices);
            vertices.extend(
                m.positions
                    .iter()
                    .zip(&m.normals)
                    .zip(&m.uvs)
                    .map(|((p, n), uv)| GpuVertex {
                        position: p.to_array(),
                        normal: n.to_array(),
                        uv: uv.to_array(),
                    }),
            );
        }
        let vertices = transfer::buffer_init(
            device,
            "scene vertices",
            bytemuck::cast_slice(&vertices),
            wgpu::BufferUsages::VERTEX,
        )?;
        let indices = transfer::buffer_init(
            device,
            "scene indices",
            bytemuck::cast_slice(&indices),
            wgpu::BufferUsages::INDEX,
        )?;

        let white = ::scene::Texture {
            name: "white".into(),
            width: 1,
            height: 1,
            rgba8: vec![255; 4],
            sampler: Default::default(),
        };
        let textures = scene
            .textures
            .iter()
            .map(|t| upload_texture(device, queue, t))
            .collect::<Result<Vec<_>, _>>()?;
        let white = upload_texture(device, queue, &white)?;
        let gpu_materials: Vec<GpuMaterial> = scene
            .materials
            .iter()
            .enumerate()
            .map(|(i, m)| GpuMaterial::new(m, i as u32))
            .collect();
        let material_groups = scene
            .materials
            .iter()
            .zip(&gpu_materials)
            .map(|(m, g)| {
                let uniform = transfer::buffer_init(
                    device,
                    "material",
                    bytemuck::bytes_of(g),
                    wgpu::BufferUsages::UNIFORM,
                )?;
                let texture = m
                    .base_color_texture
                    .map_or(&white, |t| &textures[t.texture as usize]);
                let view = texture.create_view(&Default::default());
                Ok(pass.material_layout.bind(
                    device,
                    &[
                        uniform.as_entire_binding(),
                        wgpu::BindingResource::TextureView(&view),
                        wgpu::BindingResource::Sampler(&pass.sampler),
                    ],
                ))
            })
            .collect::<Result<Vec<_>, GpuError>>()?;
        let materials = transfer::buffer_init(
            device,
            "materials",
            bytemuck::cast_slice(&gpu_materials),
            wgpu::BufferUsages::STORAGE,
        )?;
        Ok(Self {
            vertices,
            indices,
            draws,
            material_groups,
            materials,
            triangle_count: scene.triangle_count() as u64,
        })
    }
}

fn upload_texture(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    t: &::scene::Texture,
) -> Result<wgpu::Texture, GpuError> {
    transfer::check_texture_size(device, &format!("texture {:?}", t.name), t.width, t.height)?;
    transfer::texture_init(
        device,
        queue,
        &t.name,
        t.width,
        t.height,
        wgpu::TextureFormat::Rgba8UnormSrgb,
        wgpu::TextureUsages::TEXTURE_BINDING,
        &t.rgba8,
    )
}
