//! The paper's invariants on the CPU reference: bounds contain their subtrees, the criterion
//! decreases down the tree, every cut is valid (partition + criterion), incremental and
//! converged lazy cuts equal the basic cut.

use glam::Vec3;
use manylod::{
    Bsh, CutProblem, NodeView, View,
    bsh::{angle_between, level, parent},
    cut::{self, basic, refine, refine_levels, roots},
    surfels,
    view::{MAX_SPLAT_RADIUS, MIN_SPLAT_RADIUS},
};

mod common;

use common::{assert_partition, scene, sorted, tree, views};

/// Every node's sphere contains its leaves' discs' centres and its cone their normals.
#[test]
fn bounds_contain_their_subtrees() {
    let (bsh, pts, nrm) = tree(1 << 11);
    let mut seen = bsh.order.clone();
    seen.sort_unstable();
    assert_eq!(
        seen,
        (0..1 << 11).collect::<Vec<u32>>(),
        "order is a permutation"
    );
    for (i, node) in bsh.nodes.iter().enumerate() {
        let (lo, hi) = bsh.leaf_range(i as u32);
        assert_eq!(hi - lo, bsh.leaf_count() >> level(i as u32));
        for &p in &bsh.order[lo..hi] {
            let d = node.center.distance(pts[p as usize]) + bsh.leaf_radius;
            assert!(
                d <= node.radius * (1.0 + 1e-5) + 1e-5,
                "node {i}: point {p} outside by {}",
                d - node.radius
            );
            let a = angle_between(node.axis, nrm[p as usize]);
            assert!(
                a <= node.angle + 1e-4,
                "node {i}: normal {p} outside the cone ({a} > {})",
                node.angle
            );
        }
    }
    // The split choice: points spread along x split across x at the root.
    let pts: Vec<Vec3> = (0..64)
        .map(|k| Vec3::new(k as f32, (k % 4) as f32 * 0.1, 0.0))
        .collect();
    let b = Bsh::build(&pts, &vec![Vec3::Y; 64], 0.0).expect("line");
    let left: Vec<f32> = b.order[..32].iter().map(|&i| pts[i as usize].x).collect();
    assert!(
        left.iter().all(|&x| x < 32.0),
        "root split is not the median along x: {left:?}"
    );
}

/// After deforming the mesh, the refit bounds still contain every subtree.
#[test]
fn refit_bounds_contain_the_deformed_subtrees() {
    let (p, i) = scene();
    let s = surfels::sample(&p, &i, 1 << 10, 3).expect("surfels");
    let (pts, nrm) = surfels::evaluate(&s, &p, &i);
    let mut bsh = Bsh::build(&pts, &nrm, 0.01).expect("tree");
    let moved: Vec<Vec3> = p
        .iter()
        .map(|q| *q + Vec3::new((q.y * 2.0).sin() * 0.4, 0.0, q.x * 0.2))
        .collect();
    let (pts, nrm) = surfels::evaluate(&s, &moved, &i);
    bsh.refit(&pts, &nrm).expect("refit");
    for (k, node) in bsh.nodes.iter().enumerate() {
        let (lo, hi) = bsh.leaf_range(k as u32);
        for &q in &bsh.order[lo..hi] {
            assert!(
                node.center.distance(pts[q as usize]) + 0.01 <= node.radius * (1.0 + 1e-5) + 1e-5
            );
            assert!(angle_between(node.axis, nrm[q as usize]) <= node.angle + 1e-4);
        }
    }
}

/// c decreases from parent to child for every node and view.
#[test]
fn criterion_decreases_down_the_tree() {
    let (bsh, _, _) = tree(1 << 10);
    for v in views(0.3) {
        for i in 1..bsh.nodes.len() {
            let c = v.criterion(&bsh.nodes[i]);
            let cp = v.criterion(&bsh.nodes[parent(i as u32) as usize]);
            assert!(
                c <= cp * (1.0 + 1e-5) + 1e-6,
                "node {i}: {c} > parent {cp} in {v:?}"
            );
        }
    }
}

/// A node's disc in a paraboloid view is never wider than its criterion says (the criterion
/// measures at the largest scale the sphere reaches), and no wider than the rim's scale makes it.
#[test]
fn criterion_bounds_the_splatted_disc() {
    let (bsh, _, _) = tree(1 << 10);
    let mut checked = 0;
    for v in views(0.3) {
        let View::Paraboloid { size, .. } = v else {
            continue;
        };
        for node in &bsh.nodes {
            let c = v.criterion(node);
            let Some(s) = v.splat(node, 100.0) else {
                continue;
            };
            if c == 0.0 || s.radius <= MIN_SPLAT_RADIUS || s.radius >= MAX_SPLAT_RADIUS {
                continue;
            }
            let rim =
                2.0 * (node.radius / (node.center - v.eye()).length()).asin() * size as f32 * 0.5;
            assert!(
                2.0 * s.radius <= c * (1.0 + 1e-5),
                "disc {} px > c {c}",
                2.0 * s.radius
            );
            assert!(c <= rim * (1.0 + 1e-5), "c {c} > rim scale {rim}");
            checked += 1;
        }
    }
    assert!(checked > 1000, "only {checked} discs checked");
}

