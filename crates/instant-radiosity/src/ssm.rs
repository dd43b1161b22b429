//! Exact VPL visibility by rasterised shadow maps — Segovia 2006's SSM (§4.3, used by the
//! physically based mode of §6.3): every VPL's hemicube (five perspective faces,
//! [`tiled_shading::shadows::hemicube_views`]) is rasterised by the hardware into one depth
//! atlas of faces ("unrolling the hemicube in a standard shadow map"), then reindexed
//! (`ssm.wgsl`, the paper's small cube map) into the VPL's paraboloid tile of the atlas the
//! ManyLoD maps fill, so the shading looks every mode up the same way
//! ([`manylod::lookup`]). Views whose faces do not fit one depth texture are rasterised and
//! reindexed batch after batch. The CPU twin is
//! [`tiled_shading::shadows::ray_cast_atlas`]: a ray through the centre of every texel.

use ::gpu::kernel::{Binding, Kernel, Workgroups};
use ::gpu::{PassTimer, transfer};
use glam::Vec3;
use manylod::{AtlasLayout, View};
use tiled_shading::gpu::shadows::ShadowMapPass;
use tiled_shading::shadows::{ShadowView, hemicube_views};

use crate::IndirectError;

/// Faces of a VPL's hemicube.
const FACES: u32 = 5;

/// Uniform block `SsmParams` of `ssm.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct SsmParams {
    first_view: u32,
    views: u32,
    face: u32,
    face_columns: u32,
    tile: u32,
    columns: u32,
    width: u32,
    far: f32,
}

/// One batch of VPLs whose hemicubes share the face atlas.
struct Batch {
    first_view: u32,
    views: u32,
    group: wgpu::BindGroup,
}

/// The rasterised shadow maps of paraboloid views: the scene's triangles, the hemicube views,
/// the face atlas and the reindexing kernel, writing into a paraboloid atlas buffer.
pub struct RasterisedMaps {
    pass: ShadowMapPass,
    views: wgpu::Buffer,
    view_count: usize,
    far: f32,
    views_group: wgpu::BindGroup,
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    index_count: u32,
    faces: wgpu::TextureView,
    face: u32,
    face_columns: u32,
    reindex: Kernel,
    batches: Vec<Batch>,
    tile: u32,
}

