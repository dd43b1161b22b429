//! Shading of interleaved samples (§4.3): `shade.wgsl`.

use gbuffer::Image;

use crate::{InterleaveError, SplitLayout};

use super::{check_size, per_texel, to_f16};

/// One light of [`shade_subsets`]: a directional light (unit `direction` towards the light).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SubsetLight {
    /// Unit vector towards the light (w unused).
    pub direction: [f32; 4],
    /// Irradiance at normal incidence (w unused).
    pub color: [f32; 4],
}

/// §4.3 shading of interleaved samples, the crate's probe shader (`shade.wgsl`): pixel (x, y)
/// receives only the lights of its sub-buffer's subset s = (y mod m)·n + (x mod n), lights
/// `s·k .. s·k + k` with k = lights.len() / (n·m): E = Σ max(0, n·l) · colour. Pixels with no
/// surface (linear depth 0) get 0. Returns the gathered (interleaved) irradiance, rounded to f16.
pub fn shade_subsets(
    linear_depth: &Image<f32>,
    normal: &Image<u32>,
    lights: &[SubsetLight],
    layout: &SplitLayout,
) -> Result<Image<[f32; 4]>, InterleaveError> {
    check_size("linear depth", linear_depth, layout.width, layout.height)?;
    check_size("normal image", normal, layout.width, layout.height)?;
    let per_subset = crate::gpu::lights_per_subset(lights.len(), layout.pattern)?;
    Ok(per_texel(layout.width, layout.height, |x, y| {
        if linear_depth.get(x, y) == 0.0 {
            return [0.0; 4];
        }
        let nrm = gbuffer::normal::unpack_octahedral(normal.get(x, y));
        let (i, j) = layout.sub_buffer_of(x, y);
        let first = ((j * layout.pattern.n + i) * per_subset) as usize;
        let mut e = [0.0f32, 0.0, 0.0, 1.0];
        for light in &lights[first..first + per_subset as usize] {
            let d = glam::Vec3::from_slice(&light.direction[..3]);
            let cos = nrm.dot(d).max(0.0);
            for (e, c) in e.iter_mut().zip(&light.color[..3]) {
                *e += cos * c;
            }
        }
        to_f16(e)
    }))
}
