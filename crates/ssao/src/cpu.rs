//! The screen-space estimators on the CPU (the GPU kernels' twins): every [`Method`], over the
//! whole kernel or separably (Holländer 2013 §7.2.2, Huang et al. 2011), from the G-buffer's
//! linear depth and normals (positions from depth and the view ray).
//!
//! **Window methods** (filter, Crytek, volumetric obscurance) take one sample per neighbour
//! pixel q of the k × k window (k² − 1 samples a pixel):
//! - *filter* (eq. 7.1): q's point Q blocks the direction ω = (Q − p)/|Q − p| when it lies above
//!   p's tangent plane within the radius, contributing o = cos(n, ω). With the directions taken
//!   as spread uniformly over the hemisphere, (1/π)∫(1 − V_r) cos dω ≈ 2·mean(o), so
//!   A = 1 − 2·mean(o).
//! - *Crytek* (Mittring 2007): a point of the sphere of radius r around p on q's view ray, at
//!   view depth d_p + ξ·h (h the half chord of the sphere along the ray, ξ ∈ (−1, 1) a fixed
//!   sequence, odd in the offset), is occluded when the depth buffer at q lies in front of it by
//!   less than r. Normal-free: a flat surface occludes half the sphere, so A = 2·(unoccluded
//!   fraction).
//! - *volumetric obscurance* (Loos & Sloan 2010): the segment of q's view ray inside the sphere
//!   (length 2h) is occupied behind the depth buffer; A = 2·(1 − occupied / total length).
//!
//! **Horizon methods** (HBAO, GTAO) walk a line through p along a screen direction u, the
//! (k − 1)/2 pixels on each side, in the plane spanned by u and the view vector V:
//! - *HBAO* (Bavoil et al. 2008): per side, the tangent's elevation t and the highest sample's
//!   elevation h above the plane normal to V; the line's A = 1 − mean over sides of
//!   (sin h − sin t).
//! - *GTAO* (Jimenez et al. 2016): the horizon angles of both sides, clamped to the hemisphere
//!   around the projected normal, give the cosine-weighted visible arc of the slice, times the
//!   projected normal's length.
//!
//! Their k × k form averages k lines through p, π/k apart, turned by the pixel's interleaved
//! angle.
//! All samples obey the radius (binary falloff, as [`crate::reference`]); pixels without a
//! surface are open (A = 1) and never occlude; Crytek and VO leave out samples outside the
//! image (the filter counts them as open).
//!
//! **The separable approximation.** Pass 1 evaluates the method along one line through p —
//! the pixel's direction u(p) — into the line's A₁(p). Pass 2 averages A₁ over the k pixels
//! p + t·v along the perpendicular v(p) that lie on p's surface (depth within 5 % and normals
//! within 25°: the same-surface test). The frame (u, v) turns per pixel by interleaved
//! sampling with the pattern size equal to the kernel size (§7.2.2): the pixel at
//! (x mod k, y mod k) of each k × k tile takes angle π·(x mod k + k·(y mod k) + ½)/k², so the
//! lines of neighbouring pixels cover all directions of the half circle and pass 2 combines
//! them. Finally (unless left out) the feature-preserving smoothing (after Bavoil et al.
//! 2008): the mean over the k pixels along x, then along y, that pass the same-surface test —
//! a k × k cross-bilateral box that evens out the tile's pattern. Cost: 2k − 1 occlusion
//! samples and 2k smoothing reads a pixel instead of k² − 1 samples. Every estimate is clamped
//! to [0, 1] before smoothing.
//!
//! **Half resolution** runs all of this on the grid of pixels (2x, 2y) — k grid points are 2k
//! pixels — and gives each pixel the bilinear mean of the four nearest grid estimates that pass
//! the same-surface test (the nearest in depth if none does).
//!
//! **GTAO in pass 2** divides the sum of the slices' visible arcs by the sum of their open
//! arcs (|projected normal|·(cos γ + γ·sin γ)): a single slice of an open surface seen at an
//! angle weighs 0.5 to 1.4 depending on its angle to the normal, which only slices spread
//! evenly over the half circle (the k × k form's) average to 1; pass 2's neighbours are not
//! spread evenly, and a plain mean left a grain of ±0.2 on open floors.

