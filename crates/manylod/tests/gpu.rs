//! GPU kernels against the CPU reference: refit bounds, cut sets (basic, incremental, lazy),
//! atlas depths (list-based splat and the in-place variant), capacity errors.

mod common;

use common::{scene, sorted, tree, views_in_tiles};
use glam::Vec3;
use manylod::{
    AtlasLayout, Bsh, CutProblem, ManyLodError,
    bsh::angle_between,
    cut::{basic, refine_levels, roots},
    gpu::{Compaction, CutKind, GpuIsm, GpuManyLod, GpuRefit},
    splat::{self, CLEAR},
    surfels,
};

const TILE: u32 = 32;
const EPSILON: f32 = 3.0;

fn setup(bsh: &Bsh, angle: f32, capacity: usize) -> Option<(&'static gpu::Gpu, GpuManyLod)> {
    let gpu = gpu::test_device(&manylod::device_needs())?;
    let v = views_in_tiles(angle, Some(TILE));
    let layout = AtlasLayout::new(v.len(), TILE, 12.0);
    let m = GpuManyLod::new(&gpu.device, bsh, &v, EPSILON, layout, capacity, None).expect("set-up");
    Some((gpu, m))
}

fn run_cut(gpu: &gpu::Gpu, m: &mut GpuManyLod, kind: CutKind) -> manylod::Cut {
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    m.encode_cut(&mut encoder, kind, None);
    gpu.queue.submit([encoder.finish()]);
    m.read_cut(&gpu.device, &gpu.queue).expect("cut")
}

/// The deformation: a twist around y and a wave, moving every vertex.
fn deform(p: &[Vec3]) -> Vec<Vec3> {
    p.iter()
        .map(|q| {
            let a = 0.3 * q.y;
            Vec3::new(
                q.x * a.cos() - q.z * a.sin(),
                q.y + 0.1 * (2.0 * q.x).sin(),
                q.x * a.sin() + q.z * a.cos(),
            )
        })
        .collect()
}

#[test]
fn refit_matches_the_cpu() {
    let (p, i) = scene();
    let count = 1 << 12;
    let s = surfels::sample(&p, &i, count, 7).expect("surfels");
    let (pts, nrm) = surfels::evaluate(&s, &p, &i);
    let mut bsh = Bsh::build(&pts, &nrm, surfels::disc_radius(&p, &i, count)).expect("tree");
    let Some((gpu, m)) = setup(&bsh, 0.0, 1 << 16) else {
        return;
    };
    let refit = GpuRefit::new(&gpu.device, &m, &bsh, &s, &p, &i).expect("refit set-up");
    let moved = deform(&p);
    refit.set_positions(&gpu.queue, &moved).expect("positions");
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    refit.encode(&mut encoder, None);
    gpu.queue.submit([encoder.finish()]);
    let got = m.read_nodes(&gpu.device, &gpu.queue).expect("nodes");
    let (pts, nrm) = surfels::evaluate(&s, &moved, &i);
    bsh.refit(&pts, &nrm).expect("cpu refit");
    assert_eq!(got.len(), bsh.nodes.len());
    for (k, (g, w)) in got.iter().zip(&bsh.nodes).enumerate() {
        let tol = 1e-5 * (1.0 + w.radius);
        assert!(
            g.center.distance(w.center) <= tol && (g.radius - w.radius).abs() <= tol,
            "node {k}: sphere {g:?} vs {w:?}"
        );
        assert!(
            (g.angle - w.angle).abs() <= 1e-4
                && (w.angle >= std::f32::consts::PI - 1e-3
                    || angle_between(g.axis, w.axis) <= 1e-3),
            "node {k}: cone {g:?} vs {w:?}"
        );
    }
    assert_eq!(
        refit
            .set_positions(&gpu.queue, &moved[1..])
            .err()
            .map(|e| e.to_string()),
        Some(format!(
            "{} positions for a mesh of {}",
            moved.len() - 1,
            moved.len()
        ))
    );
}

#[test]
fn cuts_match_the_cpu() {
    cuts_match_the_cpu_at(1);
}