/// Per view: cut nodes cover every leaf exactly once, every visible leaf by a drawn node; every
/// cut node is valid and its parent is not.
fn assert_valid_cut(problem: &CutProblem, cut: &[NodeView]) {
    let n = problem.bsh.leaf_count();
    for v in 0..problem.views.len() as u32 {
        let mut cover = vec![0u8; n];
        let mut drawn = vec![false; n];
        for nv in cut.iter().filter(|nv| nv.view == v) {
            let (lo, hi) = problem.bsh.leaf_range(nv.node);
            for k in lo..hi {
                cover[k] += 1;
                drawn[k] |= problem.is_drawn(*nv);
            }
            {
                assert!(problem.is_valid(*nv), "view {v}: {nv:?} is not valid");
                if nv.node > 0 {
                    let p = NodeView {
                        node: parent(nv.node),
                        view: v,
                    };
                    assert!(!problem.is_valid(p), "view {v}: parent of {nv:?} is valid");
                }
            }
        }
        assert!(
            cover.iter().all(|&c| c == 1),
            "view {v}: leaves covered {:?} times",
            cover.iter().filter(|&&c| c != 1).collect::<Vec<_>>()
        );
        for (k, &d) in drawn.iter().enumerate() {
            let leaf = NodeView {
                node: (n - 1 + k) as u32,
                view: v,
            };
            assert!(
                d || !problem.is_drawn(leaf),
                "view {v}: visible leaf {k} only under culled nodes"
            );
        }
    }
}

#[test]
fn basic_cut_is_valid() {
    let (bsh, _, _) = tree(1 << 12);
    let v = views(0.0);
    for epsilon in [1.0, 4.0, 16.0] {
        let problem = CutProblem {
            bsh: &bsh,
            views: &v,
            epsilon,
        };
        let cut = basic(&problem).expect("cut");
        assert!(cut.converged);
        assert_eq!(
            cut.iterations,
            bsh.depth + 1,
            "ε {epsilon}: one iteration per level at most"
        );
        assert_valid_cut(&problem, &cut.node_views);
        let drawn = cut
            .node_views
            .iter()
            .filter(|nv| problem.is_drawn(**nv))
            .count();
        assert!(
            drawn > v.len() && drawn < cut.node_views.len(),
            "ε {epsilon}: {drawn} drawn of {}",
            cut.node_views.len()
        );
    }
}

/// Moving the views ~10° per frame: the incremental cut from last frame's equals the basic cut
/// and takes less work.
#[test]
fn incremental_cut_equals_the_basic_cut() {
    let (bsh, _, _) = tree(1 << 12);
    let epsilon = 3.0;
    let v0 = views(0.0);
    let mut last = basic(&CutProblem {
        bsh: &bsh,
        views: &v0,
        epsilon,
    })
    .expect("basic")
    .node_views;
    for frame in 1..=4 {
        let v = views(frame as f32 * 10f32.to_radians());
        let problem = CutProblem {
            bsh: &bsh,
            views: &v,
            epsilon,
        };
        let want = basic(&problem).expect("basic");
        let inc = refine(&problem, last, None).expect("incremental");
        assert!(inc.converged);
        assert_eq!(
            sorted(inc.node_views.clone()),
            sorted(want.node_views.clone()),
            "frame {frame}"
        );
        assert!(
            inc.processed < want.processed,
            "frame {frame}: incremental {} vs basic {} node-views",
            inc.processed,
            want.processed
        );
        assert_valid_cut(&problem, &inc.node_views);
        last = inc.node_views;
    }
}

/// Iterations descending several tree levels: the same basic and incremental cuts from the
/// same work in ⌈(depth + 1) / levels⌉ iterations; lazy cuts under motion still partition every
/// view's leaves; a level count out of range is an error.
#[test]
fn iterations_of_several_levels_find_the_same_cuts() {
    let (bsh, _, _) = tree(1 << 12);
    let epsilon = 3.0;
    let (v0, v1) = (views(0.0), views(10f32.to_radians()));
    let problem = |v| CutProblem {
        bsh: &bsh,
        views: v,
        epsilon,
    };
    let want = basic(&problem(&v0)).expect("basic");
    assert_eq!(want.iterations, bsh.depth + 1, "the cut reaches the leaves");
    let want_next = refine(&problem(&v1), want.node_views.clone(), None).expect("incremental");
    for levels in 1..=cut::MAX_LEVELS_PER_ITERATION {
        let got = refine_levels(&problem(&v0), roots(v0.len()), None, levels).expect("basic");
        assert_eq!(
            sorted(got.node_views.clone()),
            sorted(want.node_views.clone()),
            "{levels} levels"
        );
        assert_eq!(
            (got.iterations, got.processed, got.converged, got.culled),
            (
                (bsh.depth + 1).div_ceil(levels),
                want.processed,
                true,
                want.culled
            ),
            "{levels} levels: iterations, work, converged, culled"
        );
        let next = refine_levels(&problem(&v1), got.node_views, None, levels).expect("inc");
        assert_eq!(
            sorted(next.node_views),
            sorted(want_next.node_views.clone()),
            "{levels} levels, incremental"
        );
        assert_eq!(
            next.processed, want_next.processed,
            "{levels} levels, incremental work"
        );
        let mut lazy = roots(v0.len());
        for frame in 0..6 {
            let v = views(frame as f32 * 10f32.to_radians());
            let moved = CutProblem {
                bsh: &bsh,
                views: &v,
                epsilon,
            };
            let l = refine_levels(&moved, lazy, Some(2), levels).expect("lazy");
            assert_partition(&moved, &l.node_views, frame);
            lazy = l.node_views;
        }
    }
    for levels in [0, cut::MAX_LEVELS_PER_ITERATION + 1] {
        assert_eq!(
            refine_levels(&problem(&v0), roots(v0.len()), None, levels)
                .err()
                .map(|e| e.to_string()),
            Some(format!(
                "{levels} tree levels per iteration: must be 1 to {}",
                cut::MAX_LEVELS_PER_ITERATION
            ))
        );
    }
}