use gbuffer::{Frame, GBuffer, Image};
use glam::{Vec2, Vec3};

use crate::{AoConfig, Estimator, Method, SsaoError};

/// The kernel: `size` pixels on a side (odd, 3..=[`MAX_KERNEL`]) and the occlusion radius.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KernelConfig {
    /// Kernel side in pixels (the paper's k: 5, 11, 21).
    pub size: u32,
    /// The occlusion definition.
    pub ao: AoConfig,
}

/// The widest kernel.
pub const MAX_KERNEL: u32 = 63;

impl KernelConfig {
    /// Checks the kernel size and the radius.
    pub fn validate(&self) -> Result<(), SsaoError> {
        self.ao.validate()?;
        if self.size.is_multiple_of(2) || !(3..=MAX_KERNEL).contains(&self.size) {
            return Err(SsaoError::InvalidKernel(self.size));
        }
        Ok(())
    }
}

/// A pixel's surface.
#[derive(Clone, Copy)]
struct Surface {
    position: Vec3,
    normal: Vec3,
    depth: f32,
    /// The view ray at unit view depth.
    ray: Vec3,
}

/// The G-buffer's surfaces on the estimator's grid, read as the kernels read them: grid point
/// (x, y) is pixel (x·scale, y·scale) (scale 2 at half resolution).
struct Surfaces<'a> {
    gbuffer: &'a GBuffer,
    frame: &'a Frame,
    radius: f32,
    scale: i32,
    /// The view ray of pixel (x, y) is `rays[0] + x·rays[1] + y·rays[2]` (affine in the pixel,
    /// as the kernels compute it).
    rays: [Vec3; 3],
}

impl<'a> Surfaces<'a> {
    fn new(gbuffer: &'a GBuffer, frame: &'a Frame, config: &KernelConfig, scale: i32) -> Self {
        let origin = gbuffer::position::view_ray(frame, 0, 0);
        Self {
            gbuffer,
            frame,
            radius: config.ao.radius,
            scale,
            rays: [
                origin,
                gbuffer::position::view_ray(frame, 1, 0) - origin,
                gbuffer::position::view_ray(frame, 0, 1) - origin,
            ],
        }
    }

    /// The grid's size: the image's, divided by the scale and rounded up.
    fn size(&self) -> (i32, i32) {
        let (w, h) = (
            self.gbuffer.linear_depth.width() as i32,
            self.gbuffer.linear_depth.height() as i32,
        );
        (
            (w + self.scale - 1) / self.scale,
            (h + self.scale - 1) / self.scale,
        )
    }

    /// The pixel of grid point (x, y).
    fn pixel(&self, x: i32, y: i32) -> (u32, u32) {
        ((x * self.scale) as u32, (y * self.scale) as u32)
    }

    /// The linear depth at grid point (x, y), `None` outside the grid or where nothing was
    /// drawn.
    fn depth(&self, x: i32, y: i32) -> Option<f32> {
        let (w, h) = self.size();
        if x < 0 || y < 0 || x >= w || y >= h {
            return None;
        }
        let (px, py) = self.pixel(x, y);
        Some(self.gbuffer.linear_depth.get(px, py)).filter(|&d| d > 0.0)
    }

    fn ray(&self, x: i32, y: i32) -> Vec3 {
        let (px, py) = self.pixel(x, y);
        self.rays[0] + px as f32 * self.rays[1] + py as f32 * self.rays[2]
    }