/// Passes that descend several tree levels (`set_levels_per_pass`) against the CPU's
/// iterations of as many levels: the same cuts, iterations and work over the same frames.
#[test]
fn cuts_of_several_levels_per_pass_match_the_cpu() {
    for levels in 2..=manylod::cut::MAX_LEVELS_PER_ITERATION {
        cuts_match_the_cpu_at(levels);
    }
}

/// Six frames of basic, incremental and lazy cuts at `levels` tree levels per pass, each
/// against [`refine_levels`].
fn cuts_match_the_cpu_at(levels: u32) {
    let (bsh, _, _) = tree(1 << 12);
    let Some((gpu, mut m)) = setup(&bsh, 0.0, 1 << 18) else {
        return;
    };
    m.set_levels_per_pass(&gpu.queue, levels).expect("levels");
    let mut last = Vec::new();
    // Iterations and work match while the GPU's earlier cuts (its starting points) did.
    let mut exact = true;
    for frame in 0..6u32 {
        let v = views_in_tiles(frame as f32 * 10f32.to_radians(), Some(TILE));
        m.set_views(&gpu.queue, &v).expect("views");
        let problem = CutProblem {
            bsh: &bsh,
            views: &v,
            epsilon: EPSILON,
        };
        // Frame 0 basic, then incremental, lazy (q = 2), incremental, basic, lazy.
        let (kind, want) = match frame {
            0 | 4 => (
                CutKind::Basic,
                refine_levels(&problem, roots(v.len()), None, levels).expect("basic"),
            ),
            2 | 5 => (
                CutKind::Lazy(2),
                refine_levels(&problem, last.clone(), Some(2), levels).expect("lazy"),
            ),
            _ => (
                CutKind::Incremental,
                refine_levels(&problem, last.clone(), None, levels).expect("inc"),
            ),
        };
        let got = run_cut(gpu, &mut m, kind);
        // Exactly equal on llvmpipe; a hardware driver's asin/atan2 may decide node-views
        // whose criterion lies within rounding of ε (or of a culling plane) the other way, so
        // there at most 0.1 % may differ — and the GPU cut must still partition every view.
        let (g, w) = (
            sorted(got.node_views.clone()),
            sorted(want.node_views.clone()),
        );
        let differ = symmetric_difference(&g, &w);
        let allowed = if gpu.is_software() { 0 } else { w.len() / 1000 };
        assert!(
            differ <= allowed,
            "{levels} levels per pass, frame {frame} {kind:?}: {differ} node-views differ of {}",
            w.len()
        );
        if kind != CutKind::Lazy(2) {
            common::assert_partition(&problem, &got.node_views, frame);
        }
        exact &= differ == 0;
        if exact {
            assert_eq!(
                (got.iterations, got.processed, got.converged, got.culled),
                (want.iterations, want.processed, want.converged, want.culled),
                "{levels} levels per pass, frame {frame} {kind:?}: iterations, work, converged, culled"
            );
        }
        last = want.node_views;
    }
}

/// Node-views in one sorted list but not the other.
fn symmetric_difference(a: &[manylod::NodeView], b: &[manylod::NodeView]) -> usize {
    let (mut i, mut j, mut n) = (0, 0, 0);
    while i < a.len() || j < b.len() {
        match (a.get(i), b.get(j)) {
            (Some(x), Some(y)) if x == y => (i, j) = (i + 1, j + 1),
            (Some(x), Some(y)) if x < y => (i, n) = (i + 1, n + 1),
            (Some(_), None) => (i, n) = (i + 1, n + 1),
            _ => (j, n) = (j + 1, n + 1),
        }
    }
    n
}

/// Pixels where the GPU and CPU atlases differ: coverage (one cleared, the other not) and
/// depth (both written, packed words more than one depth step apart).
fn differences(a: &[u32], b: &[u32]) -> (usize, usize) {
    let coverage = a
        .iter()
        .zip(b)
        .filter(|(x, y)| (**x == CLEAR) != (**y == CLEAR))
        .count();
    let depth = a
        .iter()
        .zip(b)
        .filter(|(x, y)| **x != CLEAR && **y != CLEAR && (**x >> 12).abs_diff(**y >> 12) > 1)
        .count();
    (coverage, depth)
}

