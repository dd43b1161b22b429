//! Discontinuity buffer, edge-aware blur and interleaved shading (Segovia 2006 §4.3, §4.5).
//!
//! Tolerances:
//! - discontinuity buffer: none, CPU == GPU exactly (integer normals, single correctly rounded
//!   products);
//! - plain blur: |GPU − CPU| ≤ 2⁻⁹ · max(1, |CPU|) per channel — both store f16 after each pass,
//!   and the f32 sums may round differently, which can move the result by one f16 step (2⁻¹¹
//!   relative) per pass, twice;
//! - fast blur: the same bound; the hardware bilinear filter at the exact midpoint of two
//!   texels is exact up to its own f32 rounding;
//! - shading: 2⁻⁹ relative (normal decoding and the light sum in f32, then f16).

use gbuffer::{Image, normal::pack_octahedral};
use glam::Vec3;
use interleave::{
    Blur, BlurVariant, Pattern, SplitLayout, SplitVariant, Thresholds,
    cpu::{self, SubsetLight},
    gpu::{self as igpu, Shading},
};
use proptest::prelude::*;

const BLUR_TOL: f32 = 1.0 / 512.0;
const SHADE_TOL: f32 = 1.0 / 512.0;

/// A small scene's G-buffer from the CPU rasterizer: linear depth and normals.
fn scene_gbuffer(width: u32, height: u32, spheres: u32) -> (Image<f32>, Image<u32>) {
    let scene = scene::spheres_on_plane(spheres);
    let camera = scene.camera_or_framed();
    let gb = gbuffer::cpu::rasterize(&scene, &camera, width, height)
        .expect("rasterize")
        .gbuffer;
    (gb.linear_depth, gb.normal)
}

/// Two surfaces: a disc of depth 5 facing +z in front of a wall of depth 1 facing +y... and
/// any pixel-wise noise in the irradiance. Returns (depth, normals, in_disc).
fn two_surfaces(size: u32) -> (Image<f32>, Image<u32>, Image<bool>) {
    let c = size as f32 / 2.0;
    let in_disc = |x: u32, y: u32| {
        let (dx, dy) = (x as f32 + 0.5 - c, y as f32 + 0.5 - c * 0.8);
        dx * dx + dy * dy < (size as f32 * 0.3).powi(2)
    };
    let mut depth = Image::filled(size, size, 1.0f32);
    let mut normals = Image::filled(size, size, pack_octahedral(Vec3::Y));
    let mut mask = Image::filled(size, size, false);
    for y in 0..size {
        for x in 0..size {
            if in_disc(x, y) {
                depth.set(x, y, 5.0);
                normals.set(x, y, pack_octahedral(Vec3::Z));
                mask.set(x, y, true);
            }
        }
    }
    (depth, normals, mask)
}

fn noise(width: u32, height: u32, seed: u32) -> Image<[f32; 4]> {
    let mut s = seed.wrapping_mul(2_654_435_761) | 1;
    let mut next = move || {
        s ^= s << 13;
        s ^= s >> 17;
        s ^= s << 5;
        (s >> 8) as f32 / (1 << 24) as f32
    };
    let data = (0..width * height)
        .map(|_| cpu::to_f16([next() * 4.0, next(), next() * 0.25, 1.0]))
        .collect();
    Image::from_vec(width, height, data).expect("size")
}

fn assert_close(cpu: &Image<[f32; 4]>, gpu: &Image<[f32; 4]>, tol: f32, what: &str) {
    let mut worst = (0.0f32, 0, 0);
    for y in 0..cpu.height() {
        for x in 0..cpu.width() {
            for (a, b) in cpu.get(x, y).iter().zip(gpu.get(x, y)) {
                let err = (a - b).abs() / a.abs().max(1.0);
                if err > worst.0 {
                    worst = (err, x, y);
                }
            }
        }
    }
    assert!(
        worst.0 <= tol,
        "{what}: relative error {} at {:?} (cpu {:?}, gpu {:?})",
        worst.0,
        (worst.1, worst.2),
        cpu.get(worst.1, worst.2),
        gpu.get(worst.1, worst.2)
    );
}

