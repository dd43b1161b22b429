//! The bounding-sphere hierarchy (§3.5.3): a perfect complete binary tree over `n = 2^d`
//! points, built top-down by splitting every node's points at the x, y or z median — the axis
//! whose two halves have the smallest summed bounding volume — with presorted lists (Wald &
//! Havran: each split partitions the three sorted lists, no re-sorting). Every node stores a
//! bounding sphere of its points (leaves: the surfel's disc) and a normal cone; both are
//! recomputed bottom-up after deformation ([`Bsh::refit`]) without changing the tree.
//!
//! Layout: heap order, node `i` has children `2i + 1` and `2i + 2`; the leaves are nodes
//! `n − 1 .. 2n − 1`, leaf `k` holding point `order[k]`.

use glam::Vec3;
use rayon::prelude::*;

use crate::ManyLodError;

/// A node's bounds (32 bytes, the GPU layout): sphere `center`/`radius`, normal cone
/// `axis`/`angle` (half-angle in radians; π: any direction).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Node {
    /// Sphere centre.
    pub center: Vec3,
    /// Sphere radius.
    pub radius: f32,
    /// Cone axis (unit).
    pub axis: Vec3,
    /// Cone half-angle (radians, at most π).
    pub angle: f32,
}

/// Relative growth of merged bounds, so children stay inside their parent despite rounding.
const GROW: f32 = 1e-6;

impl Node {
    /// A leaf: a disc of `radius` at `p` facing `normal` (a zero normal: any direction).
    pub fn leaf(p: Vec3, normal: Vec3, radius: f32) -> Self {
        let axis = normal.normalize_or_zero();
        Self {
            center: p,
            radius,
            axis: if axis == Vec3::ZERO { Vec3::Z } else { axis },
            angle: if axis == Vec3::ZERO {
                std::f32::consts::PI
            } else {
                0.0
            },
        }
    }

    /// The smallest sphere around both spheres and the smallest cone around both cones (grown
    /// by a relative 1e-6 so that containment survives rounding).
    pub fn merge(&self, o: &Node) -> Node {
        let (center, radius) = merge_spheres((self.center, self.radius), (o.center, o.radius));
        let (axis, angle) = merge_cones((self.axis, self.angle), (o.axis, o.angle));
        Node {
            center,
            radius: radius * (1.0 + GROW) + GROW * center.abs().max_element().max(1.0) * 1e-1,
            axis,
            angle: (angle + GROW).min(std::f32::consts::PI),
        }
    }
}

fn merge_spheres((c1, r1): (Vec3, f32), (c2, r2): (Vec3, f32)) -> (Vec3, f32) {
    let d = c1.distance(c2);
    if d + r2 <= r1 {
        return (c1, r1);
    }
    if d + r1 <= r2 {
        return (c2, r2);
    }
    let r = 0.5 * (d + r1 + r2);
    (c1 + (c2 - c1) * ((r - r1) / d), r)
}

fn merge_cones((a1, t1): (Vec3, f32), (a2, t2): (Vec3, f32)) -> (Vec3, f32) {
    let pi = std::f32::consts::PI;
    let phi = angle_between(a1, a2);
    if phi + t2 <= t1 {
        return (a1, t1);
    }
    if phi + t1 <= t2 {
        return (a2, t2);
    }
    let t = 0.5 * (phi + t1 + t2);
    if t >= pi || phi > pi - 1e-3 {
        return (a1, pi);
    }
    // Rotate a1 towards a2 by t − t1 (spherical interpolation).
    let f = (t - t1) / phi;
    let s = phi.sin();
    let axis = (a1 * ((1.0 - f) * phi).sin() + a2 * (f * phi).sin()) / s;
    (axis.normalize_or(a1), t)
}

/// Angle between two unit vectors, accurate near 0 and π (unlike `acos` of the dot product).
pub fn angle_between(a: Vec3, b: Vec3) -> f32 {
    a.cross(b).length().atan2(a.dot(b))
}

/// The hierarchy: tree order and node bounds.
#[derive(Clone, Debug, PartialEq)]
pub struct Bsh {
    /// Tree depth `d`: `2^d` leaves, `2^(d+1) − 1` nodes.
    pub depth: u32,
    /// Point of each leaf slot.
    pub order: Vec<u32>,
    /// Node bounds in heap order.
    pub nodes: Vec<Node>,
    /// Radius of the leaves' discs.
    pub leaf_radius: f32,
}

/// Parent of node `i > 0`.
pub fn parent(i: u32) -> u32 {
    (i - 1) / 2
}

/// First child of node `i`.
pub fn first_child(i: u32) -> u32 {
    2 * i + 1
}

/// Level of node `i` (root 0).
pub fn level(i: u32) -> u32 {
    (i + 1).ilog2()
}