/// Lazy cuts (q = 1 iteration per frame) from the roots reach the basic cut.
#[test]
fn lazy_cut_converges_to_the_basic_cut() {
    let (bsh, _, _) = tree(1 << 12);
    let v = views(0.5);
    let problem = CutProblem {
        bsh: &bsh,
        views: &v,
        epsilon: 3.0,
    };
    let want = sorted(basic(&problem).expect("basic").node_views);
    let mut lazy = roots(v.len());
    for frame in 0..=bsh.depth {
        let l = refine(&problem, lazy, Some(1)).expect("lazy");
        assert_eq!(l.iterations, 1);
        assert_eq!(l.converged, frame == bsh.depth, "frame {frame}");
        lazy = l.node_views;
    }
    assert_eq!(sorted(lazy), want, "lazy converged");
}

/// Lazy cuts under views moving 10° per frame (q = 2): what a frame leaves (cut and leftover
/// active node-views) still covers every leaf exactly once — the paper's one-level merge loses
/// leaves here — and once the views stop, the lazy cut reaches the basic cut.
#[test]
fn lazy_cut_under_motion_stays_a_partition() {
    let (bsh, _, _) = tree(1 << 12);
    let epsilon = 3.0;
    let mut lazy = roots(views(0.0).len());
    let mut unconverged = 0;
    for frame in 0..24 {
        let v = views(frame as f32 * 10f32.to_radians());
        let problem = CutProblem {
            bsh: &bsh,
            views: &v,
            epsilon,
        };
        let l = refine(&problem, lazy, Some(2)).expect("lazy");
        unconverged += u32::from(!l.converged);
        assert_partition(&problem, &l.node_views, frame);
        lazy = l.node_views;
    }
    assert!(unconverged > 4, "the motion should keep the lazy cut busy");
    let v = views(23.0 * 10f32.to_radians());
    let problem = CutProblem {
        bsh: &bsh,
        views: &v,
        epsilon,
    };
    let l = refine(&problem, lazy, None).expect("converge");
    assert_eq!(
        sorted(l.node_views),
        sorted(basic(&problem).expect("basic").node_views)
    );
}

#[test]
fn bad_input_is_an_error() {
    let (p, i) = scene();
    assert!(
        surfels::sample(&p, &i, 1000, 1).is_err(),
        "not a power of two"
    );
    assert!(
        surfels::sample(&p, &i[..4], 1024, 1).is_err(),
        "indices not triangles"
    );
    assert!(
        surfels::sample(&p, &[0, 1, 99999], 1024, 1).is_err(),
        "index out of range"
    );
    let mut q = p.clone();
    q[3] = Vec3::NAN;
    assert!(surfels::sample(&q, &i, 1024, 1).is_err(), "NaN");
    assert!(
        surfels::sample(&[Vec3::ZERO; 3], &[0, 1, 2], 1024, 1).is_err(),
        "no area"
    );
    assert!(
        Bsh::build(&[Vec3::ZERO; 3], &[Vec3::Y; 3], 0.1).is_err(),
        "3 points"
    );
    let (bsh, _, _) = tree(256);
    let bad = [View::Paraboloid {
        position: Vec3::ZERO,
        normal: Vec3::new(0.0, 2.0, 0.0),
        size: 32,
    }];
    assert!(
        basic(&CutProblem {
            bsh: &bsh,
            views: &bad,
            epsilon: 1.0
        })
        .is_err(),
        "non-unit normal"
    );
    let ok = views(0.0);
    assert!(
        basic(&CutProblem {
            bsh: &bsh,
            views: &ok,
            epsilon: 0.0
        })
        .is_err(),
        "ε = 0"
    );
    assert!(
        refine(
            &CutProblem {
                bsh: &bsh,
                views: &ok,
                epsilon: 1.0
            },
            vec![NodeView {
                node: 9999,
                view: 0
            }],
            None
        )
        .is_err()
    );
}
