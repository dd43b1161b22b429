//! VPL shadow maps split into batches of views (devices whose storage bindings cannot hold
//! every view's node-view list, e.g. llvmpipe's and many GPUs' 128 MiB, or whose textures
//! cannot hold every hemicube) give the same atlas, bit for bit, as one batch: cuts and
//! hemicubes are per view, and every batch writes into the one atlas (hemicubes up to the
//! rasteriser's sub-pixel rounding).

use instant_radiosity::{
    shadows::{ShadowConfig, VplShadowMaps, VplShadows},
    vpl,
};

fn atlas(
    gpu: &gpu::Gpu,
    mode: VplShadows,
    list_bytes: Option<u64>,
    frames: u32,
) -> (Vec<u32>, usize) {
    let scene = scene::cornell_box();
    let bvh = scene::Bvh::build(&scene);
    let set = vpl::generate_from_primary(&scene, &bvh, 48, 4, 3).expect("vpls");
    let config = ShadowConfig {
        points_log2: 14,
        tile: 16,
        ism_points: 512,
        list_bytes,
        ..ShadowConfig::for_mode(mode)
    };
    let mut maps =
        VplShadowMaps::new(&gpu.device, &scene, &set, mode, &config).expect("shadow maps");
    for _ in 0..frames {
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        maps.encode(&mut encoder, None);
        gpu.queue.submit([encoder.finish()]);
    }
    let atlas = maps.read_atlas(&gpu.device, &gpu.queue).expect("atlas");
    (atlas, maps.batch_count())
}

#[test]
fn batched_views_give_the_same_atlas_as_one_batch() {
    let Some(gpu) = gpu::test_device(&instant_radiosity::device_needs()) else {
        return;
    };
    // ManyLoD: 16 × 16 × 24 node-views of 8 bytes per view; 20 views' worth per list gives
    // 3 batches of 48 views. Two frames: the basic cut, then an incremental one.
    let per_view = 16 * 16 * 24 * 8;
    for frames in [1, 2] {
        let (one, batches) = atlas(&gpu, VplShadows::ManyLod, None, frames);
        assert_eq!(batches, 1, "the default limits hold 48 views' lists");
        let (split, batches) = atlas(&gpu, VplShadows::ManyLod, Some(20 * per_view), frames);
        assert_eq!(batches, 3);
        assert!(one.iter().any(|&w| w != u32::MAX), "the atlas holds splats");
        assert!(
            one == split,
            "ManyLoD, {frames} frames: batched atlas differs"
        );
    }
    // ISM: 512 points of 8 bytes per view; 7 views per list gives 7 batches.
    let (one, _) = atlas(&gpu, VplShadows::Ism, None, 1);
    let (split, batches) = atlas(&gpu, VplShadows::Ism, Some(7 * 512 * 8), 1);
    assert_eq!(batches, 7);
    assert!(one == split, "ISM: batched atlas differs");
    // Rasterised hemicubes: 5 faces of 32 × 32 depths (4 KiB each) per view; 4 views' faces
    // per face atlas gives 12 batches.
    let (one, batches) = atlas(gpu, VplShadows::Rasterised, None, 1);
    assert_eq!(batches, 1);
    let (split, batches) = atlas(gpu, VplShadows::Rasterised, Some(4 * 5 * 32 * 32 * 4), 1);
    assert_eq!(batches, 12);
    assert!(one.iter().any(|&w| w != u32::MAX), "the atlas holds depths");
    // Faces sit at other viewport offsets in other batches, so the rasteriser's sub-pixel
    // rounding may move depths in the last bits (measured: 831 of 12 544 texels, at most
    // 4.7e-4 of the far distance); coverage (empty or not) must not change.
    for (a, b) in one.iter().zip(&split) {
        let (da, db) = (
            manylod::splat::unpack_depth(*a),
            manylod::splat::unpack_depth(*b),
        );
        assert!(
            (*a == u32::MAX) == (*b == u32::MAX) && (da - db).abs() <= 1e-3,
            "rasterised: batched atlas differs ({da} vs {db})"
        );
    }
}