    fn at(&self, x: i32, y: i32) -> Option<Surface> {
        let depth = self.depth(x, y)?;
        let ray = self.ray(x, y);
        let (px, py) = self.pixel(x, y);
        Some(Surface {
            position: self.frame.eye.truncate() + ray * depth,
            normal: gbuffer::normal::unpack_octahedral(self.gbuffer.normal.get(px, py)),
            depth,
            ray,
        })
    }

    /// The position of pixel (x, y), `None` outside the image or where there is no surface.
    fn position(&self, x: i32, y: i32) -> Option<Vec3> {
        self.depth(x, y)
            .map(|d| self.frame.eye.truncate() + self.ray(x, y) * d)
    }

    /// The world direction of screen direction `u` (x right, y down).
    fn screen_direction(&self, u: Vec2) -> Vec3 {
        self.frame
            .inv_view
            .transform_vector3(Vec3::new(u.x, -u.y, 0.0))
    }
}

fn check(gbuffer: &GBuffer, frame: &Frame, config: &KernelConfig) -> Result<(), SsaoError> {
    config.validate()?;
    crate::check_size(gbuffer, frame)
}

/// ξ(m) ∈ (−1, 1) of the window offset numbered m (`m(−o) = −m(o)`, so ξ is odd in the
/// offset and a plane occludes exactly half of each ± pair).
fn crytek_offset(m: i32) -> f32 {
    let f = (m.unsigned_abs() as f32 * 0.618_034).fract();
    if m < 0 { -f } else { f }
}

/// The running sums of a window method: what occludes, out of what was sampled.
#[derive(Clone, Copy, Default)]
struct Sums {
    occluded: f32,
    total: f32,
}

/// Adds the sample at pixel q (window offset numbered m) to p's sums.
fn add_window_sample(
    method: Method,
    s: &Surfaces,
    p: &Surface,
    (qx, qy): (i32, i32),
    m: i32,
    sums: &mut Sums,
) {
    let r = s.radius;
    if method == Method::Filter {
        sums.total += 1.0;
        if let Some(q) = s.position(qx, qy) {
            sums.occluded += occlusion(p, q, r);
        }
        return;
    }
    // Crytek and VO: q's view ray through the sphere around p (none outside the image).
    let (w, h) = s.size();
    if qx < 0 || qy < 0 || qx >= w || qy >= h {
        return;
    }
    let lateral = (s.ray(qx, qy) - p.ray).length() * p.depth;
    if lateral >= r {
        return;
    }
    let half_chord = (r * r - lateral * lateral).sqrt();
    let buffer = s.depth(qx, qy);
    if method == Method::Crytek {
        let sample = p.depth + crytek_offset(m) * half_chord;
        sums.total += 1.0;
        if buffer.is_some_and(|b| b < sample && sample - b < r) {
            sums.occluded += 1.0;
        }
    } else {
        sums.total += 2.0 * half_chord;
        if let Some(b) = buffer {
            sums.occluded += (p.depth + half_chord - b).clamp(0.0, 2.0 * half_chord);
        }
    }
}

/// A window method's A from its sums (unclamped).
fn window_value(method: Method, sums: Sums) -> f32 {
    if sums.total <= 0.0 {
        return 1.0;
    }
    let fraction = sums.occluded / sums.total;
    match method {
        Method::Filter => 1.0 - 2.0 * fraction,
        _ => 2.0 * (1.0 - fraction),
    }
}

/// The pixel `t` steps along `direction` from (x, y), rounded half up.
fn step(x: i32, y: i32, direction: Vec2, t: i32) -> (i32, i32) {
    let o = (direction * t as f32 + 0.5).floor();
    (x + o.x as i32, y + o.y as i32)
}

/// The highest sin(elevation) above the plane normal to `view` of the samples at `pixels` (one
/// side of a line), starting from `lowest`.
fn horizon(
    s: &Surfaces,
    p: &Surface,
    view: Vec3,
    pixels: impl Iterator<Item = (i32, i32)>,
    lowest: f32,
) -> f32 {
    let mut highest = lowest;
    for (qx, qy) in pixels {
        if let Some(q) = s.position(qx, qy) {
            let delta = q - p.position;
            let d2 = delta.length_squared();
            if d2 > 0.0 && d2 < s.radius * s.radius {
                highest = highest.max(delta.dot(view) * d2.sqrt().recip());
            }
        }
    }
    highest
}

