//! Punctual lights with a finite influence radius.

use std::str::FromStr;

use glam::Vec3;

use crate::Aabb;

/// A light source. Point and spot lights have a finite `radius` at which their attenuation
/// reaches exactly zero, so culled and brute-force shading agree.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Light {
    /// Omnidirectional light.
    Point {
        /// Position.
        position: Vec3,
        /// Linear colour.
        color: Vec3,
        /// Intensity (colour multiplier; candela for glTF lights).
        intensity: f32,
        /// Influence radius.
        radius: f32,
    },
    /// Cone light.
    Spot {
        /// Position.
        position: Vec3,
        /// Unit direction the cone points to.
        direction: Vec3,
        /// Linear colour.
        color: Vec3,
        /// Intensity.
        intensity: f32,
        /// Influence radius.
        radius: f32,
        /// Angle (radians) inside which the light is at full strength.
        inner_angle: f32,
        /// Angle (radians) beyond which the light is zero.
        outer_angle: f32,
    },
    /// Hemispherical point light (Segovia 2006 §4.3; the emission of a virtual point light and
    /// of a small Lambertian area light): intensity `intensity · cos θ` around `direction`,
    /// zero behind it, with the same finite-radius attenuation as a point light.
    Hemispherical {
        /// Position.
        position: Vec3,
        /// Unit direction of maximal emission (the emitter's normal).
        direction: Vec3,
        /// Linear colour.
        color: Vec3,
        /// Intensity along `direction`.
        intensity: f32,
        /// Influence radius.
        radius: f32,
    },
    /// Light from infinitely far away.
    Directional {
        /// Unit direction the light travels in.
        direction: Vec3,
        /// Linear colour.
        color: Vec3,
        /// Intensity (illuminance).
        intensity: f32,
    },
}

impl Light {
    /// The light moved by `m`: positions as points, directions as vectors (renormalised),
    /// radii scaled by `m`'s largest axis scale.
    pub fn transformed(&self, m: glam::Mat4) -> Light {
        let point = |p: Vec3| m.transform_point3(p);
        let dir = |d: Vec3| m.transform_vector3(d).normalize_or(d);
        let scale = glam::Mat3::from_mat4(m)
            .to_cols_array_2d()
            .iter()
            .map(|c| Vec3::from(*c).length())
            .fold(0.0f32, f32::max);
        let mut light = *self;
        match &mut light {
            Light::Point {
                position, radius, ..
            } => {
                *position = point(*position);
                *radius *= scale;
            }
            Light::Spot {
                position,
                direction,
                radius,
                ..
            }
            | Light::Hemispherical {
                position,
                direction,
                radius,
                ..
            } => {
                *position = point(*position);
                *direction = dir(*direction);
                *radius *= scale;
            }
            Light::Directional { direction, .. } => *direction = dir(*direction),
        }
        light
    }
}

/// Radius at which a light of `intensity` falls to 1/256 of unit illuminance, used when a
/// glTF light has no `range`.
pub(crate) fn default_radius(intensity: f32) -> f32 {
    (intensity.max(0.0) * 256.0).sqrt().max(1e-3)
}

fn parse_floats(s: &str) -> Result<Vec<f32>, String> {
    s.split(',')
        .map(|v| match v.trim().parse::<f32>() {
            Ok(f) if f.is_finite() => Ok(f),
            Ok(_) => Err("numbers must be finite".to_string()),
            Err(_) => Err(format!("{v:?} is not a number")),
        })
        .collect()
}

impl FromStr for Light {
    type Err = String;

    /// Parses a light from the command line:
    /// `point:X,Y,Z,RADIUS[,R,G,B,INTENSITY]`,
    /// `spot:X,Y,Z,DX,DY,DZ,RADIUS,INNER_DEG,OUTER_DEG[,R,G,B,INTENSITY]`,
    /// `hemi:X,Y,Z,DX,DY,DZ,RADIUS[,R,G,B,INTENSITY]`, `dir:DX,DY,DZ[,R,G,B,INTENSITY]`.
    /// Colour defaults to white, intensity to 1.
    fn from_str(s: &str) -> Result<Self, String> {
        let (kind, rest) = s
            .split_once(':')
            .ok_or("expected KIND:NUMBERS, e.g. point:0,1,0,5")?;
        let v = parse_floats(rest)?;
        let base = match kind {
            "point" => 4,
            "spot" => 9,
            "hemi" => 7,
            "dir" | "directional" => 3,
            _ => {
                return Err(format!(
                    "unknown light kind {kind:?} (point, spot, hemi, dir)"
                ));
            }
        };
        if v.len() != base && v.len() != base + 4 {
            return Err(format!(
                "{kind} light takes {base} or {} numbers, got {}",
                base + 4,
                v.len()
            ));
        }
        let (color, intensity) = if v.len() > base {
            (Vec3::new(v[base], v[base + 1], v[base + 2]), v[base + 3])
        } else {
            (Vec3::ONE, 1.0)
        };
        let vec = |i: usize| Vec3::new(v[i], v[i + 1], v[i + 2]);
        let dir = |i: usize| vec(i).try_normalize().ok_or("direction must not be zero");
        let radius = |r: f32| {
            if r > 0.0 {
                Ok(r)
            } else {
                Err("radius must be positive".to_string())
            }
        };
        Ok(match kind {
            "point" => Light::Point {
                position: vec(0),
                color,
                intensity,
                radius: radius(v[3])?,
            },
            "spot" => {
                let (inner, outer) = (v[7].to_radians(), v[8].to_radians());
                if !(0.0..=outer).contains(&inner) || outer > std::f32::consts::FRAC_PI_2 {
                    return Err("spot angles need 0 <= inner <= outer <= 90 degrees".into());
                }
                Light::Spot {
                    position: vec(0),
                    direction: dir(3)?,
                    color,
                    intensity,
                    radius: radius(v[6])?,
                    inner_angle: inner,
                    outer_angle: outer,
                }
            }
            "hemi" => Light::Hemispherical {
                position: vec(0),
                direction: dir(3)?,
                color,
                intensity,
                radius: radius(v[6])?,
            },
            _ => Light::Directional {
                direction: dir(0)?,
                color,
                intensity,
            },
        })
    }
}

/// A small deterministic generator (SplitMix64) for reproducible scenes.
pub(crate) struct SplitMix(pub u64);

impl SplitMix {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in \[0, 1).
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// `count` point lights spread uniformly (seeded) through `bounds`, with saturated colours.
///
/// Each light's radius is `0.6 × diagonal / ∛count`, so the overlap per point stays roughly
/// constant as the count grows; the intensity is `radius² / 4`, so a surface at half the
/// radius receives about unit illuminance.
pub fn scatter_point_lights(bounds: Aabb, count: usize, seed: u64) -> Vec<Light> {
    let mut rng = SplitMix(seed);
    let radius = 0.6 * bounds.diagonal() / (count.max(1) as f32).cbrt();
    (0..count)
        .map(|_| {
            let t = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
            let hue = rng.next_f32() * 6.0;
            let color = Vec3::new(
                (hue - 3.0).abs() - 1.0,
                2.0 - (hue - 2.0).abs(),
                2.0 - (hue - 4.0).abs(),
            )
            .clamp(Vec3::ZERO, Vec3::ONE)
                * 0.7
                + 0.3;
            Light::Point {
                position: bounds.min + (bounds.max - bounds.min) * t,
                color,
                intensity: radius * radius * 0.25,
                radius,
            }
        })
        .collect()
}

/// Rec. 709 luminance of a linear RGB colour.
pub fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}