#[test]
fn atlas_matches_the_cpu() {
    let (bsh, _, _) = tree(1 << 14);
    let Some((gpu, mut m)) = setup(&bsh, 0.3, 1 << 19) else {
        return;
    };
    let v = views_in_tiles(0.3, Some(TILE));
    let layout = m.layout();
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    m.encode_cut(&mut encoder, CutKind::Basic, None);
    m.encode_splat(&mut encoder, None);
    gpu.queue.submit([encoder.finish()]);
    let got = m.read_atlas(&gpu.device, &gpu.queue).expect("atlas");
    let cut = m.read_cut(&gpu.device, &gpu.queue).expect("cut");
    let problem = CutProblem {
        bsh: &bsh,
        views: &v,
        epsilon: EPSILON,
    };
    let flagged = problem.flag_culled(&cut.node_views);
    let want = splat::splat(&bsh.nodes, &v, &flagged, &layout).expect("cpu splat");
    let written = want.iter().filter(|&&w| w != CLEAR).count();
    assert!(
        written > want.len() / 20,
        "the views should see the scene: {written} of {} pixels",
        want.len()
    );
    let (coverage, depth) = differences(&got, &want);
    assert!(
        coverage <= written / 1000 && depth <= written / 1000,
        "{coverage} coverage and {depth} depth differences of {written} pixels"
    );

    // The in-place variant rasterises the same basic cut with either compaction: the same
    // atlas, bit for bit (atomic minimum does not depend on the order).
    let compactions = m.compactions();
    assert_eq!(
        compactions.contains(&Compaction::Ballot),
        gpu.device.features().contains(wgpu::Features::SUBGROUP),
        "the ballot compaction runs exactly where the device has subgroups"
    );
    eprintln!("in-place compactions tested: {compactions:?}");
    for compaction in compactions {
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        m.encode_inplace(&mut encoder, compaction, None)
            .expect("in-place");
        gpu.queue.submit([encoder.finish()]);
        let inplace = m
            .read_atlas(&gpu.device, &gpu.queue)
            .expect("in-place atlas");
        let same = inplace.iter().zip(&got).filter(|(a, b)| a == b).count();
        assert_eq!(
            same,
            got.len(),
            "in-place ({compaction:?}) vs list-based atlas"
        );
    }
}

/// The nearest node per pixel (point-based GI's lookup): where the GPU and CPU atlases hold
/// the same packed depth, the same node won the pixel (the smallest index among equal
/// depths, on both sides).
#[test]
fn nearest_nodes_match_the_cpu() {
    let (bsh, _, _) = tree(1 << 14);
    let Some((gpu, mut m)) = setup(&bsh, 0.3, 1 << 19) else {
        return;
    };
    m.enable_nearest_nodes(&gpu.device).expect("nearest pass");
    let v = views_in_tiles(0.3, Some(TILE));
    let layout = m.layout();
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    m.encode_cut(&mut encoder, CutKind::Basic, None);
    m.encode_splat(&mut encoder, None);
    gpu.queue.submit([encoder.finish()]);
    let atlas = m.read_atlas(&gpu.device, &gpu.queue).expect("atlas");
    let ids = m
        .read_nearest_nodes(&gpu.device, &gpu.queue)
        .expect("ids")
        .expect("enabled");
    let cut = m.read_cut(&gpu.device, &gpu.queue).expect("cut");
    let problem = CutProblem {
        bsh: &bsh,
        views: &v,
        epsilon: EPSILON,
    };
    let want_depth = splat::splat(
        &bsh.nodes,
        &v,
        &problem.flag_culled(&cut.node_views),
        &layout,
    )
    .expect("cpu splat");
    let (width, _) = layout.size();
    let tile = TILE as usize;
    let (mut compared, mut same) = (0, 0);
    for (view_index, view) in v.iter().enumerate() {
        let drawn: Vec<u32> = cut
            .node_views
            .iter()
            .filter(|nv| nv.view as usize == view_index && problem.is_drawn(**nv))
            .map(|nv| nv.node)
            .collect();
        let want = splat::nearest_nodes(&bsh.nodes, view, &drawn, &layout);
        let slot = view_index as u32;
        let (ox, oy) = (
            (slot % layout.columns) as usize * tile,
            (slot / layout.columns) as usize * tile,
        );
        for (i, &w) in want.iter().enumerate() {
            let p = (oy + i / tile) * width as usize + ox + i % tile;
            if atlas[p] == want_depth[p] {
                compared += 1;
                same += usize::from(ids[p] == w);
            }
            if atlas[p] == CLEAR {
                assert_eq!(ids[p], splat::NO_NODE, "an empty pixel has no node");
            }
        }
    }
    assert!(
        compared > v.len() * tile * tile / 2,
        "{compared} pixels compared"
    );
    assert!(
        same * 1000 >= compared * 999,
        "{same} of {compared} pixels of equal depth have the same nearest node"
    );
}