/// A along the line through pixel (x, y) in screen direction `u`, with its weight in pass 2:
/// the window method's samples on the line (k − 1), or the horizon method's two sides
/// (unclamped); weight 1, but GTAO's the open slice's value (see the module).
fn line_value(
    method: Method,
    s: &Surfaces,
    p: &Surface,
    (x, y): (i32, i32),
    u: Vec2,
    half: i32,
) -> [f32; 2] {
    if !method.is_horizon_based() {
        let mut sums = Sums::default();
        for t in (-half..=half).filter(|&t| t != 0) {
            add_window_sample(method, s, p, step(x, y, u, t), t, &mut sums);
        }
        return [window_value(method, sums), 1.0];
    }
    let view = (s.frame.eye.truncate() - p.position).normalize();
    let direction = s.screen_direction(u);
    // The samples of each side, t = 1 … k/2 steps along ±u.
    let side = |sign: i32| (1..=half).map(move |t| step(x, y, u, sign * t));
    // The slice: the plane of V and the direction; `ortho` lies in it, normal to V.
    let ortho = direction - view * direction.dot(view);
    let axis = ortho.cross(view).normalize_or_zero();
    if method == Method::Hbao {
        // The tangent in the slice, towards +u, and its elevation.
        let mut tangent = axis.cross(p.normal);
        if tangent.dot(ortho) < 0.0 {
            tangent = -tangent;
        }
        let sin_t = tangent.normalize_or_zero().dot(view);
        // The other side's tangent is −tangent, at elevation −t.
        let forward = horizon(s, p, view, side(1), sin_t);
        let backward = horizon(s, p, view, side(-1), -sin_t);
        return [1.0 - 0.5 * ((forward - sin_t) + (backward + sin_t)), 1.0];
    }
    // GTAO: the projected normal and its angle γ from V in the slice.
    let projected = p.normal - axis * p.normal.dot(axis);
    let length = projected.length();
    if length <= 0.0 {
        return [0.0, 0.0];
    }
    let cos_n = (projected.dot(view) / length).clamp(0.0, 1.0);
    let gamma = if ortho.dot(projected) < 0.0 {
        -cos_n.acos()
    } else {
        cos_n.acos()
    };
    let half_pi = std::f32::consts::FRAC_PI_2;
    let forward = horizon(s, p, view, side(1), (gamma + half_pi).cos());
    let backward = horizon(s, p, view, side(-1), (gamma - half_pi).cos());
    let clamp = |h: f32| gamma + (h - gamma).clamp(-half_pi, half_pi);
    let h_forward = clamp(forward.clamp(-1.0, 1.0).acos());
    let h_backward = clamp(-backward.clamp(-1.0, 1.0).acos());
    let arc = |h: f32| 0.25 * (cos_n + 2.0 * h * gamma.sin() - (2.0 * h - gamma).cos());
    // The open slice's arc is cos γ + γ·sin γ.
    let open = cos_n + gamma * gamma.sin();
    [length * (arc(h_forward) + arc(h_backward)), length * open]
}

/// o(p, q): the cosine of the direction to `q` when it blocks it within `radius`, else 0.
fn occlusion(p: &Surface, q: Vec3, radius: f32) -> f32 {
    let v = q - p.position;
    let d2 = v.length_squared();
    if d2 <= 0.0 || d2 >= radius * radius {
        return 0.0;
    }
    (p.normal.dot(v) * d2.sqrt().recip()).max(0.0)
}

