//! Compact normal storage (Ishmukhametov 2013 §3.6, after Pranckevičius' "Compact Normal
//! Storage for Small G-Buffers"), plus the octahedral mapping the G-buffer uses.
//!
//! Every [`NormalEncoding`] maps a unit normal to two values in \[0, 1\] that a two-channel
//! unorm target stores; WGSL twins live in `shaders/gbuffer/normal_encoding.wgsl`.
//! Some encodings only cover part of the sphere ([`NormalEncoding::domain_min_z`]): in view
//! space, normals of visible surfaces have z ≥ 0 (up to interpolation).

use std::f32::consts::PI;

use glam::{Vec2, Vec3};

/// The encodings of thesis §3.6 and the octahedral mapping.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NormalEncoding {
    /// Store X and Y, reconstruct Z ≥ 0 (Killzone 2).
    XyReconstructZ,
    /// Azimuth and z (spherical coordinates).
    Spherical,
    /// Sphere map transform (CryEngine 3).
    SphereMap,
    /// Stereographic projection scaled by 1.7777.
    Stereographic,
    /// Octahedral mapping (Meyer et al. 2010; Cigolle et al. 2014).
    Octahedral,
}

/// Stereographic scale of the thesis.
const STEREO_SCALE: f32 = 1.7777;

fn safe_normalize2(v: Vec2) -> Vec2 {
    let l2 = v.length_squared();
    if l2 > 1e-30 { v / l2.sqrt() } else { Vec2::X }
}

fn oct_wrap(v: Vec2) -> Vec2 {
    let sign = Vec2::new(
        if v.x >= 0.0 { 1.0 } else { -1.0 },
        if v.y >= 0.0 { 1.0 } else { -1.0 },
    );
    (Vec2::ONE - Vec2::new(v.y.abs(), v.x.abs())) * sign
}

/// Octahedral mapping of a unit normal to \[−1, 1\]².
pub fn encode_octahedral_snorm(n: Vec3) -> Vec2 {
    let p = Vec2::new(n.x, n.y) / (n.x.abs() + n.y.abs() + n.z.abs());
    if n.z < 0.0 { oct_wrap(p) } else { p }
}

/// Inverse of [`encode_octahedral_snorm`].
pub fn decode_octahedral_snorm(e: Vec2) -> Vec3 {
    let mut n = Vec3::new(e.x, e.y, 1.0 - e.x.abs() - e.y.abs());
    let t = (-n.z).max(0.0);
    n.x += if n.x >= 0.0 { -t } else { t };
    n.y += if n.y >= 0.0 { -t } else { t };
    n.normalize()
}

/// WGSL `pack2x16snorm`: x in the low 16 bits.
pub fn pack2x16snorm(v: Vec2) -> u32 {
    let q = |c: f32| ((c.clamp(-1.0, 1.0) * 32767.0).round_ties_even() as i32 as u32) & 0xffff;
    q(v.x) | (q(v.y) << 16)
}

/// WGSL `unpack2x16snorm`.
pub fn unpack2x16snorm(w: u32) -> Vec2 {
    let c = |b: u32| ((b as u16 as i16) as f32 / 32767.0).max(-1.0);
    Vec2::new(c(w & 0xffff), c(w >> 16))
}

/// The G-buffer's normal word: octahedral, two snorm16. A zero normal is stored as +Z.
pub fn pack_octahedral(n: Vec3) -> u32 {
    let l2 = n.length_squared();
    let n = if l2 > 1e-30 { n / l2.sqrt() } else { Vec3::Z };
    pack2x16snorm(encode_octahedral_snorm(n))
}

/// Decodes the G-buffer's normal word.
pub fn unpack_octahedral(w: u32) -> Vec3 {
    decode_octahedral_snorm(unpack2x16snorm(w))
}

impl NormalEncoding {
    /// All encodings, in the order of the WGSL test kernel.
    pub const ALL: [Self; 5] = [
        Self::XyReconstructZ,
        Self::Spherical,
        Self::SphereMap,
        Self::Stereographic,
        Self::Octahedral,
    ];