/// The ISM baseline: GPU atlas == CPU atlas of the same random points.
#[test]
fn ism_atlas_matches_the_cpu() {
    let (bsh, _, _) = tree(1 << 14);
    let Some((gpu, m)) = setup(&bsh, 0.3, 1 << 16) else {
        return;
    };
    let v = views_in_tiles(0.3, Some(TILE));
    let n = bsh.leaf_count();
    let (points, list) = splat::ism(&bsh.nodes[n - 1..], v.len(), 1024, 5).expect("ism");

    let ism = GpuIsm::new(&gpu.device, &m, &points, &list).expect("gpu ism");
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    ism.encode(&mut encoder, &m, None);
    gpu.queue.submit([encoder.finish()]);
    let got = m.read_atlas(&gpu.device, &gpu.queue).expect("atlas");
    let want = splat::splat(&points, &v, &list, &m.layout()).expect("cpu");
    let written = want.iter().filter(|&&w| w != CLEAR).count();
    assert!(written > want.len() / 20, "{written} pixels written");
    let (coverage, depth) = differences(&got, &want);
    assert!(
        coverage <= written / 1000 && depth <= written / 1000,
        "{coverage} coverage and {depth} depth differences of {written} pixels"
    );
    assert!(splat::ism(&points, v.len(), 0, 1).is_err());
}

#[test]
fn overflow_and_bad_input_are_errors() {
    let (bsh, _, _) = tree(1 << 12);
    let Some((gpu, mut m)) = setup(&bsh, 0.0, 64) else {
        return;
    };
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    m.encode_cut(&mut encoder, CutKind::Basic, None);
    gpu.queue.submit([encoder.finish()]);
    assert!(matches!(
        m.read_cut(&gpu.device, &gpu.queue),
        Err(ManyLodError::Capacity { capacity: 64, .. })
    ));
    let v = views_in_tiles(0.0, Some(TILE));
    let layout = AtlasLayout::new(v.len(), TILE, 12.0);
    // Views larger than the tile are refused (smaller ones fill its corner).
    let wrong_tiles = views_in_tiles(0.0, Some(2 * TILE));
    assert!(matches!(
        GpuManyLod::new(&gpu.device, &bsh, &wrong_tiles, 1.0, layout, 1 << 16, None),
        Err(ManyLodError::View { index: 0, .. })
    ));
    assert!(GpuManyLod::new(&gpu.device, &bsh, &v, f32::NAN, layout, 1 << 16, None).is_err());
    assert!(m.set_views(&gpu.queue, &v[1..]).is_err(), "view count");
}