impl RasterisedMaps {
    /// Hemicubes of `face × face` texels for every paraboloid view of `layout` (the views'
    /// positions are their eyes), over the triangle `mesh`, reindexed into `atlas` (the
    /// layout's packed depths). Faces that do not fit the device's largest texture (or
    /// `max_bytes` of 32-bit depths) go in batches; a hemicube larger than that is an error.
    pub fn new(
        device: &wgpu::Device,
        (positions, indices): (&[Vec3], &[u32]),
        views: &[View],
        layout: AtlasLayout,
        face: u32,
        atlas: &wgpu::Buffer,
        max_bytes: Option<u64>,
    ) -> Result<Self, IndirectError> {
        layout.check(views)?;
        let max_side = device.limits().max_texture_dimension_2d;
        if face == 0 || face > max_side {
            return Err(IndirectError::Ssm(format!(
                "hemicube faces of {face} texels do not fit the device's {max_side}-texel textures"
            )));
        }
        let far = layout.far;
        let hemicubes = hemicubes(views, face, far)?;
        let pass = ShadowMapPass::new(device)?;
        let views_buffer = transfer::buffer_init(
            device,
            "hemicube views",
            bytemuck::cast_slice(&hemicubes),
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        )?;
        let views_group = pass.bind_views(device, &views_buffer);
        let vertices: Vec<[f32; 3]> = positions.iter().map(|p| p.to_array()).collect();
        let vertex_buffer = transfer::buffer_init(
            device,
            "ssm vertices",
            bytemuck::cast_slice(&vertices),
            wgpu::BufferUsages::VERTEX,
        )?;
        let index_buffer = transfer::buffer_init(
            device,
            "ssm indices",
            bytemuck::cast_slice(indices),
            wgpu::BufferUsages::INDEX,
        )?;
        // A square-ish face atlas for all faces, capped at the device's texture side.
        let per_side = max_side / face;
        let total = views.len() as u32 * FACES;
        let face_columns = ((f64::from(total)).sqrt().ceil() as u32).clamp(1, per_side);
        // At most the device's workgroups along z, one VPL each, and `max_bytes` of faces.
        let face_bytes = u64::from(face) * u64::from(face) * 4;
        let byte_faces = max_bytes.map_or(u64::MAX, |b| b / face_bytes);
        let batch_views = (u64::from(face_columns * per_side).min(byte_faces) as u32 / FACES)
            .min(device.limits().max_compute_workgroups_per_dimension)
            .max(1);
        let rows = (batch_views.min(views.len() as u32) * FACES).div_ceil(face_columns);
        if u64::from(batch_views * FACES) > u64::from(face_columns * per_side).min(byte_faces) {
            return Err(IndirectError::Ssm(format!(
                "a hemicube of {face}-texel faces does not fit the device's {max_side}-texel \
                 textures or {max_bytes:?} bytes"
            )));
        }
        let texture = transfer::allocation(device, "the hemicube face atlas", || {
            Ok::<_, IndirectError>(device.create_texture(&wgpu::TextureDescriptor {
                label: Some("hemicube faces"),
                size: wgpu::Extent3d {
                    width: face_columns * face,
                    height: rows.max(1) * face,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: tiled_shading::gpu::shadows::SHADOW_FORMAT,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                    | wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            }))
        })?;
        let faces = texture.create_view(&Default::default());
        let module = crate::SHADERS.module(device, "ssm.wgsl")?;
        use Binding::{Storage as Rw, StorageRead as R, TextureDepth as D, Uniform as U};
        let reindex = Kernel::new(device, &module, "reindex", &[R, D, U, Rw], &[]);
        let (width, _) = layout.size();
        let mut batches = Vec::new();
        for first in (0..views.len() as u32).step_by(batch_views as usize) {
            let params = SsmParams {
                first_view: first,
                views: batch_views.min(views.len() as u32 - first),
                face,
                face_columns,
                tile: layout.tile,
                columns: layout.columns,
                width,
                far,
            };
            let params_buffer = transfer::buffer_init(
                device,
                "ssm params",
                bytemuck::bytes_of(&params),
                wgpu::BufferUsages::UNIFORM,
            )?;
            let group = reindex.bind(
                device,
                &[
                    views_buffer.as_entire_binding(),
                    wgpu::BindingResource::TextureView(&faces),
                    params_buffer.as_entire_binding(),
                    atlas.as_entire_binding(),
                ],
            );
            batches.push(Batch {
                first_view: first,
                views: params.views,
                group,
            });
        }
        Ok(Self {
            pass,
            views: views_buffer,
            view_count: views.len(),
            far,
            views_group,
            vertices: vertex_buffer,
            indices: index_buffer,
            index_count: indices.len() as u32,
            faces,
            face,
            face_columns,
            reindex,
            batches,
            tile: layout.tile,
        })
    }

    /// Records every batch: its hemicube faces rasterised (one render pass, a viewport per
    /// face), then reindexed into the paraboloid tiles; timed as `SSM raster` and
    /// `SSM reindex`.
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&PassTimer>) {
        for batch in &self.batches {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("SSM raster"),
                color_attachments: &[],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &self.faces,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: timer.and_then(|t| t.render_pass("SSM raster")),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(self.pass.pipeline());
            pass.set_bind_group(0, &self.views_group, &[]);
            pass.set_vertex_buffer(0, self.vertices.slice(..));
            pass.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint32);
            for slot in 0..batch.views * FACES {
                let (x, y) = (slot % self.face_columns, slot / self.face_columns);
                let f = self.face as f32;
                pass.set_viewport(x as f32 * f, y as f32 * f, f, f, 0.0, 1.0);
                let view = batch.first_view * FACES + slot;
                pass.draw_indexed(0..self.index_count, 0, view..view + 1);
            }
            drop(pass);
            ::gpu::kernel::Passes::one(
                "SSM reindex",
                &self.reindex.pipeline,
                vec![batch.group.clone()],
                Workgroups::Direct([self.tile.div_ceil(8), self.tile.div_ceil(8), batch.views]),
            )
            .encode(encoder, timer);
        }
    }

    /// Moves the hemicubes to other paraboloid `views` (as many as made, same tile): the
    /// next [`RasterisedMaps::encode`] rasterises from there.
    pub fn set_views(&self, queue: &wgpu::Queue, views: &[View]) -> Result<(), IndirectError> {
        if views.len() != self.view_count {
            return Err(IndirectError::Ssm(format!(
                "{} views for hemicubes made for {}",
                views.len(),
                self.view_count
            )));
        }
        let hemicubes = hemicubes(views, self.face, self.far)?;
        queue.write_buffer(&self.views, 0, bytemuck::cast_slice(&hemicubes));
        Ok(())
    }

    /// How many batches the hemicubes were split into (1 where the face atlas holds them all).
    pub fn batch_count(&self) -> usize {
        self.batches.len()
    }
}

/// The hemicubes of paraboloid `views` (their positions are the eyes), `face` texels wide,
/// depth 1 at `far`: [`FACES`] views each.
fn hemicubes(views: &[View], face: u32, far: f32) -> Result<Vec<ShadowView>, IndirectError> {
    views
        .iter()
        .map(|v| match *v {
            View::Paraboloid {
                position, normal, ..
            } => Ok(hemicube_views(position, normal, (1e-4 * far, far), face)),
            View::Perspective { .. } => Err(IndirectError::Ssm(
                "rasterised shadow maps need paraboloid (VPL) views".into(),
            )),
        })
        .collect::<Result<Vec<_>, _>>()
        .map(|h| h.concat())
}
