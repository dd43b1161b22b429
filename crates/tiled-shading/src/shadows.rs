//! Shadow maps for the direct lights: per light a set of depth views — a spot light one
//! perspective view (five cube faces around its axis when its cone is wider than
//! [`MAX_SPOT_VIEW_ANGLE`]), a point light the six faces of a cube, a hemispherical light five
//! (its back face sees nothing it lights), a directional light cascades fitted to the camera's
//! view frustum — rendered into one depth array (a layer per view, [`crate::gpu::shadows`]) and
//! looked up per pixel with a 3×3 tent filter (percentage-closer filtering, Reeves et al. 1987).
//!
//! The lookup ([`visibility`], `shadows.wgsl`'s `shadow_visibility`) is the same on the CPU
//! and the GPU: the receiver moves along its normal by `normal_offset` texels (its footprint
//! in the map, which removes the self-shadowing of surfaces at grazing angles), is projected
//! into the view that holds it (the cube face of the largest axis; the first cascade that
//! contains it), and each of the 4×4 texels under the tent compares the receiver's linear
//! depth with the stored one plus `bias` texels and the receiver's slope tolerance
//! ([`slope_texels`]: what its tilted plane gains across the tent). The penumbra this filter draws is 3 texels
//! wide (the tent's support) whatever the light's size: a hard-shadow filter, not a soft
//! shadow; area lights get their penumbrae from several shadowed points
//! (`instant_radiosity::vpl::area_lights`, see `docs/shadows.md`).
//!
//! Many lights can instead take their shadows from a ManyLoD atlas (Holländer 2013 §3.6, the
//! many-view cut that renders the VPLs' shadow maps): [`paraboloid_views`] gives a light's
//! paraboloid views, [`paraboloid_plan`] numbers them, and a light whose `shadow_count` carries
//! [`PARABOLOID_SHADOW`] is looked up there ([`manylod::lookup`], one texel, no filter).
//!
//! Or no map at all: a light whose `shadow_count` is [`RAY_SHADOW`] casts a ray through the
//! scene's BVH per receiver ([`crate::rays::RayShadows`]) — exact hard shadows, the path
//! tracer's.

use glam::{Mat4, Vec3, Vec4Swizzles};
use manylod::lookup::{self, AtlasParams};
use scene::{Aabb, Camera, orthonormal_basis};

use crate::{GpuLight, LIGHT_DIRECTIONAL, ShadingError};

/// `GpuLight::shadow_count` of a light without shadows.
pub const NO_SHADOW: u32 = 0;

/// Flag of `GpuLight::shadow_count`: the light's (count & 0xff) views are paraboloid tiles of
/// the ManyLoD atlas from tile `shadow_first`, not depth-array layers.
pub const PARABOLOID_SHADOW: u32 = 0x8000_0000;

/// `GpuLight::shadow_count` of a light whose visibility is a ray through the scene's BVH
/// ([`crate::rays::RayShadows`]); no views.
pub const RAY_SHADOW: u32 = 0x4000_0000;

/// Widest spot cone (half angle, radians) drawn into one perspective view; wider spots use
/// five cube faces around their axis.
pub const MAX_SPOT_VIEW_ANGLE: f32 = 1.0;

/// `GpuLight::kind` of a point light (`lighting.wgsl`).
const LIGHT_POINT: u32 = 0;
/// `GpuLight::kind` of a spot light.
const LIGHT_SPOT: u32 = 1;
/// `GpuLight::kind` of a hemispherical light.
const LIGHT_HEMISPHERICAL: u32 = 3;

/// Texels kept around every cube face and cascade for the filter's footprint, so a receiver
/// inside a face never reads across its edge.
const MARGIN_TEXELS: f32 = 2.0;

/// One depth view of a light, as `shadows.wgsl` reads it (96 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ShadowView {
    /// World → clip (depth 0 at `near`, 1 at `far`).
    pub view_proj: [[f32; 4]; 4],
    /// The view's axis (unit; the direction it looks along): picks the cube face.
    pub axis: [f32; 3],
    /// Near plane distance along the axis.
    pub near: f32,
    /// Far plane distance along the axis.
    pub far: f32,
    /// 1 for an orthographic view (directional cascades), 0 for a perspective one.
    pub orthographic: u32,
    /// World size of a texel: at unit distance along the axis (perspective), or everywhere
    /// (orthographic).
    pub texel: f32,
    /// Padding to 96 bytes.
    pub _pad: u32,
}

