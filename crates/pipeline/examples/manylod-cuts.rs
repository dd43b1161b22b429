//! `manylod-cuts`: a picture of three views' cuts through one hierarchy (Holländer 2013
//! Fig. 3.13) on Sponza, from the CPU reference. Three VPL views (one on the floor, one on a
//! wall facing ±x, one facing ±z) of the benchmark's spot light each get their basic cut; each
//! panel shows the scene's surfels from one overview camera, coloured by the level of the cut
//! node that covers them in that panel's view (blue: coarse, yellow: fine, each node's surfels
//! tinted alike so node extents show; grey: culled), with the view marked by a red ring.
//! Writes `manylod-cuts.png`.

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Parser;
use gbuffer::Image;
use glam::{Mat4, Vec3, Vec4Swizzles};
use instant_radiosity::{
    shadows::{scene_mesh, vpl_views},
    vpl,
};
use manylod::{Bsh, CutProblem, View, bsh::level, cut, surfels};
use rayon::prelude::*;
use scene::Bvh;

/// Draws three VPL views' cuts.
#[derive(Parser, Debug)]
struct Args {
    #[command(flatten)]
    scene: bench::SceneOption,
    /// Output folder.
    #[arg(long, default_value = "out")]
    out: PathBuf,
    /// Surfels (a power of two).
    #[arg(long, default_value_t = 1 << 20)]
    points: usize,
    /// Cut threshold ε in pixels.
    #[arg(long, default_value_t = 2.0)]
    epsilon: f32,
    /// Panel width in pixels (height 3/4 of it).
    #[arg(long, default_value_t = 640)]
    width: u32,
}

/// Micro-view side in pixels, as in the benchmark.
const TILE: u32 = 32;
/// The overview camera's vertical field of view in degrees.
const FOV_Y: f32 = 70.0;

/// Blue → green → yellow over `t` in [0, 1].
fn ramp(t: f32) -> Vec3 {
    let stops = [
        Vec3::new(0.15, 0.2, 0.75),
        Vec3::new(0.1, 0.65, 0.6),
        Vec3::new(0.45, 0.8, 0.2),
        Vec3::new(1.0, 0.85, 0.1),
    ];
    let x = t.clamp(0.0, 1.0) * (stops.len() - 1) as f32;
    let i = (x as usize).min(stops.len() - 2);
    stops[i].lerp(stops[i + 1], x - i as f32)
}

/// A stable tint in [0.7, 1] per node, so neighbouring cut nodes tell apart.
fn tint(node: u32) -> f32 {
    let h = node.wrapping_mul(0x9E37_79B9) >> 24;
    0.7 + 0.3 * h as f32 / 255.0
}

/// The first VPL view whose axis is within ~25° of one of `axes` (either sign).
fn pick(views: &[View], axis: Vec3) -> Option<View> {
    views.iter().copied().find(|v| match v {
        View::Paraboloid { normal, .. } => normal.dot(axis).abs() > 0.9,
        View::Perspective { .. } => false,
    })
}