    /// Short name for tables.
    pub fn name(self) -> &'static str {
        match self {
            Self::XyReconstructZ => "XY + reconstructed Z",
            Self::Spherical => "spherical",
            Self::SphereMap => "sphere map",
            Self::Stereographic => "stereographic",
            Self::Octahedral => "octahedral",
        }
    }

    /// Smallest z of the normals the encoding can represent: 0 for XY (the sign of z is
    /// lost), −0.5 for the stereographic projection (its 1.7777 scale clips beyond 120° from
    /// +Z), −1 (the whole sphere) for the others.
    pub fn domain_min_z(self) -> f32 {
        match self {
            Self::XyReconstructZ => 0.0,
            Self::Stereographic => -0.5,
            _ => -1.0,
        }
    }

    /// Encodes a unit normal to two values in \[0, 1\].
    pub fn encode(self, n: Vec3) -> Vec2 {
        let e = match self {
            Self::XyReconstructZ => Vec2::new(n.x, n.y),
            Self::Spherical => Vec2::new(n.y.atan2(n.x) / PI, n.z),
            Self::SphereMap => {
                safe_normalize2(Vec2::new(n.x, n.y)) * (n.z * 0.5 + 0.5).max(0.0).sqrt()
            }
            Self::Stereographic => Vec2::new(n.x, n.y) / (n.z + 1.0) / STEREO_SCALE,
            Self::Octahedral => encode_octahedral_snorm(n),
        };
        e * 0.5 + 0.5
    }

    /// Decodes two values in \[0, 1\] to a unit normal.
    pub fn decode(self, e: Vec2) -> Vec3 {
        let a = e * 2.0 - 1.0;
        match self {
            Self::XyReconstructZ => Vec3::new(a.x, a.y, (1.0 - a.length_squared()).max(0.0).sqrt()),
            Self::Spherical => {
                let (s, c) = (a.x * PI).sin_cos();
                let r = (1.0 - a.y * a.y).max(0.0).sqrt();
                Vec3::new(c * r, s * r, a.y)
            }
            Self::SphereMap => {
                let z = a.length_squared() * 2.0 - 1.0;
                (safe_normalize2(a) * (1.0 - z * z).max(0.0).sqrt()).extend(z)
            }
            Self::Stereographic => {
                let p = Vec3::new(a.x * STEREO_SCALE, a.y * STEREO_SCALE, 1.0);
                let b = 2.0 / p.length_squared();
                Vec3::new(b * p.x, b * p.y, b - 1.0)
            }
            Self::Octahedral => decode_octahedral_snorm(a),
        }
    }

    /// Encode, quantize each value to `bits`-bit unorm, decode.
    pub fn round_trip(self, n: Vec3, bits: u32) -> Vec3 {
        let scale = ((1u64 << bits) - 1) as f32;
        let q = self.encode(n).clamp(Vec2::ZERO, Vec2::ONE) * scale;
        self.decode(Vec2::new(q.x.round(), q.y.round()) / scale)
    }
}

/// `count` nearly uniform unit vectors on the sphere (Fibonacci lattice).
pub fn fibonacci_sphere(count: usize) -> impl Iterator<Item = Vec3> {
    let golden = PI * (3.0 - 5f32.sqrt());
    (0..count).map(move |i| {
        let z = 1.0 - 2.0 * (i as f32 + 0.5) / count as f32;
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = golden * i as f32;
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    })
}

/// Angular error in degrees between unit vectors.
pub fn angle_deg(a: Vec3, b: Vec3) -> f32 {
    // atan2 of |a×b| and a·b is accurate for tiny angles, unlike acos.
    a.cross(b).length().atan2(a.dot(b)).to_degrees()
}