impl ShadowView {
    /// Distance along the axis of a stored depth `d` (`linear_shadow_depth`).
    pub fn linear_depth(&self, d: f32) -> f32 {
        if self.orthographic == 1 {
            self.near + d * (self.far - self.near)
        } else {
            self.near * self.far / (self.far - d * (self.far - self.near))
        }
    }

    /// The stored depth of distance `z` along the axis: the inverse of
    /// [`ShadowView::linear_depth`].
    pub fn stored_depth(&self, z: f32) -> f32 {
        if self.orthographic == 1 {
            (z - self.near) / (self.far - self.near)
        } else {
            self.far / (self.far - self.near) * (1.0 - self.near / z)
        }
    }
}

/// How shadow maps are made and read.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowMapConfig {
    /// Width and height of every view (texels).
    pub resolution: u32,
    /// Cascades per directional light (1–8).
    pub cascades: u32,
    /// How far from the camera the cascades reach (`None`: to the far end of the scene's
    /// bounds as the camera sees them, at most the camera's far plane).
    pub max_distance: Option<f32>,
    /// Depth tolerance, in texels of the receiver's footprint.
    pub bias: f32,
    /// Receiver offset along its normal, in texels of its footprint.
    pub normal_offset: f32,
}

impl Default for ShadowMapConfig {
    fn default() -> Self {
        Self {
            resolution: 1024,
            cascades: 4,
            max_distance: None,
            bias: 1.0,
            normal_offset: 1.5,
        }
    }
}

impl ShadowMapConfig {
    /// Rejects a zero or too large resolution, a cascade count outside 1–8 and negative or
    /// non-finite offsets.
    pub fn validate(&self) -> Result<(), ShadingError> {
        let bad = |problem: String| Err(ShadingError::InvalidShadows(problem));
        if !(8..=16384).contains(&self.resolution) {
            return bad(format!(
                "resolution {} must be 8 to 16384 texels",
                self.resolution
            ));
        }
        if !(1..=8).contains(&self.cascades) {
            return bad(format!("{} cascades: 1 to 8 are allowed", self.cascades));
        }
        for (what, v) in [("bias", self.bias), ("normal offset", self.normal_offset)] {
            if !(v.is_finite() && v >= 0.0) {
                return bad(format!("{what} {v} must be finite and non-negative"));
            }
        }
        if let Some(d) = self.max_distance
            && !(d.is_finite() && d > 0.0)
        {
            return bad(format!("cascade distance {d} must be positive and finite"));
        }
        Ok(())
    }
}

/// Every view of the shadowed lights and which views each light owns.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ShadowPlan {
    /// The views, one depth-array layer each.
    pub views: Vec<ShadowView>,
    /// Per light: (first view, view count); count [`NO_SHADOW`] for an unshadowed light.
    pub lights: Vec<(u32, u32)>,
}

impl ShadowPlan {
    /// Writes each light's views into its `shadow_first` / `shadow_count`.
    pub fn assign(&self, lights: &mut [GpuLight]) {
        for (light, &(first, count)) in lights.iter_mut().zip(&self.lights) {
            light.shadow_first = first;
            light.shadow_count = count;
        }
    }
}

/// The tangent of half the field of view that keeps [`MARGIN_TEXELS`] around a view whose
/// useful half-angle has tangent `t`.
fn with_margin(t: f32, resolution: u32) -> f32 {
    t / (1.0 - 2.0 * MARGIN_TEXELS / resolution as f32)
}

/// A square perspective view from `position` along `axis` whose half-angle has tangent
/// `tan_half`, from `near` to `far`.
fn perspective(
    position: Vec3,
    axis: Vec3,
    tan_half: f32,
    (near, far): (f32, f32),
    resolution: u32,
) -> ShadowView {
    let up = if axis.cross(Vec3::Y).length_squared() < 1e-6 {
        Vec3::Z
    } else {
        Vec3::Y
    };
    let view = glam::camera::rh::view::look_to_mat4(position, axis, up);
    let proj = glam::camera::rh::proj::directx::perspective(2.0 * tan_half.atan(), 1.0, near, far);
    ShadowView {
        view_proj: (proj * view).to_cols_array_2d(),
        axis: axis.to_array(),
        near,
        far,
        orthographic: 0,
        texel: 2.0 * tan_half / resolution as f32,
        _pad: 0,
    }
}