#[test]
fn discontinuities_follow_the_definition() {
    let (depth, normals, mask) = two_surfaces(40);
    let disc = cpu::discontinuity(&depth, &normals, &Thresholds::default()).expect("disc");
    for y in 0..40 {
        for x in 0..40 {
            let here = mask.get(x, y);
            let differs = [(x + 1, y), (x, y + 1), (x + 1, y + 1)]
                .into_iter()
                .any(|(a, b)| a < 40 && b < 40 && mask.get(a, b) != here);
            let [r, g, _, a] = disc.get(x, y);
            assert_eq!(
                (r == 255, g == 255, a),
                (differs, differs, 255),
                "pixel ({x}, {y})"
            );
        }
    }
    // Thresholds are strict: a 20° crease is continuous at 30° and a discontinuity at 10°.
    let crease = Image::from_vec(
        2,
        1,
        vec![
            pack_octahedral(Vec3::Z),
            pack_octahedral(Vec3::new(
                0.0,
                20f32.to_radians().sin(),
                20f32.to_radians().cos(),
            )),
        ],
    )
    .expect("img");
    let flat = Image::filled(2, 1, 3.0f32);
    let at = |deg: f32| {
        cpu::discontinuity(
            &flat,
            &crease,
            &Thresholds {
                normal_deg: deg,
                depth_ratio: 0.05,
            },
        )
        .expect("disc")
        .get(0, 0)[0]
    };
    assert_eq!((at(30.0), at(10.0)), (0, 255));
    // Depth: 3 → 3.2 is a 6.7 % step.
    let step = Image::from_vec(2, 1, vec![3.0f32, 3.2]).expect("img");
    let same = Image::filled(2, 1, pack_octahedral(Vec3::Z));
    let at = |ratio: f32| {
        cpu::discontinuity(
            &step,
            &same,
            &Thresholds {
                normal_deg: 30.0,
                depth_ratio: ratio,
            },
        )
        .expect("disc")
        .get(0, 0)[1]
    };
    assert_eq!((at(0.1), at(0.05)), (0, 255));
    assert!(
        cpu::discontinuity(
            &step,
            &same,
            &Thresholds {
                normal_deg: 0.0,
                depth_ratio: 0.1
            }
        )
        .is_err()
    );
    assert!(
        cpu::discontinuity(
            &step,
            &same,
            &Thresholds {
                normal_deg: 30.0,
                depth_ratio: f32::NAN
            }
        )
        .is_err()
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(12))]

    #[test]
    fn gpu_discontinuity_buffer_equals_cpu(
        width in 8u32..120, height in 8u32..120, spheres in 1u32..12,
        normal_deg in 1.0f32..179.0, depth_ratio in 0.0f32..0.3,
    ) {
        let Some(gpu) = gpu::test_device(&interleave::device_needs()) else { return Ok(()) };
        let (depth, normals) = scene_gbuffer(width, height, spheres);
        let t = Thresholds { normal_deg, depth_ratio };
        let expected = cpu::discontinuity(&depth, &normals, &t).expect("cpu");
        let got = igpu::run_discontinuity(gpu, &depth, &normals, &t).expect("gpu");
        prop_assert!(got == expected, "discontinuity buffers differ ({t:?})");
    }
}

#[test]
fn gpu_discontinuity_buffer_on_random_normals() {
    let Some(gpu) = gpu::test_device(&interleave::device_needs()) else {
        return;
    };
    // Random words cover every octahedral case (both hemispheres, ±32768) at once.
    let mut s = 0x9e37_79b9u32;
    let words: Vec<u32> = (0..97 * 61)
        .map(|_| {
            s ^= s << 13;
            s ^= s >> 17;
            s ^= s << 5;
            s
        })
        .collect();
    let depths: Vec<f32> = words.iter().map(|w| (w >> 20) as f32 * 0.01).collect();
    let normals = Image::from_vec(97, 61, words).expect("img");
    let depth = Image::from_vec(97, 61, depths).expect("img");
    for deg in [5.0, 45.0, 90.0, 135.0] {
        let t = Thresholds {
            normal_deg: deg,
            depth_ratio: 0.02,
        };
        let expected = cpu::discontinuity(&depth, &normals, &t).expect("cpu");
        let got = igpu::run_discontinuity(gpu, &depth, &normals, &t).expect("gpu");
        assert!(got == expected, "discontinuity buffers differ at {deg}°");
    }
}