fn main() -> Result<()> {
    let args = Args::parse();
    let (_, scene) = args.scene.load()?;
    let bvh = Bvh::build(&scene);
    let bounds = scene.bounds();
    let (center, extent, diagonal) = (bounds.center(), bounds.max - bounds.min, bounds.diagonal());
    // The benchmark's spot light at frame 0.
    let spot = bench::orbiting_spot(&bounds, 0.0);
    let set = vpl::generate(
        &scene,
        &bvh,
        &[spot],
        &vpl::VplConfig { count: 256, subsets: 1, seed: 1, emissive: false, bounces: 1 },
    )?;
    let candidates = vpl_views(&set, TILE, 1e-3 * diagonal);
    let views: Vec<View> = [Vec3::Y, Vec3::X, Vec3::Z]
        .iter()
        .map(|&a| pick(&candidates, a).context("no VPL faces that way"))
        .collect::<Result<_>>()?;

    let (positions, indices) = scene_mesh(&scene);
    let s = surfels::sample(&positions, &indices, args.points, 1)?;
    let (p, n) = surfels::evaluate(&s, &positions, &indices);
    let bsh = Bsh::build(&p, &n, surfels::disc_radius(&positions, &indices, args.points))?;
    let problem = CutProblem { bsh: &bsh, views: &views, epsilon: args.epsilon };
    let cut = problem.flag_culled(&cut::basic(&problem)?.node_views);

    // Overview camera: from one end of the scene, above the floor, looking down the length.
    let (w, h) = (args.width, args.width * 3 / 4);
    let eye = center + Vec3::new(-0.42 * extent.x, 0.05 * extent.y, 0.0);
    let look = glam::camera::rh::view::look_at_mat4(
        eye,
        center + Vec3::new(0.1 * extent.x, -0.2 * extent.y, 0.0),
        Vec3::Y,
    );
    let proj = glam::camera::rh::proj::directx::perspective(
        FOV_Y.to_radians(),
        w as f32 / h as f32,
        0.01 * diagonal,
        2.0 * diagonal,
    );
    let camera = proj * look;
    let leaf_start = bsh.leaf_count() - 1;
    // The colour ramp spans the levels of the drawn cut nodes.
    let drawn_levels = cut.iter().filter(|nv| nv.node & cut::CULLED == 0).map(|nv| level(nv.node));
    let levels = (drawn_levels.clone().min().unwrap_or(0), drawn_levels.max().unwrap_or(0));
    let focal = h as f32 * 0.5 / (0.5 * FOV_Y).to_radians().tan();

    let panels: Vec<Image<[f32; 4]>> = (0..views.len() as u32)
        .into_par_iter()
        .map(|v| {
            // The cut node (with its culled flag) covering every leaf slot in view v.
            let mut cover = vec![u32::MAX; bsh.leaf_count()];
            for nv in cut.iter().filter(|nv| nv.view == v) {
                let (lo, hi) = bsh.leaf_range(nv.node & !cut::CULLED);
                cover[lo..hi].fill(nv.node);
            }
            panel(&bsh, leaf_start, &cover, camera, eye, (w, h, focal), levels, &views[v as usize])
        })
        .collect();
    let gap = 8;
    let mut out = Image::filled(3 * w + 2 * gap, h, [1.0f32, 1.0, 1.0, 1.0]);
    for (k, img) in panels.iter().enumerate() {
        for y in 0..h {
            for x in 0..w {
                out.set(k as u32 * (w + gap) + x, y, img.get(x, y));
            }
        }
    }
    std::fs::create_dir_all(&args.out)?;
    let file = args.out.join("manylod-cuts.png");
    out.write_png(&file)?;
    for (k, v) in views.iter().enumerate() {
        let count = cut.iter().filter(|nv| nv.view == k as u32).count();
        let culled =
            cut.iter().filter(|nv| nv.view == k as u32 && nv.node & cut::CULLED != 0).count();
        println!("view {k} at {:?}: {count} cut node-views ({culled} culled)", v.eye());
    }
    println!("wrote {}", file.display());
    Ok(())
}

/// One panel: surfels splatted as discs with a depth test, coloured by their cut node.
#[allow(clippy::too_many_arguments)]
fn panel(
    bsh: &Bsh,
    leaf_start: usize,
    cover: &[u32],
    camera: Mat4,
    eye: Vec3,
    (w, h, focal): (u32, u32, f32),
    (lo, hi): (u32, u32),
    view: &View,
) -> Image<[f32; 4]> {
    let mut img = Image::filled(w, h, [1.0f32, 1.0, 1.0, 1.0]);
    let mut depth = vec![f32::INFINITY; (w * h) as usize];
    let project = |p: Vec3| {
        let c = camera * p.extend(1.0);
        (c.w > 0.0).then(|| {
            let ndc = c.xyz() / c.w;
            ((ndc.x * 0.5 + 0.5) * w as f32, (0.5 - ndc.y * 0.5) * h as f32, ndc.z)
        })
    };
    for (k, &node) in cover.iter().enumerate() {
        let leaf = &bsh.nodes[leaf_start + k];
        let Some((x, y, z)) = project(leaf.center) else {
            continue;
        };
        let shade = 0.55 + 0.45 * leaf.axis.dot((eye - leaf.center).normalize()).abs();
        let colour = if node & cut::CULLED != 0 {
            Vec3::splat(0.35)
        } else {
            ramp((level(node) - lo) as f32 / (hi - lo).max(1) as f32) * tint(node)
        } * shade;
        // The surfel's disc, at least a pixel wide, at most 5.
        let r = (leaf.radius * focal / leaf.center.distance(eye)).clamp(0.7, 2.5);
        let (x0, x1) = ((x - r).floor().max(0.0), (x + r).ceil().min(w as f32 - 1.0));
        let (y0, y1) = ((y - r).floor().max(0.0), (y + r).ceil().min(h as f32 - 1.0));
        for py in y0 as u32..=y1 as u32 {
            for px in x0 as u32..=x1 as u32 {
                let (dx, dy) = (px as f32 + 0.5 - x, py as f32 + 0.5 - y);
                let i = (py * w + px) as usize;
                if dx * dx + dy * dy <= r * r && z < depth[i] {
                    depth[i] = z;
                    img.set(px, py, colour.extend(1.0).to_array());
                }
            }
        }
    }
    // The view: a red ring around its position.
    if let Some((x, y, _)) = project(view.eye()) {
        for a in 0..360 {
            let t = (a as f32).to_radians();
            for r in [7.0f32, 8.0, 9.0] {
                let (px, py) = (x + r * t.cos(), y + r * t.sin());
                if px >= 0.0 && py >= 0.0 && px < w as f32 && py < h as f32 {
                    img.set(px as u32, py as u32, [1.0, 0.0, 0.0, 1.0]);
                }
            }
        }
    }
    img
}