/// The cube faces around `axis`: +axis, then the four sides, then −axis.
fn cube_axes(axis: Vec3) -> [Vec3; 6] {
    let (t, b) = orthonormal_basis(axis);
    [axis, t, -t, b, -b, -axis]
}

/// Cascade `k` of `count` ends at this fraction of the cascaded range: the practical split
/// scheme (Zhang et al. 2006), half logarithmic, half uniform.
fn cascade_end(k: u32, count: u32, near: f32, far: f32) -> f32 {
    let f = (k + 1) as f32 / count as f32;
    let log = near * (far / near).powf(f);
    let uniform = near + (far - near) * f;
    0.5 * (log + uniform)
}

/// The cascades of a directional light travelling along `direction`: each an orthographic
/// box around the bounding sphere of one slice of the camera's view frustum (so it does not
/// change size as the camera turns), its texels snapped to world positions (so shadows do not
/// shimmer as the camera moves), deep enough to hold every caster in `bounds`.
fn cascades(
    direction: Vec3,
    camera: &Camera,
    aspect: f32,
    bounds: Aabb,
    config: &ShadowMapConfig,
) -> Vec<ShadowView> {
    let forward = (camera.target - camera.eye).normalize_or(Vec3::NEG_Z);
    // The camera's distance to the farthest corner of the scene bounds bounds what it sees.
    let corners = (0..8).map(|i| {
        Vec3::new(
            if i & 1 == 0 {
                bounds.min.x
            } else {
                bounds.max.x
            },
            if i & 2 == 0 {
                bounds.min.y
            } else {
                bounds.max.y
            },
            if i & 4 == 0 {
                bounds.min.z
            } else {
                bounds.max.z
            },
        )
    });
    let scene_far = corners
        .clone()
        .map(|c| (c - camera.eye).dot(forward))
        .fold(camera.near, f32::max);
    let far = config
        .max_distance
        .unwrap_or(scene_far)
        .min(camera.far)
        .max(camera.near * 2.0);
    let near = camera.near;
    let tan_y = (camera.fov_y * 0.5).tan();
    let tan_x = tan_y * aspect;
    let view = glam::camera::rh::view::look_to_mat4(
        Vec3::ZERO,
        direction,
        if direction.cross(Vec3::Y).length_squared() < 1e-6 {
            Vec3::Z
        } else {
            Vec3::Y
        },
    );
    // Depth range of the casters along the light, from the light-space corners of the bounds.
    let light_z: Vec<f32> = corners.map(|c| view.transform_point3(c).z).collect();
    let (z_min, z_max) = light_z
        .iter()
        .fold((f32::MAX, f32::MIN), |(lo, hi), &z| (lo.min(z), hi.max(z)));
    let mut start = near;
    (0..config.cascades)
        .map(|k| {
            let end = cascade_end(k, config.cascades, near, far);
            // Bounding sphere of the frustum slice [start, end]: centre on the axis.
            let d2 = 1.0 + tan_x * tan_x + tan_y * tan_y;
            let centre_t = (0.5 * (start + end) * d2).min(end);
            let radius = ((end - centre_t).powi(2) + (end * end) * (d2 - 1.0))
                .max((centre_t - start).powi(2) + (start * start) * (d2 - 1.0))
                .sqrt();
            start = end;
            let radius = with_margin(radius, config.resolution);
            let centre = view.transform_point3(camera.eye + forward * centre_t);
            // Snap the centre to whole texels of this cascade.
            let texel = 2.0 * radius / config.resolution as f32;
            let snap = |v: f32| (v / texel).round() * texel;
            let (cx, cy) = (snap(centre.x), snap(centre.y));
            // Light space looks down −z: near = −z_max, far = −z_min, with a little slack.
            let slack = 1e-3 * (z_max - z_min).max(1e-3);
            let (zn, zf) = (-z_max - slack, -z_min + slack);
            let proj = glam::camera::rh::proj::directx::orthographic(
                cx - radius,
                cx + radius,
                cy - radius,
                cy + radius,
                zn,
                zf,
            );
            ShadowView {
                view_proj: (proj * view).to_cols_array_2d(),
                axis: direction.to_array(),
                near: zn,
                far: zf,
                orthographic: 1,
                texel,
                _pad: 0,
            }
        })
        .collect()
}

