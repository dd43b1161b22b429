//! ManyLoD VPL shadow maps follow a moving mesh by refitting their hierarchy (Holländer 2013
//! §3.5.3). Moved rigidly as a whole (VPLs too), the refit tree is the fresh tree moved: the
//! atlas equals maps built afresh on the moved scene; maps left at the old positions do not.
//! The ISM baseline's points follow the refit leaves the same way.
//! Moved in parts (the Cornell blocks alone), a refit tree keeps its old grouping, so its
//! spheres grow and its cuts drift from a fresh build's — still nearer than the stale maps.

use glam::Vec3;
use instant_radiosity::{
    shadows::{ShadowConfig, VplShadowMaps, VplShadows, scene_mesh},
    vpl::{self, VplSet},
};
use scene::Scene;

/// Fraction of atlas texels whose coverage differs or whose depths differ by more than 2 % of
/// the far distance.
fn disagreement(a: &[u32], b: &[u32]) -> f64 {
    let differ = a
        .iter()
        .zip(b)
        .filter(|&(&x, &y)| {
            let (dx, dy) = (
                manylod::splat::unpack_depth(x),
                manylod::splat::unpack_depth(y),
            );
            (x == u32::MAX) != (y == u32::MAX) || (dx - dy).abs() > 0.02
        })
        .count();
    differ as f64 / a.len() as f64
}

const CONFIG: ShadowConfig = ShadowConfig {
    points_log2: 15,
    epsilon: 2.0,
    tile: 16,
    ism_points: 8192,
    bias: 0.01,
    normal_offset: 1.0,
    slope: 0.0,
    list_bytes: None,
    refit: true,
};

/// The atlas of `mode` maps built on `scene` for `set`, after a first frame moved to `moved` (its
/// mesh positions, its VPLs) when given, and two more frames.
fn atlas(
    gpu: &gpu::Gpu,
    mode: VplShadows,
    (scene, set): (&Scene, &VplSet),
    moved: Option<(Option<&Scene>, &VplSet)>,
) -> Vec<u32> {
    let config = ShadowConfig {
        ism_points: 512,
        ..CONFIG
    };
    let mut maps = VplShadowMaps::new(&gpu.device, scene, set, mode, &config).expect("maps");
    let frame = |maps: &mut VplShadowMaps| {
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        maps.encode(&mut encoder, None);
        gpu.queue.submit([encoder.finish()]);
    };
    frame(&mut maps);
    if let Some((mesh, vpls)) = moved {
        if let Some(mesh) = mesh {
            maps.set_positions(&gpu.queue, &scene_mesh(mesh).0)
                .expect("positions");
        }
        maps.set_vpls(&gpu.queue, vpls).expect("vpls");
    }
    frame(&mut maps);
    frame(&mut maps);
    maps.read_atlas(&gpu.device, &gpu.queue).expect("atlas")
}

/// `scene` with the meshes `which` accepts moved by `d`.
fn moved(scene: &Scene, d: Vec3, which: impl Fn(&str) -> bool) -> Scene {
    let mut s = scene.clone();
    for m in s.meshes.iter_mut().filter(|m| which(&m.name)) {
        for p in &mut m.positions {
            *p += d;
        }
    }
    s
}

#[test]
fn refit_maps_follow_a_moved_mesh() {
    let Some(gpu) = gpu::test_device(&instant_radiosity::device_needs()) else {
        return;
    };
    let before = scene::cornell_box();
    let bvh = scene::Bvh::build(&before);
    let set = vpl::generate_from_primary(&before, &bvh, 32, 4, 5).expect("vpls");
    // The whole box and its VPLs moved rigidly.
    let d = Vec3::new(0.05, 0.02, -0.03);
    let after = moved(&before, d, |_| true);
    let mut set_after = set.clone();
    for v in &mut set_after.vpls {
        v.position += d;
    }
    let fresh = atlas(gpu, VplShadows::ManyLod, (&after, &set_after), None);
    let refit = atlas(
        gpu,
        VplShadows::ManyLod,
        (&before, &set),
        Some((Some(&after), &set_after)),
    );
    let stale = atlas(
        gpu,
        VplShadows::ManyLod,
        (&before, &set),
        Some((None, &set_after)),
    );
    let (refit_off, stale_off) = (disagreement(&refit, &fresh), disagreement(&stale, &fresh));
    println!("rigid move: refit vs fresh {refit_off:.4}, stale vs fresh {stale_off:.4}");
    assert!(stale_off > 0.02, "the move changes the maps ({stale_off})");
    assert!(
        refit_off < 0.005,
        "refit maps {refit_off} off the fresh ones"
    );
    // The ISM points follow the refit leaves: the same rigid move, the same test.
    let ism = VplShadows::Ism;
    let fresh = atlas(gpu, ism, (&after, &set_after), None);
    let refit = atlas(gpu, ism, (&before, &set), Some((Some(&after), &set_after)));
    let stale = atlas(gpu, ism, (&before, &set), Some((None, &set_after)));
    let (refit_off, stale_off) = (disagreement(&refit, &fresh), disagreement(&stale, &fresh));
    println!("ISM rigid move: refit vs fresh {refit_off:.4}, stale vs fresh {stale_off:.4}");
    assert!(stale_off > 0.02, "the move changes the ISM ({stale_off})");
    // Measured 1.8 % on llvmpipe against 64 % for the stale points: each view's random subset
    // picks leaves by their index in the tree, which a fresh build orders slightly otherwise.
    assert!(refit_off < 0.05, "refit ISM {refit_off} off the fresh one");
    // The blocks alone moved: the refit is nearer the fresh maps than the stale ones are.
    let blocks = moved(&before, Vec3::new(-0.03, 0.0, 0.015), |n| n == "blocks");
    let fresh = atlas(gpu, VplShadows::ManyLod, (&blocks, &set), None);
    let refit = atlas(
        gpu,
        VplShadows::ManyLod,
        (&before, &set),
        Some((Some(&blocks), &set)),
    );
    let stale = atlas(gpu, VplShadows::ManyLod, (&before, &set), None);
    let (refit_off, stale_off) = (disagreement(&refit, &fresh), disagreement(&stale, &fresh));
    println!("blocks moved: refit vs fresh {refit_off:.4}, stale vs fresh {stale_off:.4}");
    assert!(
        refit_off < stale_off,
        "refit {refit_off}, stale {stale_off}"
    );
    // Maps made without refit refuse new positions with a clear error.
    let mut plain = VplShadowMaps::new(
        &gpu.device,
        &before,
        &set,
        VplShadows::ManyLod,
        &ShadowConfig {
            refit: false,
            ..CONFIG
        },
    )
    .expect("maps");
    let e = plain
        .set_positions(&gpu.queue, &scene_mesh(&after).0)
        .unwrap_err();
    assert!(e.to_string().contains("refit"), "{e}");
}