/// The splat writes into the caller's atlas buffer (`new(.., Some(atlas))`): the same atlas as the one
/// `new` allocates; a buffer too small or without `STORAGE` is an error naming the atlas.
#[test]
fn caller_owned_atlas_is_checked_and_written() {
    let (bsh, _, _) = tree(1 << 12);
    let Some((gpu, mut own)) = setup(&bsh, 0.3, 1 << 18) else {
        return;
    };
    let d = &gpu.device;
    let v = views_in_tiles(0.3, Some(TILE));
    let layout = own.layout();
    let (w, h) = layout.size();
    let buffer =
        |size, usage| gpu::transfer::buffer(d, "application's atlas", size, usage).expect("buffer");
    let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
    let atlas = buffer(u64::from(w * h) * 4, usage);
    let mut mine = GpuManyLod::new(d, &bsh, &v, EPSILON, layout, 1 << 18, Some(&atlas))
        .expect("caller's atlas");
    let mut encoder = d.create_command_encoder(&Default::default());
    for m in [&mut own, &mut mine] {
        m.encode_cut(&mut encoder, CutKind::Basic, None);
        m.encode_splat(&mut encoder, None);
    }
    gpu.queue.submit([encoder.finish()]);
    let want = own.read_atlas(d, &gpu.queue).expect("atlas");
    assert_eq!(mine.read_atlas(d, &gpu.queue).expect("atlas"), want);
    let read = gpu::transfer::read_buffer(d, &gpu.queue, &atlas).expect("read");
    assert_eq!(bytemuck::cast_slice::<u8, u32>(&read), &want[..]);
    for (size, usage, words) in [
        (u64::from(w * h) * 4 - 4, usage, "bytes"),
        (
            u64::from(w * h) * 4,
            wgpu::BufferUsages::COPY_SRC,
            "STORAGE",
        ),
    ] {
        let e = GpuManyLod::new(
            d,
            &bsh,
            &v,
            EPSILON,
            layout,
            1 << 18,
            Some(&buffer(size, usage)),
        )
        .err()
        .expect("rejected");
        assert!(
            e.to_string().contains("ManyLoD atlas") && e.to_string().contains(words),
            "{e}"
        );
    }
}