/// The views of `light` (a validated [`GpuLight`]).
pub fn light_views(
    light: &GpuLight,
    camera: &Camera,
    aspect: f32,
    bounds: Aabb,
    config: &ShadowMapConfig,
) -> Vec<ShadowView> {
    let direction = Vec3::from(light.direction);
    if light.kind == LIGHT_DIRECTIONAL {
        return cascades(direction, camera, aspect, bounds, config);
    }
    let position = Vec3::from(light.position);
    let depth = (light.radius * 1e-3, light.radius);
    let res = config.resolution;
    if light.kind == LIGHT_SPOT && light.cos_outer.acos() <= MAX_SPOT_VIEW_ANGLE {
        let tan = with_margin(light.cos_outer.acos().tan(), res);
        return vec![perspective(position, direction, tan, depth, res)];
    }
    let faces = if light.kind == LIGHT_HEMISPHERICAL || light.kind == LIGHT_SPOT {
        5
    } else {
        6
    };
    cube_views(position, direction, depth, res, faces)
}

/// The first `faces` cube faces around `axis` ([`cube_axes`]) seen from `position`.
fn cube_views(
    position: Vec3,
    axis: Vec3,
    depth: (f32, f32),
    resolution: u32,
    faces: usize,
) -> Vec<ShadowView> {
    let tan = with_margin(1.0, resolution);
    cube_axes(axis)[..faces]
        .iter()
        .map(|&axis| perspective(position, axis, tan, depth, resolution))
        .collect()
}

/// The hemicube of a hemispherical light at `position` with unit `axis`: the five cube faces
/// +axis and the four sides (the back face sees nothing it lights), `resolution` texels
/// wide, depth 0 at `near` and 1 at `far` — the views [`light_views`] gives such a light, and
/// a VPL's exact shadow map (Segovia 2006 §4.3: the hemicube unrolled into a shadow map).
pub fn hemicube_views(
    position: Vec3,
    axis: Vec3,
    (near, far): (f32, f32),
    resolution: u32,
) -> Vec<ShadowView> {
    cube_views(position, axis, (near, far), resolution, 5)
}

/// The plan for `lights`, shadowing those `shadowed` says (one flag per light), for
/// `camera` (directional cascades follow it) over a scene of `bounds`. More views than
/// `max_views` (the device's texture array layers) is an error naming the count.
pub fn plan(
    lights: &[GpuLight],
    shadowed: &[bool],
    camera: &Camera,
    aspect: f32,
    bounds: Aabb,
    config: &ShadowMapConfig,
    max_views: u32,
) -> Result<ShadowPlan, ShadingError> {
    config.validate()?;
    let mut plan = ShadowPlan::default();
    for (light, &on) in lights
        .iter()
        .zip(shadowed.iter().chain(std::iter::repeat(&false)))
    {
        if !on {
            plan.lights.push((0, NO_SHADOW));
            continue;
        }
        let views = light_views(light, camera, aspect, bounds, config);
        plan.lights
            .push((plan.views.len() as u32, views.len() as u32));
        plan.views.extend(views);
    }
    if plan.views.len() > max_views as usize {
        return Err(ShadingError::InvalidShadows(format!(
            "{} shadow views for {} shadowed lights exceed the device's {max_views} texture \
             array layers: shadow fewer lights",
            plan.views.len(),
            shadowed.iter().filter(|&&s| s).count()
        )));
    }
    Ok(plan)
}