/// (maximum, mean) angular error in degrees of `encoding` at `bits` per value over
/// `count` Fibonacci-sphere normals inside its domain.
pub fn measure_error(encoding: NormalEncoding, bits: u32, count: usize) -> (f32, f32) {
    use rayon::prelude::*;
    let normals: Vec<Vec3> = fibonacci_sphere(count)
        .filter(|n| n.z >= encoding.domain_min_z())
        .collect();
    let (max, sum) = normals
        .par_iter()
        .map(|&n| {
            let e = angle_deg(n, encoding.round_trip(n, bits).normalize_or_zero());
            (e, f64::from(e))
        })
        .reduce(|| (0.0, 0.0), |a, b| (a.0.max(b.0), a.1 + b.1));
    (max, (sum / normals.len() as f64) as f32)
}

/// Thesis §3.6 "per-pixel view space": the frame whose z is the direction from the pixel to
/// the eye, x = normalize(z.z, 0, −z.x), y = z × x (columns x, y, z). A surface the eye sees
/// has a normal with z ≥ 0 in it, so x and y suffice — in perspective too, where plain view
/// space ([`NormalEncoding::XyReconstructZ`]) sees normals with z < 0 near the image edges.
/// `to_eye` (unit) must not be parallel to y.
pub fn per_pixel_view_frame(to_eye: Vec3) -> glam::Mat3 {
    let z = to_eye;
    let x = Vec3::new(z.z, 0.0, -z.x).normalize();
    glam::Mat3::from_cols(x, z.cross(x), z)
}

/// Per-pixel view-space encoding of `n` seen along `to_eye`: its x and y in
/// [`per_pixel_view_frame`], in \[0, 1\].
pub fn encode_per_pixel_view(n: Vec3, to_eye: Vec3) -> Vec2 {
    let f = per_pixel_view_frame(to_eye);
    Vec2::new(f.x_axis.dot(n), f.y_axis.dot(n)) * 0.5 + 0.5
}

/// Inverse of [`encode_per_pixel_view`]: z = √(1 − x² − y²) ≥ 0, back to the caller's space.
pub fn decode_per_pixel_view(e: Vec2, to_eye: Vec3) -> Vec3 {
    let a = e * 2.0 - 1.0;
    per_pixel_view_frame(to_eye) * Vec3::new(a.x, a.y, (1.0 - a.length_squared()).max(0.0).sqrt())
}

/// The unit directions from pixels to the eye of a 90° × 90° view looking down −z, in view
/// space, `side` × `side` of them: where [`measure_per_pixel_view_error`] looks.
fn view_directions(side: usize) -> impl Iterator<Item = Vec3> {
    (0..side * side).map(move |i| {
        let s = |k: usize| (k as f32 + 0.5) / side as f32 * 2.0 - 1.0;
        Vec3::new(-s(i % side), -s(i / side), 1.0).normalize()
    })
}

/// (maximum, mean) angular error in degrees of the per-pixel view-space encoding at `bits` per
/// value: `count` Fibonacci-sphere normals, each seen from the 8 × 8 pixels of a 90° view that
/// see its front (normal · direction to the eye ≥ 0).
pub fn measure_per_pixel_view_error(bits: u32, count: usize) -> (f32, f32) {
    use rayon::prelude::*;
    let scale = ((1u64 << bits) - 1) as f32;
    let views: Vec<Vec3> = view_directions(8).collect();
    let normals: Vec<Vec3> = fibonacci_sphere(count).collect();
    let (max, sum, n) = normals
        .par_iter()
        .flat_map_iter(|&n| {
            views
                .iter()
                .filter(move |v| n.dot(**v) >= 0.0)
                .map(move |&v| (n, v))
        })
        .map(|(n, v)| {
            let q = (encode_per_pixel_view(n, v) * scale).round() / scale;
            let e = angle_deg(n, decode_per_pixel_view(q, v).normalize_or_zero());
            (e, f64::from(e), 1u64)
        })
        .reduce(
            || (0.0, 0.0, 0),
            |a, b| (a.0.max(b.0), a.1 + b.1, a.2 + b.2),
        );
    (max, (sum / n as f64) as f32)
}