/// Single-view point rendering (§3.6.1, Fig. 3.20): one 96×54 camera in a one-view atlas of
/// 96² px, cut at ε = 1 px. GPU = CPU (cut, depths, nearest nodes); nothing lands below the
/// view's 54 rows; and against the mesh itself, rasterised here by brute force at the same
/// pixel centres (the ground truth), the points cover the same pixels except on the mesh's
/// silhouettes and lie on its surface.
#[test]
fn single_view_points_cover_the_mesh() {
    let Some(gpu) = gpu::test_device(&manylod::device_needs()) else {
        return;
    };
    // The shared scene with its ground quad cut into 32×32 squares (R₃ sampling of two
    // 8×8 triangles lines the points up in rows farther apart than a pixel here) and its
    // sphere wound outwards (back-facing nodes are culled).
    let (mut p, mut idx) = scene();
    let g = p.len() as u32 - 4;
    p.truncate(g as usize);
    idx.truncate(idx.len() - 6);
    for t in idx.chunks_exact_mut(3) {
        t.swap(1, 2);
    }
    for j in 0..=32u32 {
        for i in 0..=32u32 {
            p.push(Vec3::new(i as f32 / 4.0 - 4.0, 0.0, j as f32 / 4.0 - 4.0));
        }
    }
    for j in 0..32 {
        for i in 0..32 {
            let a = g + j * 33 + i;
            idx.extend([a, a + 33, a + 1, a + 1, a + 33, a + 34]);
        }
    }
    let count = 1 << 16;
    let sampled = surfels::sample(&p, &idx, count, 7).expect("surfels");
    let (points, normals) = surfels::evaluate(&sampled, &p, &idx);
    let bsh = Bsh::build(&points, &normals, surfels::disc_radius(&p, &idx, count)).expect("tree");
    let (w, h) = (96u32, 54u32);
    let (eye, fov_y, near, far) = (Vec3::new(0.5, 6.0, 6.0), 0.9f32, 0.1f32, 50.0f32);
    let proj = glam::camera::rh::proj::directx::perspective(fov_y, w as f32 / h as f32, near, far);
    let view_proj =
        proj * glam::camera::rh::view::look_at_mat4(eye, Vec3::new(0.0, 0.5, 0.0), Vec3::Y);
    let v = [manylod::View::Perspective {
        eye,
        view_proj,
        fov_y,
        size: (w, h),
    }];
    let layout = AtlasLayout::new(1, w, 12.0);
    let mut m = GpuManyLod::new(&gpu.device, &bsh, &v, 1.0, layout, 1 << 18, None).expect("set-up");
    m.enable_nearest_nodes(&gpu.device).expect("nearest pass");
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    m.encode_cut(&mut encoder, CutKind::Basic, None);
    m.encode_splat(&mut encoder, None);
    gpu.queue.submit([encoder.finish()]);
    let atlas = m.read_atlas(&gpu.device, &gpu.queue).expect("atlas");
    let ids = m
        .read_nearest_nodes(&gpu.device, &gpu.queue)
        .expect("ids")
        .expect("enabled");
    let cut = m.read_cut(&gpu.device, &gpu.queue).expect("cut");

    let problem = CutProblem {
        bsh: &bsh,
        views: &v,
        epsilon: 1.0,
    };
    let want = basic(&problem).expect("cpu cut");
    let differ = symmetric_difference(
        &sorted(cut.node_views.clone()),
        &sorted(want.node_views.clone()),
    );
    let allowed = if gpu.is_software() {
        0
    } else {
        want.node_views.len() / 1000
    };
    assert!(differ <= allowed, "{differ} node-views differ");
    let flagged = problem.flag_culled(&cut.node_views);
    let want_depth = splat::splat(&bsh.nodes, &v, &flagged, &layout).expect("cpu splat");
    let (coverage, depth) = differences(&atlas, &want_depth);
    assert_eq!((coverage, depth), (0, 0), "GPU vs CPU atlas");
    let drawn: Vec<u32> = cut
        .node_views
        .iter()
        .filter(|nv| problem.is_drawn(**nv))
        .map(|nv| nv.node)
        .collect();
    let want_ids = splat::nearest_nodes(&bsh.nodes, &v[0], &drawn, &layout);
    let same = ids.iter().zip(&want_ids).filter(|(a, b)| a == b).count();
    assert!(
        same * 1000 >= ids.len() * 999,
        "{same} of {} nearest nodes",
        ids.len()
    );
    let tile = w as usize;
    assert!(
        atlas[h as usize * tile..].iter().all(|&d| d == CLEAR),
        "nothing is splatted past the view's rows"
    );

    // The mesh's nearest depth at every pixel centre (NDC depth; ∞ where no triangle).
    let screen: Vec<Vec3> = p
        .iter()
        .map(|&q| {
            let c = view_proj * q.extend(1.0);
            let n = c.truncate() / c.w;
            Vec3::new(
                (n.x * 0.5 + 0.5) * w as f32,
                (0.5 - n.y * 0.5) * h as f32,
                n.z,
            )
        })
        .collect();
    let mut mesh = vec![f32::INFINITY; (w * h) as usize];
    for t in idx.chunks_exact(3) {
        let [a, b, c] = [0, 1, 2].map(|k| screen[t[k] as usize]);
        let area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
        if area == 0.0 {
            continue;
        }
        for y in 0..h {
            for x in 0..w {
                let q = glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                let edge = |u: Vec3, v: Vec3| {
                    ((v.x - u.x) * (q.y - u.y) - (v.y - u.y) * (q.x - u.x)) / area
                };
                let (l0, l1, l2) = (edge(b, c), edge(c, a), edge(a, b));
                if l0 >= 0.0 && l1 >= 0.0 && l2 >= 0.0 {
                    let d = &mut mesh[(y * w + x) as usize];
                    *d = d.min(l0 * a.z + l1 * b.z + l2 * c.z);
                }
            }
        }
    }
    let covered = |x: u32, y: u32| mesh[(y * w + x) as usize].is_finite();
    let linear = |d: f32| near * far / (far - d * (far - near));
    let (mut silhouette, mut missed, mut errors) = (0, 0, Vec::new());
    for y in 0..h {
        for x in 0..w {
            let edge = [(-1i32, 0i32), (1, 0), (0, -1), (0, 1)]
                .iter()
                .any(|&(dx, dy)| {
                    let (nx, ny) = (x as i32 + dx, y as i32 + dy);
                    nx >= 0
                        && ny >= 0
                        && (nx as u32) < w
                        && (ny as u32) < h
                        && covered(nx as u32, ny as u32) != covered(x, y)
                });
            silhouette += usize::from(edge);
            let word = atlas[(y * w) as usize + x as usize];
            let points = word != CLEAR;
            if points != covered(x, y) {
                missed += 1;
                if !edge {
                    eprintln!(
                        "pixel ({x}, {y}) differs: points {points}, mesh depth {}",
                        mesh[(y * w + x) as usize]
                    );
                }
            } else if points && !edge {
                // A drawn node is < 1 px wide, so its disc's depth (its centre's) is the
                // surface's somewhere within about a pixel: within the range of the mesh's
                // depths over the 3×3 pixels around, plus one pixel footprint.
                let truth = linear(mesh[(y * w + x) as usize]);
                let footprint = truth * 2.0 * (fov_y * 0.5).tan() / h as f32;
                let (mut lo, mut hi) = (truth, truth);
                for (nx, ny) in (x.saturating_sub(1)..(x + 2).min(w))
                    .flat_map(|nx| (y.saturating_sub(1)..(y + 2).min(h)).map(move |ny| (nx, ny)))
                {
                    let d = mesh[(ny * w + nx) as usize];
                    if d.is_finite() {
                        (lo, hi) = (lo.min(linear(d)), hi.max(linear(d)));
                    }
                }
                let got = linear(splat::unpack_depth(word));
                errors.push((got - truth).abs() / (hi - lo + footprint));
            }
        }
    }
    errors.sort_by(f32::total_cmp);
    let (median, p99) = (errors[errors.len() / 2], errors[errors.len() * 99 / 100]);
    eprintln!(
        "single view: {} node-views drawn, {missed} coverage differences on {silhouette} \
         silhouette pixels; depth error / allowed: median {median:.3}, 99th percentile {p99:.3}",
        drawn.len()
    );
    assert!(
        missed * 2 <= silhouette,
        "{missed} of {silhouette} silhouette pixels differ"
    );
    assert!(p99 <= 1.0, "depth error / allowed: 99th percentile {p99}");
}