/// The paraboloid views (origin, axis) that cover what `light` lights: one around a spot's
/// direction (two, ±direction, for a cone wider than 90°) or a hemispherical light's, two
/// (±y) for a point light, none for a directional light (cascades only). The order is the
/// one `paraboloid_axis` in `shadows.wgsl` assumes.
pub fn paraboloid_views(light: &GpuLight) -> Vec<(Vec3, Vec3)> {
    let count = match light.kind {
        LIGHT_DIRECTIONAL => 0,
        LIGHT_SPOT if light.cos_outer < 0.0 => 2,
        LIGHT_SPOT | LIGHT_HEMISPHERICAL => 1,
        _ => 2,
    };
    let p = Vec3::from(light.position);
    (0..count).map(|k| (p, paraboloid_axis(light, k))).collect()
}

/// The axis of paraboloid view `k` (0 or 1) of `light`: ±y for a point light, ±its direction
/// otherwise (`paraboloid_axis` in `shadows.wgsl`).
fn paraboloid_axis(light: &GpuLight, k: u32) -> Vec3 {
    let axis = if light.kind == LIGHT_POINT {
        Vec3::Y
    } else {
        Vec3::from(light.direction)
    };
    if k == 1 { -axis } else { axis }
}

/// The paraboloid views of the lights `shadowed` says (one flag per light), numbered from
/// tile 0, and per light (first tile, [`PARABOLOID_SHADOW`] | count), or [`NO_SHADOW`].
pub fn paraboloid_plan(lights: &[GpuLight], shadowed: &[bool]) -> (Vec<(Vec3, Vec3)>, ShadowPlan) {
    let mut views = Vec::new();
    let mut plan = ShadowPlan::default();
    for (light, &on) in lights
        .iter()
        .zip(shadowed.iter().chain(std::iter::repeat(&false)))
    {
        let own = if on {
            paraboloid_views(light)
        } else {
            Vec::new()
        };
        plan.lights.push(if own.is_empty() {
            (0, NO_SHADOW)
        } else {
            (views.len() as u32, PARABOLOID_SHADOW | own.len() as u32)
        });
        views.extend(own);
    }
    (views, plan)
}

/// Visibility of `p` from `light` through its paraboloid tiles of `atlas` (the one facing `p`
/// of a pair, the other where the normal offset crosses the seam; `paraboloid_visibility` in
/// `shadows.wgsl`).
fn paraboloid_visibility(
    (atlas, params): &(Vec<u32>, AtlasParams),
    light: &GpuLight,
    p: Vec3,
    n: Vec3,
) -> f32 {
    let origin = Vec3::from(light.position);
    let count = light.shadow_count & 0xff;
    let first = u32::from(count == 2 && (p - origin).dot(paraboloid_axis(light, 0)) < 0.0);
    // At a pair's seam the normal offset may carry the receiver over to the other view.
    let order: &[u32] = if count == 2 {
        &[first, 1 - first]
    } else {
        &[0]
    };
    for &k in order {
        let view = (origin, paraboloid_axis(light, k));
        if let Some(t) = lookup::texel(params, light.shadow_first + k, view, p, n) {
            return lookup::test(atlas, t);
        }
    }
    0.0
}

/// The index (among the light's `count` views) of the view that holds `p`: the cube face of
/// the largest axis for a cube, the first cascade whose box contains `p` (else the last).
fn pick_view(light: &GpuLight, views: &[ShadowView], p: Vec3, resolution: u32) -> usize {
    if light.kind == LIGHT_DIRECTIONAL {
        let inner = 1.0 - 2.0 * MARGIN_TEXELS / resolution as f32;
        return views
            .iter()
            .position(|v| {
                let c = Mat4::from_cols_array_2d(&v.view_proj) * p.extend(1.0);
                c.x.abs() <= inner && c.y.abs() <= inner
            })
            .unwrap_or(views.len() - 1);
    }
    let w = p - Vec3::from(light.position);
    let mut best = 0;
    for (i, v) in views.iter().enumerate() {
        if w.dot(Vec3::from(v.axis)) > w.dot(Vec3::from(views[best].axis)) {
            best = i;
        }
    }
    best
}