fn blurs() -> impl Iterator<Item = Blur> {
    [5, 7, 11, 17].into_iter().flat_map(|k| {
        [BlurVariant::Plain, BlurVariant::Fast].map(|v| Blur::new(k, v).expect("blur"))
    })
}

#[test]
fn constant_image_stays_constant() {
    let (depth, normals) = scene_gbuffer(64, 48, 6);
    let disc = cpu::discontinuity(&depth, &normals, &Thresholds::default()).expect("disc");
    let c = cpu::to_f16([0.3, 1.7, 0.01, 1.0]);
    let constant = Image::filled(64, 48, c);
    for blur in blurs() {
        assert_eq!(
            cpu::blur(&constant, &disc, &blur).expect("blur"),
            constant,
            "{blur:?}"
        );
        if let Some(gpu) = gpu::test_device(&interleave::device_needs()) {
            let got = igpu::run_blur(gpu, &constant, &disc, &blur).expect("gpu blur");
            assert!(got == constant, "GPU {blur:?}");
        }
    }
}

#[test]
fn blur_never_mixes_across_a_discontinuity() {
    // 64×64 (a power of two, so the GPU's bilinear lookups land exactly on texel centres and
    // midpoints; see docs/interleave.md).
    let (depth, normals, in_disc) = two_surfaces(64);
    let disc = cpu::discontinuity(&depth, &normals, &Thresholds::default()).expect("disc");
    let base = noise(64, 64, 1);
    let mut changed = base.clone();
    for y in 0..64 {
        for x in 0..64 {
            if in_disc.get(x, y) {
                changed.set(x, y, cpu::to_f16([9.0, 0.0, 3.0, 1.0]));
            }
        }
    }
    let gpu = gpu::test_device(&interleave::device_needs());
    for blur in blurs() {
        let mut results = vec![(
            "CPU",
            cpu::blur(&base, &disc, &blur).expect("blur"),
            cpu::blur(&changed, &disc, &blur).expect("blur"),
        )];
        if let Some(gpu) = gpu {
            results.push((
                "GPU",
                igpu::run_blur(gpu, &base, &disc, &blur).expect("blur"),
                igpu::run_blur(gpu, &changed, &disc, &blur).expect("blur"),
            ));
        }
        for (who, a, b) in results {
            let mut blended = 0;
            for y in 0..64 {
                for x in 0..64 {
                    if !in_disc.get(x, y) {
                        assert_eq!(
                            a.get(x, y),
                            b.get(x, y),
                            "{who} {blur:?}: wall pixel ({x}, {y}) saw the disc"
                        );
                        blended += usize::from(a.get(x, y) != base.get(x, y));
                    }
                }
            }
            assert!(
                blended > 2000,
                "{who} {blur:?}: only {blended} wall pixels were blurred at all"
            );
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(8))]

    #[test]
    fn gpu_blur_matches_cpu(width in 8u32..100, height in 8u32..100, spheres in 1u32..10, seed in any::<u32>()) {
        let Some(gpu) = gpu::test_device(&interleave::device_needs()) else { return Ok(()) };
        let (depth, normals) = scene_gbuffer(width, height, spheres);
        let disc = cpu::discontinuity(&depth, &normals, &Thresholds::default()).expect("disc");
        let irradiance = noise(width, height, seed);
        for blur in blurs() {
            let expected = cpu::blur(&irradiance, &disc, &blur).expect("cpu");
            let got = igpu::run_blur(gpu, &irradiance, &disc, &blur).expect("gpu");
            assert_close(&expected, &got, BLUR_TOL, &format!("{blur:?} {width}×{height}"));
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(6))]

    /// The one-dispatch discontinuity buffer + blur equals the CPU's discontinuity buffer
    /// exactly and its blur of each image within the blur tolerance, across tile borders
    /// (sizes not multiples of 16, walks up to radius 8).
    #[test]
    fn gpu_discontinuity_blur_equals_cpu(width in 8u32..100, height in 8u32..100, spheres in 1u32..10, seed in any::<u32>()) {
        let Some(gpu) = gpu::test_device(&interleave::device_needs()) else { return Ok(()) };
        let (depth, normals) = scene_gbuffer(width, height, spheres);
        let t = Thresholds::default();
        let disc = cpu::discontinuity(&depth, &normals, &t).expect("disc");
        let images = [noise(width, height, seed), noise(width, height, seed ^ 0x9e37_79b9)];
        for blur in blurs() {
            let (got_disc, got) = igpu::run_discontinuity_blur(gpu, (&depth, &normals), images.each_ref(), &t, &blur).expect("gpu");
            prop_assert!(got_disc == disc, "discontinuity buffers differ ({:?})", blur);
            for (image, got) in images.iter().zip(&got) {
                let expected = cpu::blur(image, &disc, &blur).expect("cpu");
                assert_close(&expected, got, BLUR_TOL, &format!("{blur:?} {width}×{height}"));
            }
        }
    }
}