/// Sphere volume of the box around `ids` (half its diagonal cubed).
fn split_volume(points: &[Vec3], ids: &[u32]) -> f32 {
    let (lo, hi) = ids.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), &i| (lo.min(points[i as usize]), hi.max(points[i as usize])),
    );
    (0.5 * (hi - lo).length()).powi(3)
}

impl Bsh {
    /// Builds the tree over `points` (a power of two of them) with their `normals`, leaves of
    /// radius `leaf_radius`.
    pub fn build(
        points: &[Vec3],
        normals: &[Vec3],
        leaf_radius: f32,
    ) -> Result<Self, ManyLodError> {
        let n = points.len();
        if !n.is_power_of_two() || n > 1 << 26 {
            return Err(ManyLodError::PointCount(n));
        }
        if normals.len() != n {
            return Err(ManyLodError::Mismatch(format!(
                "{} normals for {n} points",
                normals.len()
            )));
        }
        if let Some(index) = points.iter().position(|p| !p.is_finite()) {
            return Err(ManyLodError::NonFinite {
                what: "point",
                index,
            });
        }
        if !(leaf_radius.is_finite() && leaf_radius >= 0.0) {
            return Err(ManyLodError::Mismatch(format!("leaf radius {leaf_radius}")));
        }
        // Presorted lists and each point's rank along each axis.
        let mut lists: [Vec<u32>; 3] = [0, 1, 2].map(|a| {
            let mut ids: Vec<u32> = (0..n as u32).collect();
            ids.par_sort_unstable_by(|&i, &j| {
                points[i as usize][a]
                    .total_cmp(&points[j as usize][a])
                    .then(i.cmp(&j))
            });
            ids
        });
        let ranks: [Vec<u32>; 3] = [0, 1, 2].map(|a| {
            let mut r = vec![0u32; n];
            for (k, &i) in lists[a].iter().enumerate() {
                r[i as usize] = k as u32;
            }
            r
        });
        let depth = n.ilog2();
        for k in 0..depth {
            let len = n >> k;
            let [x, y, z] = &mut lists;
            x.par_chunks_mut(len)
                .zip(y.par_chunks_mut(len))
                .zip(z.par_chunks_mut(len))
                .for_each(|((x, y), z)| {
                    let mut segment = [x, y, z];
                    let half = len / 2;
                    let best = (0..3)
                        .min_by(|&a, &b| {
                            let v = |a: usize| {
                                split_volume(points, &segment[a][..half])
                                    + split_volume(points, &segment[a][half..])
                            };
                            v(a).total_cmp(&v(b))
                        })
                        .unwrap_or(0);
                    let threshold = ranks[best][segment[best][half] as usize];
                    for (a, list) in segment.iter_mut().enumerate() {
                        if a != best {
                            let (left, right): (Vec<u32>, Vec<u32>) = list
                                .iter()
                                .partition(|&&i| ranks[best][i as usize] < threshold);
                            list[..half].copy_from_slice(&left);
                            list[half..].copy_from_slice(&right);
                        }
                    }
                });
        }
        let [order, _, _] = lists;
        let mut bsh = Bsh {
            depth,
            order,
            nodes: vec![Node::default(); 2 * n - 1],
            leaf_radius,
        };
        bsh.refit(points, normals)?;
        Ok(bsh)
    }

    /// Number of leaves.
    pub fn leaf_count(&self) -> usize {
        self.order.len()
    }

    /// Recomputes every node's bounds bottom-up from moved `points` and `normals` (same tree).
    pub fn refit(&mut self, points: &[Vec3], normals: &[Vec3]) -> Result<(), ManyLodError> {
        let n = self.leaf_count();
        if points.len() != n || normals.len() != n {
            return Err(ManyLodError::Mismatch(format!(
                "{} points and {} normals for a tree of {n} leaves",
                points.len(),
                normals.len()
            )));
        }
        let r = self.leaf_radius;
        self.nodes[n - 1..]
            .par_iter_mut()
            .zip(&self.order)
            .for_each(|(node, &i)| *node = Node::leaf(points[i as usize], normals[i as usize], r));
        for l in (0..self.depth).rev() {
            let (upper, lower) = self.nodes.split_at_mut((2usize << l) - 1);
            // Level l is the end of `upper`; its k-th node's children are lower[2k], lower[2k + 1].
            let first = (1usize << l) - 1;
            upper[first..]
                .par_iter_mut()
                .zip(lower.par_chunks(2))
                .for_each(|(node, c)| *node = c[0].merge(&c[1]));
        }
        Ok(())
    }

    /// Leaf slots `lo..hi` under node `i`.
    pub fn leaf_range(&self, i: u32) -> (usize, usize) {
        let l = level(i);
        let span = (self.leaf_count() >> l) as u64;
        let first = u64::from(i) + 1 - (1u64 << l);
        ((first * span) as usize, ((first + 1) * span) as usize)
    }
}