/// Kaplanyan 2010's best fit for normals in three unorm8 channels (thesis §3.6): `n` (unit)
/// stored as `t · n · 0.5 + 0.5` with the length `t` ∈ (0, 1] whose quantized vector,
/// normalized, is nearest to `n` — found by trying every 8-bit value of the largest component
/// (the exact search the thesis calls too expensive for real time).
pub fn best_fit_length(n: Vec3) -> f32 {
    let m = n.abs().max_element();
    let decode = |b: u8| f32::from(b) / 255.0 * 2.0 - 1.0;
    (128..=255u8)
        .map(|b| decode(b) / m)
        .filter(|&t| t > 0.0 && t <= 1.0)
        .map(|t| (angle_deg(n, decode_unorm8x3(encode_unorm8x3(n * t))), t))
        .fold((f32::INFINITY, 1.0), |a, b| if b.0 < a.0 { b } else { a })
        .1
}

/// A vector in \[−1, 1\]³ as three unorm8 values (`v · 0.5 + 0.5`, rounded).
pub fn encode_unorm8x3(v: Vec3) -> [u8; 3] {
    (v * 0.5 + 0.5)
        .clamp(Vec3::ZERO, Vec3::ONE)
        .to_array()
        .map(|c| (c * 255.0).round() as u8)
}

/// Three unorm8 values back to a unit vector (`normalize(b / 255 · 2 − 1)`).
pub fn decode_unorm8x3(b: [u8; 3]) -> Vec3 {
    Vec3::from_array(b.map(|c| f32::from(c) / 255.0 * 2.0 - 1.0)).normalize_or_zero()
}

/// The precomputed best-fit lengths (Kaplanyan 2010, thesis §3.6: "prebake the results of the
/// search" into a texture): by symmetry a length depends only on the sorted magnitudes of the
/// components, so one `size × size` table over (mid / max, min / max) ∈ \[0, 1\]² holds them.
#[derive(Clone, Debug)]
pub struct BestFitTable {
    size: usize,
    lengths: Vec<f32>,
}

impl BestFitTable {
    /// Searches every texel's direction ([`best_fit_length`]); `size` ≥ 2.
    pub fn new(size: usize) -> Self {
        use rayon::prelude::*;
        let size = size.max(2);
        let lengths = (0..size * size)
            .into_par_iter()
            .map(|i| {
                let s = |k: usize| k as f32 / (size - 1) as f32;
                let (u, v) = (s(i % size), s(i / size));
                best_fit_length(Vec3::new(v * u, u, 1.0).normalize())
            })
            .collect();
        Self { size, lengths }
    }

    /// The stored length for `n`'s direction (nearest texel).
    pub fn length(&self, n: Vec3) -> f32 {
        let mut a = n.abs().to_array();
        a.sort_by(f32::total_cmp);
        let [lo, mid, hi] = a;
        let hi = hi.max(f32::MIN_POSITIVE);
        let texel = |x: f32| ((x * (self.size - 1) as f32).round() as usize).min(self.size - 1);
        let (u, v) = (mid / hi, if mid > 0.0 { lo / mid } else { 0.0 });
        self.lengths[texel(v) * self.size + texel(u)]
    }

    /// Encodes `n` with its tabulated length.
    pub fn encode(&self, n: Vec3) -> [u8; 3] {
        encode_unorm8x3(n * self.length(n))
    }
}

/// (maximum, mean) angular error in degrees over `count` Fibonacci-sphere normals of three
/// unorm8 channels: `table` `None` stores the normalized normal (the banding the thesis shows),
/// `Some` the best-fit length from the table.
pub fn measure_unorm8x3_error(table: Option<&BestFitTable>, count: usize) -> (f32, f32) {
    use rayon::prelude::*;
    let normals: Vec<Vec3> = fibonacci_sphere(count).collect();
    let (max, sum) = normals
        .par_iter()
        .map(|&n| {
            let stored = match table {
                Some(t) => t.encode(n),
                None => encode_unorm8x3(n),
            };
            let e = angle_deg(n, decode_unorm8x3(stored));
            (e, f64::from(e))
        })
        .reduce(|| (0.0, 0.0), |a, b| (a.0.max(b.0), a.1 + b.1));
    (max, (sum / normals.len() as f64) as f32)
}