/// The frame directions u of a k × k interleaving tile: entry x + k·y at angle
/// π·(x + k·y + ½)/k² (the GPU kernels read the same table).
pub fn frame_directions(k: u32) -> Vec<Vec2> {
    let n = k * k;
    (0..n)
        .map(|i| {
            let a = std::f32::consts::PI * (i as f32 + 0.5) / n as f32;
            Vec2::new(a.cos(), a.sin())
        })
        .collect()
}

/// Pixel (x, y)'s entry of the k × k interleaving tile.
fn pattern_index(x: i32, y: i32, k: u32) -> usize {
    let k = k as i32;
    (x.rem_euclid(k) + k * y.rem_euclid(k)) as usize
}

/// Pass 1 of the separable approximation at full resolution: `method` along the line through
/// each pixel in screen direction `direction(x, y)` (k − 1 samples): the line's A (unclamped;
/// 1 where there is no surface) and its weight in pass 2 (1, but GTAO's open arc).
pub fn pass_1d(
    gbuffer: &GBuffer,
    frame: &Frame,
    config: &KernelConfig,
    method: Method,
    direction: impl Fn(i32, i32) -> Vec2 + Sync + Send,
) -> Result<Image<[f32; 2]>, SsaoError> {
    check(gbuffer, frame, config)?;
    let s = Surfaces::new(gbuffer, frame, config, 1);
    Ok(pass_1(&s, config, method, direction))
}

fn pass_1(
    s: &Surfaces,
    config: &KernelConfig,
    method: Method,
    direction: impl Fn(i32, i32) -> Vec2 + Sync + Send,
) -> Image<[f32; 2]> {
    let half = (config.size / 2) as i32;
    crate::per_pixel(grid(s), |x, y, _| {
        let (x, y) = (x as i32, y as i32);
        match s.at(x, y) {
            Some(p) => line_value(method, s, &p, (x, y), direction(x, y), half),
            None => [1.0, 1.0],
        }
    })
}

fn grid(s: &Surfaces) -> (u32, u32) {
    let (w, h) = s.size();
    (w as u32, h as u32)
}

/// Whether q lies on p's surface (the same-surface test of pass 2, the smoothing and the
/// upsampling).
fn same_surface(p: &Surface, q: &Surface) -> bool {
    (q.depth - p.depth).abs() <= 0.05 * p.depth && p.normal.dot(q.normal) >= 0.9
}

/// The accessibility A of every pixel by `estimator` (see the module).
pub fn estimate(
    gbuffer: &GBuffer,
    frame: &Frame,
    config: &KernelConfig,
    estimator: Estimator,
) -> Result<Image<f32>, SsaoError> {
    check(gbuffer, frame, config)?;
    if !estimator.half_resolution {
        return Ok(estimate_grid(
            &Surfaces::new(gbuffer, frame, config, 1),
            config,
            estimator,
        ));
    }
    let coarse = Surfaces::new(gbuffer, frame, config, 2);
    let a = estimate_grid(&coarse, config, estimator);
    let fine = Surfaces::new(gbuffer, frame, config, 1);
    Ok(crate::per_pixel(grid(&fine), |x, y, _| {
        upsample(&fine, &coarse, &a, x as i32, y as i32)
    }))
}

/// Pixel (x, y)'s A from the half-resolution estimates `a`: the bilinear weights of the (up
/// to) four nearest grid points on its surface, normalised; with none on its surface, the
/// nearest in depth; 1 without a surface.
fn upsample(fine: &Surfaces, coarse: &Surfaces, a: &Image<f32>, x: i32, y: i32) -> f32 {
    let Some(p) = fine.at(x, y) else {
        return 1.0;
    };
    let (x0, y0) = (x.div_euclid(2), y.div_euclid(2));
    let (fx, fy) = ((x % 2) as f32 * 0.5, (y % 2) as f32 * 0.5);
    let (mut sum, mut weights) = (0.0, 0.0);
    let mut nearest = (f32::INFINITY, 1.0);
    for (i, j) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
        let weight = (if i == 0 { 1.0 - fx } else { fx }) * (if j == 0 { 1.0 - fy } else { fy });
        let Some(q) = coarse.at(x0 + i, y0 + j).filter(|_| weight > 0.0) else {
            continue;
        };
        let value = a.get((x0 + i) as u32, (y0 + j) as u32);
        if same_surface(&p, &q) {
            sum += weight * value;
            weights += weight;
        }
        let gap = (q.depth - p.depth).abs();
        if gap < nearest.0 {
            nearest = (gap, value);
        }
    }
    if weights > 0.0 {
        sum / weights
    } else {
        nearest.1
    }
}