/// Shadow maps as the CPU reads them: the views and their depth (one `resolution²` layer
/// per view, row-major, as rendered on the GPU and read back, or as [`ray_cast_maps`] makes
/// them).
#[derive(Clone, Debug)]
pub struct ShadowMaps {
    /// The views.
    pub views: Vec<ShadowView>,
    /// Depth (0 at near, 1 at far) of every layer.
    pub depth: Vec<f32>,
    /// Texels across a layer.
    pub resolution: u32,
    /// The configuration's bias and normal offset (texels).
    pub bias: f32,
    /// See [`ShadowMapConfig::normal_offset`].
    pub normal_offset: f32,
    /// The ManyLoD atlas of the lights with [`PARABOLOID_SHADOW`] and its parameters.
    pub atlas: Option<(Vec<u32>, AtlasParams)>,
    /// The BVH the lights with [`RAY_SHADOW`] cast their rays through.
    pub rays: Option<crate::rays::RayShadows>,
}

/// Most texels of [`slope_texels`].
pub const MAX_SLOPE_TEXELS: f32 = 6.0;

/// The depth tolerance (texels of the footprint) a receiver tilted by θ from the direction to
/// `light` needs so its own surface does not shadow it in the tent filter: its plane moves
/// tan θ texels of depth per texel across the map and the tent's taps reach 2 texels away;
/// at most [`MAX_SLOPE_TEXELS`] (`slope_texels` in `shadows.wgsl`). Without it, walls the
/// sun grazes at 75° lost up to a fifth of their light.
pub fn slope_texels(light: &GpuLight, p: Vec3, n: Vec3) -> f32 {
    let (l, _) = crate::lighting::light_incidence(light, p);
    let c = n.dot(l).clamp(1e-3, 1.0);
    (2.0 * (1.0 - c * c).sqrt() / c).min(MAX_SLOPE_TEXELS)
}

/// Fraction of `light` that reaches `p` (normal `n`) through `maps`: 1 for an unshadowed
/// light, else the tent-filtered comparison described in the module docs (`shadow_visibility`
/// in `shadows.wgsl`).
pub fn visibility(maps: &ShadowMaps, light: &GpuLight, p: Vec3, n: Vec3) -> f32 {
    if light.shadow_count == NO_SHADOW {
        return 1.0;
    }
    if light.shadow_count == RAY_SHADOW {
        return maps
            .rays
            .as_ref()
            .map_or(1.0, |rays| rays.visibility(light, p, n));
    }
    if light.shadow_count & PARABOLOID_SHADOW != 0 {
        return maps
            .atlas
            .as_ref()
            .map_or(1.0, |atlas| paraboloid_visibility(atlas, light, p, n));
    }
    let first = light.shadow_first as usize;
    let views = &maps.views[first..first + light.shadow_count as usize];
    let k = pick_view(light, views, p, maps.resolution);
    let (v, layer) = (&views[k], first + k);
    let axis = Vec3::from(v.axis);
    let m = Mat4::from_cols_array_2d(&v.view_proj);
    let distance = if v.orthographic == 1 {
        1.0
    } else {
        (p - Vec3::from(light.position)).dot(axis).max(0.0)
    };
    let footprint = v.texel * distance;
    let q = p + n * (maps.normal_offset * footprint);
    let clip = m * q.extend(1.0);
    if clip.w <= 0.0 {
        return 1.0;
    }
    let ndc = clip.xyz() / clip.w;
    let receiver =
        v.linear_depth(ndc.z.clamp(0.0, 1.0)) - (maps.bias + slope_texels(light, p, n)) * footprint;
    let res = maps.resolution as i32;
    let x = (ndc.x * 0.5 + 0.5) * res as f32 - 0.5;
    let y = (0.5 - ndc.y * 0.5) * res as f32 - 0.5;
    let (bx, by) = (x.floor(), y.floor());
    let (fx, fy) = (x - bx, y - by);
    let weights = |f: f32| [1.0 - f, 1.0, 1.0, f];
    let (wx, wy) = (weights(fx), weights(fy));
    let base = layer * (res * res) as usize;
    let mut lit = 0.0;
    for (j, wyj) in wy.iter().enumerate() {
        let ty = (by as i32 - 1 + j as i32).clamp(0, res - 1);
        for (i, wxi) in wx.iter().enumerate() {
            let tx = (bx as i32 - 1 + i as i32).clamp(0, res - 1);
            let d = maps.depth[base + (ty * res + tx) as usize];
            if receiver <= v.linear_depth(d) {
                lit += wxi * wyj;
            }
        }
    }
    (lit / 9.0).min(1.0)
}