#[test]
fn blur_rejects_bad_kernels() {
    for k in [0, 3, 4, 6, 19] {
        assert!(Blur::new(k, BlurVariant::Plain).is_err(), "kernel {k}");
    }
}

/// One light per subset, its colour naming the subset: red = s + 1.
fn subset_lights(pattern: Pattern, per_subset: u32) -> Vec<SubsetLight> {
    (0..pattern.count() * per_subset)
        .map(|l| {
            let s = l / per_subset;
            let d = Vec3::new((l as f32 * 0.7).sin(), 1.0, (l as f32 * 1.3).cos()).normalize();
            SubsetLight {
                direction: [d.x, d.y, d.z, 0.0],
                color: [(s + 1) as f32 / per_subset as f32, 0.5, 0.25, 0.0],
            }
        })
        .collect()
}

#[test]
fn each_pixel_sees_only_its_subset() {
    // Every pixel faces +y and all lights are above it, so red = (s + 1)·Σcos/per_subset ≠ 0
    // exactly for its own subset s.
    let layout = SplitLayout::new(13, 7, Pattern::new(4, 3).expect("p")).expect("layout");
    let depth = Image::filled(13, 7, 2.0f32);
    let normals = Image::filled(13, 7, pack_octahedral(Vec3::Y));
    let lights: Vec<SubsetLight> = (0..12)
        .map(|s| SubsetLight {
            direction: [0.0, 1.0, 0.0, 0.0],
            color: [s as f32 + 1.0, 0.0, 0.0, 0.0],
        })
        .collect();
    let e = cpu::shade_subsets(&depth, &normals, &lights, &layout).expect("shade");
    for y in 0..7 {
        for x in 0..13 {
            assert_eq!(
                e.get(x, y)[0],
                ((y % 3) * 4 + x % 4 + 1) as f32,
                "pixel ({x}, {y})"
            );
        }
    }
    assert!(cpu::shade_subsets(&depth, &normals, &lights[..11], &layout).is_err());
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(8))]

    #[test]
    fn gpu_fused_shading_equals_split_shade_gather_and_cpu(
        width in 8u32..110, height in 8u32..110, n in 1u32..9, m in 1u32..7, per_subset in 1u32..5,
    ) {
        let Some(gpu) = gpu::test_device(&interleave::device_needs()) else { return Ok(()) };
        let (depth, normals) = scene_gbuffer(width, height, 5);
        let pattern = Pattern::new(n, m).expect("pattern");
        let layout = SplitLayout::new(width, height, pattern).expect("layout");
        let lights = subset_lights(pattern, per_subset);
        let expected = cpu::shade_subsets(&depth, &normals, &lights, &layout).expect("cpu");
        let fused = igpu::run_shading(gpu, &depth, &normals, &lights, &layout, Shading::Fused).expect("fused");
        assert_close(&expected, &fused, SHADE_TOL, "fused shading");
        for variant in [SplitVariant::OnePass, SplitVariant::TwoPass(interleave::Block::fitted(16, 16, pattern)), SplitVariant::Tiled] {
            let split = igpu::run_shading(gpu, &depth, &normals, &lights, &layout, Shading::Split(variant)).expect("split");
            prop_assert!(split == fused, "{variant:?}: split + shade + gather differs from fused shading");
        }
    }
}