/// A on `s`'s grid (see the module).
fn estimate_grid(s: &Surfaces, config: &KernelConfig, estimator: Estimator) -> Image<f32> {
    let k = config.size;
    let half = (k / 2) as i32;
    let directions = frame_directions(k);
    let method = estimator.method;
    if !estimator.separable {
        return crate::per_pixel(grid(s), |x, y, _| {
            let (x, y) = (x as i32, y as i32);
            let Some(p) = s.at(x, y) else {
                return 1.0;
            };
            let value = if method.is_horizon_based() {
                // k lines, π/k apart, turned by the pixel's interleaved angle.
                let first = pattern_index(x, y, k);
                (0..k as usize)
                    .map(|i| {
                        let u = directions[(first + i * k as usize) % directions.len()];
                        line_value(method, s, &p, (x, y), u, half)[0]
                    })
                    .sum::<f32>()
                    / k as f32
            } else {
                let mut sums = Sums::default();
                for dy in -half..=half {
                    for dx in (-half..=half).filter(|&dx| (dx, dy) != (0, 0)) {
                        let m = dx + k as i32 * dy;
                        add_window_sample(method, s, &p, (x + dx, y + dy), m, &mut sums);
                    }
                }
                window_value(method, sums)
            };
            value.clamp(0.0, 1.0)
        });
    }
    let u = |x: i32, y: i32| directions[pattern_index(x, y, k)];
    let first = pass_1(s, config, method, u);
    let combined = crate::per_pixel(grid(s), |x, y, _| {
        let (x, y) = (x as i32, y as i32);
        let Some(p) = s.at(x, y) else {
            return 1.0;
        };
        let d = u(x, y);
        let v = Vec2::new(-d.y, d.x);
        let (mut sum, mut weights) = (0.0, 0.0);
        for t in -half..=half {
            let (qx, qy) = step(x, y, v, t);
            if s.at(qx, qy).is_some_and(|q| same_surface(&p, &q)) {
                let [value, weight] = first.get(qx as u32, qy as u32);
                sum += value;
                weights += weight;
            }
        }
        if weights > 0.0 {
            (sum / weights).clamp(0.0, 1.0)
        } else {
            1.0
        }
    });
    if !estimator.smoothing {
        return combined;
    }
    let across = smooth(s, &combined, half, (1, 0));
    smooth(s, &across, half, (0, 1))
}

/// The feature-preserving smoothing after pass 2 (§7.2.2, after Bavoil et al. 2008): the mean
/// of `a` over the k grid points along `axis` that lie on p's surface. Run along x, then y: a
/// k × k cross-bilateral box, which evens out the interleaving tile's k × k pattern.
fn smooth(s: &Surfaces, a: &Image<f32>, half: i32, (ax, ay): (i32, i32)) -> Image<f32> {
    crate::per_pixel(grid(s), |x, y, _| {
        let (x, y) = (x as i32, y as i32);
        let Some(p) = s.at(x, y) else {
            return 1.0;
        };
        let (mut sum, mut count) = (0.0, 0.0);
        for t in -half..=half {
            let (qx, qy) = (x + t * ax, y + t * ay);
            if s.at(qx, qy).is_some_and(|q| same_surface(&p, &q)) {
                sum += a.get(qx as u32, qy as u32);
                count += 1.0;
            }
        }
        sum / count
    })
}