/// The hybrid CPU/GPU cut (§3.7.3): every split of events and compaction between rayon and
/// the GPU finds the basic cut — the same node-views, iterations and work — and a list that
/// outgrows the capacity is an error.
#[test]
fn hybrid_splits_find_the_basic_cut() {
    use manylod::hybrid::{GpuHybridCut, Split, Unit};
    let Some(gpu) = gpu::test_device(&manylod::device_needs()) else {
        return;
    };
    let (bsh, _, _) = tree(1 << 12);
    let v = views_in_tiles(0.3, Some(TILE));
    let problem = CutProblem {
        bsh: &bsh,
        views: &v,
        epsilon: EPSILON,
    };
    let want = basic(&problem).expect("basic");
    let hybrid = GpuHybridCut::new(&gpu.device, &bsh, &v, EPSILON, 1 << 16).expect("set-up");
    for gpu_events in [0.0, 0.5, 1.0] {
        for compaction in [Unit::Cpu, Unit::Gpu] {
            let split = Split {
                gpu_events,
                compaction,
            };
            let (got, timing) = hybrid
                .cut(&gpu.device, &gpu.queue, &problem, split)
                .expect("hybrid cut");
            let differ = symmetric_difference(
                &sorted(got.node_views.clone()),
                &sorted(want.node_views.clone()),
            );
            let allowed = if gpu.is_software() || gpu_events == 0.0 {
                0
            } else {
                want.node_views.len() / 1000
            };
            assert!(
                differ <= allowed,
                "{}: {differ} node-views differ",
                split.name()
            );
            if differ == 0 {
                assert_eq!(
                    (got.iterations, got.processed, got.culled),
                    (want.iterations, want.processed, want.culled),
                    "{}",
                    split.name()
                );
            }
            assert!(timing.total_ms > 0.0);
        }
    }
    let small = GpuHybridCut::new(&gpu.device, &bsh, &v, EPSILON, 256).expect("set-up");
    let split = Split {
        gpu_events: 1.0,
        compaction: Unit::Gpu,
    };
    assert!(matches!(
        small.cut(&gpu.device, &gpu.queue, &problem, split),
        Err(ManyLodError::Capacity { .. })
    ));
    let bad = Split {
        gpu_events: 1.5,
        compaction: Unit::Cpu,
    };
    assert!(hybrid.cut(&gpu.device, &gpu.queue, &problem, bad).is_err());
}
