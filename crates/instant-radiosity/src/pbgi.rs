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
//! This is the CPU reference, the specification the GPU kernels follow; it is tested against
//! the path tracer's one-bounce light (`tests/pbgi.rs`).

use glam::Vec3;
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
    config: PbgiConfig,
}

impl LitPoints {
    /// Surfels of `scene` lit by `lights` (shadow rays through the scene's triangles).
    pub fn new(
        scene: &Scene,
        lights: &[GpuLight],
        config: &PbgiConfig,
    ) -> Result<Self, IndirectError> {
        config.validate()?;
        let (positions, indices) = scene_mesh(scene);
        let count = 1usize << config.points_log2;
        let surfels = manylod::surfels::sample(&positions, &indices, count, 1)?;
        let (points, normals) = manylod::surfels::evaluate(&surfels, &positions, &indices);
        let bvh = RayBvh::new((&positions, &indices))?;
        let albedos = crate::near_field::triangle_albedos(scene);
        let reach = 2.0 * scene.bounds().diagonal().max(1e-6);
        let radiance: Vec<Vec3> = surfels
            .par_iter()
            .zip(points.par_iter().zip(&normals))
            .map(|(s, (&p, &n))| {
                let rho = crate::near_field::unpack_rgb(albedos[s.triangle as usize]);
                let e = crate::near_field::direct_irradiance(&bvh, lights, reach, (p, n));
                rho * e * std::f32::consts::FRAC_1_PI
            })
            .collect();
        let leaf_radius = manylod::surfels::disc_radius(&positions, &indices, count);
        let bsh = Bsh::build(&points, &normals, leaf_radius)?;
        Ok(Self::from_hierarchy(
            bsh,
            &radiance,
            scene.bounds().diagonal(),
            *config,
        ))
    }

    /// The hierarchy `bsh` over points whose exit radiance is `leaf_radiance` (in the points'
    /// order, before the tree's), views reaching `far`.
    pub fn from_hierarchy(bsh: Bsh, leaf_radiance: &[Vec3], far: f32, config: PbgiConfig) -> Self {
        let n = bsh.leaf_count();
        let mut radiance = vec![Vec3::ZERO; 2 * n - 1];
        for (slot, &i) in bsh.order.iter().enumerate() {
            radiance[n - 1 + slot] = leaf_radiance[i as usize];
        }
        for i in (0..n - 1).rev() {
            let c = manylod::bsh::first_child(i as u32) as usize;
            radiance[i] = (radiance[c] + radiance[c + 1]) * 0.5;
        }
        Self {
            bsh,
            radiance,
            far: far.max(1e-6),
            config,
        }
    }

    /// The irradiance at each receiver `(position, unit normal)`: its paraboloid view's texels
    /// (nearest drawn node each) weighted by [`texel_weight`].
    pub fn gather(&self, receivers: &[(Vec3, Vec3)]) -> Result<Vec<Vec3>, IndirectError> {
        let tile = self.config.tile;
        let views: Vec<View> = receivers
            .iter()
            .map(|&(p, n)| View::Paraboloid {
                position: p + n * crate::rays::ray_lift(p),
                normal: n,
                size: tile,
            })
            .collect();
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