/// One light's (diffuse, specular) contribution at `s` with its shadow (`shade_shadowed` in
/// `shadows.wgsl`): [`crate::lighting::shade_light`] scaled by [`visibility`], looked up only
/// where the light reaches the surface's front.
pub fn shade_shadowed(
    light: &GpuLight,
    s: &crate::lighting::Surface,
    maps: Option<&ShadowMaps>,
) -> (Vec3, Vec3) {
    let (l, att) = crate::lighting::light_incidence(light, s.p);
    if att <= 0.0 || s.n.dot(l) <= 0.0 {
        return (Vec3::ZERO, Vec3::ZERO);
    }
    let visible = maps.map_or(1.0, |m| visibility(m, light, s.p, s.n));
    if visible <= 0.0 {
        return (Vec3::ZERO, Vec3::ZERO);
    }
    crate::lighting::reflect_light(Vec3::from(light.color) * (att * visible), l, s)
}

/// Shadow maps made by casting a ray through the centre of every texel of every view
/// against `bvh`: the depth a perfect rasteriser would store there (1 where the ray meets
/// nothing before the far plane). The ground truth of [`crate::gpu::shadows`]'s maps.
pub fn ray_cast_maps(
    bvh: &scene::Bvh,
    views: &[ShadowView],
    config: &ShadowMapConfig,
) -> ShadowMaps {
    use rayon::prelude::*;
    let res = config.resolution;
    let depth = views
        .par_iter()
        .flat_map_iter(|v| {
            let inverse = Mat4::from_cols_array_2d(&v.view_proj).inverse();
            (0..res * res).map(move |t| {
                let (x, y) = ((t % res) as f32 + 0.5, (t / res) as f32 + 0.5);
                let ndc_x = 2.0 * x / res as f32 - 1.0;
                let ndc_y = 1.0 - 2.0 * y / res as f32;
                let a = inverse.project_point3(Vec3::new(ndc_x, ndc_y, 0.0));
                let b = inverse.project_point3(Vec3::new(ndc_x, ndc_y, 1.0));
                let dir = b - a;
                let length = dir.length();
                match bvh.closest_hit(a, dir / length, length) {
                    // `a` lies on the near plane: the hit's distance along the axis is
                    // `near` plus its advance along the axis.
                    Some(hit) => {
                        v.stored_depth(v.near + (dir / length * hit.t).dot(Vec3::from(v.axis)))
                    }
                    None => 1.0,
                }
            })
        })
        .collect();
    ShadowMaps {
        views: views.to_vec(),
        depth,
        resolution: res,
        bias: config.bias,
        normal_offset: config.normal_offset,
        atlas: None,
        rays: None,
    }
}

/// A ManyLoD-style atlas of paraboloid `views` (origin, axis) made by casting a ray through
/// the centre of every texel against `bvh`: the packed distance (over `params.far`) of the
/// first surface a perfect splatting would store there (clear where the ray meets nothing
/// or the texel lies outside the hemisphere). The ground truth of the ManyLoD maps.
pub fn ray_cast_atlas(bvh: &scene::Bvh, views: &[(Vec3, Vec3)], params: &AtlasParams) -> Vec<u32> {
    use manylod::splat::{CLEAR, pack_depth};
    use rayon::prelude::*;
    let (tile, width) = (params.tile, params.width);
    let rows = (views.len() as u32).div_ceil(params.columns.max(1));
    let mut atlas = vec![CLEAR; (width * rows * tile) as usize];
    atlas
        .par_chunks_mut(width as usize)
        .enumerate()
        .for_each(|(y, row)| {
            let (ty, py) = (y as u32 / tile, y as u32 % tile);
            for (x, word) in row.iter_mut().enumerate() {
                let (tx, px) = (x as u32 / tile, x as u32 % tile);
                let Some(&(origin, normal)) = views.get((ty * params.columns + tx) as usize) else {
                    continue;
                };
                // The inverse of uv = l.xy / (1 + l.z) on the unit sphere.
                let uv = (glam::Vec2::new(px as f32, py as f32) + 0.5) / tile as f32 * 2.0 - 1.0;
                let r2 = uv.length_squared();
                if r2 >= 1.0 {
                    continue;
                }
                let z = (1.0 - r2) / (1.0 + r2);
                let (t, b) = manylod::view::paraboloid_frame(normal);
                let dir = t * (uv.x * (1.0 + z)) + b * (uv.y * (1.0 + z)) + normal * z;
                let eye = origin + normal * params.lift;
                if let Some(hit) = bvh.closest_hit(eye, dir.normalize(), params.far) {
                    *word = pack_depth(hit.t / params.far, 0);
                }
            }
        });
    atlas
}

/// How often a shadow lookup agrees with shadow rays ([`ray_agreement`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RayAgreement {
    /// Receiver–light pairs compared.
    pub pairs: usize,
    /// Of those, where the lookup and the ray agree.
    pub agree: usize,
    /// Of those, occluded by the ray.
    pub occluded: usize,
    /// Of the occluded, those the lookup finds occluded too.
    pub found: usize,
    /// Pairs left out: the lookup undecided (partly lit) or near a shadow's edge.
    pub skipped: usize,
}

impl std::fmt::Display for RayAgreement {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} receiver–light pairs ({} left out): {:.2} % agree with shadow rays; {} of {} occluded found",
            self.pairs,
            self.skipped,
            100.0 * self.fraction(),
            self.found,
            self.occluded
        )
    }
}

impl RayAgreement {
    /// `agree / pairs`.
    pub fn fraction(&self) -> f64 {
        self.agree as f64 / self.pairs.max(1) as f64
    }
}

/// The ground-truth check of shadows: for every G-buffer pixel of `gb` and every light of
/// `lights` that reaches its front, the lookup `lit(light, p, n)` (`None`: undecided, e.g.
/// partly lit) against [`ray_visibility`] through `bvh` from `p` lifted by `lift(p)`; pairs
/// where a point `edge(light, p)` away on the surface (four directions; 0: no band) gets
/// another ray answer are left out.
#[allow(clippy::too_many_arguments)]
pub fn ray_agreement(
    gb: &gbuffer::GBuffer,
    frame: &gbuffer::Frame,
    lights: &[GpuLight],
    bvh: &scene::Bvh,
    (lift, reach): (impl Fn(Vec3) -> f32, f32),
    lit: impl Fn(&GpuLight, Vec3, Vec3) -> Option<bool>,
    edge: impl Fn(&GpuLight, Vec3) -> f32,
) -> RayAgreement {
    let mut a = RayAgreement::default();
    for y in 0..gb.height() {
        for x in 0..gb.width() {
            let Some(s) = crate::cpu::sample(gb, frame, x, y) else {
                continue;
            };
            let (p, n) = (s.position, s.normal);
            for light in lights {
                let (l, att) = crate::lighting::light_incidence(light, p);
                if att <= 0.0 || n.dot(l) <= 0.05 {
                    continue;
                }
                let ray = |q: Vec3| ray_visibility(bvh, light, q, n, lift(q), reach);
                let truth = ray(p);
                let e = edge(light, p);
                let (t, b) = orthonormal_basis(n);
                let near_edge = e > 0.0 && [t, -t, b, -b].iter().any(|&d| ray(p + d * e) != truth);
                let Some(says) = lit(light, p, n).filter(|_| !near_edge) else {
                    a.skipped += 1;
                    continue;
                };
                a.pairs += 1;
                a.occluded += usize::from(!truth);
                a.found += usize::from(!truth && !says);
                a.agree += usize::from(says == truth);
            }
        }
    }
    a
}

/// Whether `p` (normal `n`) sees `light`, by a ray through `bvh` (the ground truth the
/// shadow maps approximate): from `p` lifted by `lift` along `n` to the light's position, or
/// against a directional light's direction up to `reach`.
pub fn ray_visibility(
    bvh: &scene::Bvh,
    light: &GpuLight,
    p: Vec3,
    n: Vec3,
    lift: f32,
    reach: f32,
) -> bool {
    let origin = p + n * lift;
    if light.kind == LIGHT_DIRECTIONAL {
        return !bvh.any_hit(origin, -Vec3::from(light.direction), reach);
    }
    let to = Vec3::from(light.position) - origin;
    let d = to.length();
    d <= 0.0 || !bvh.any_hit(origin, to / d, d * (1.0 - 1e-4))
}
