//! Invariants of adaptive supersampling (Holländer 2013 §4.3) and CPU-vs-GPU agreement.
//!
//! GPU tests render the supersampled G-buffer on the GPU and give the very same G-buffer (read
//! back) to the CPU reference, so CPU and GPU shade and measure identical samples.

use adaptive_ssaa::cpu::{self, ShadingInputs, SsGBuffer};
use adaptive_ssaa::gpu::{SsaaRenderer, TEXTURE_SIZE};
use adaptive_ssaa::{
    ArrayLayers, Constants, GeometricMetric, Resolve, ShadingMetric, SsaaConfig, SsaaError,
    SsaaMaterial, TextureArray, bayer_matrix, dither_matrix, dither_order, prefix_spread,
};
use gbuffer::Image;
use tiled_shading::GpuLight;

const W: u32 = 96;
const H: u32 = 64;

/// Best possible prefix spread for `k` cells of an `m × m` torus, by exhaustive search.
fn best_spread(m: u32, k: usize) -> f32 {
    let cells: Vec<[u32; 2]> = (0..m * m).map(|i| [i % m, i / m]).collect();
    let mut best = 0.0f32;
    let mut pick = vec![0usize; k];
    // Combinations of k cells in lexicographic order.
    fn next(pick: &mut [usize], n: usize) -> bool {
        let k = pick.len();
        for i in (0..k).rev() {
            if pick[i] < n - k + i {
                pick[i] += 1;
                for j in i + 1..k {
                    pick[j] = pick[j - 1] + 1;
                }
                return true;
            }
        }
        false
    }
    for (i, p) in pick.iter_mut().enumerate() {
        *p = i;
    }
    loop {
        let subset: Vec<[u32; 2]> = pick.iter().map(|&i| cells[i]).collect();
        best = best.max(*prefix_spread(&subset, m).last().unwrap_or(&0.0));
        if !next(&mut pick, cells.len()) {
            return best;
        }
    }
}

#[test]
fn dither_matrices_are_permutations() {
    for m in 2..=8 {
        let mut v = dither_matrix(m);
        v.sort_unstable();
        assert_eq!(v, (0..m * m).collect::<Vec<_>>(), "m = {m}");
    }
}

#[test]
fn dither_prefixes_are_maximally_spread() {
    // Ordered dithering's property: each prefix of the order (the samples a pixel with k
    // samples uses) is as spread out as k cells of the tiled window can be. Exhaustive search
    // over all k-subsets of the torus.
    for m in [2u32, 4] {
        let spread = prefix_spread(&dither_order(m), m);
        for (i, &s) in spread.iter().enumerate() {
            let k = i + 2;
            assert_eq!(s, best_spread(m, k), "m = {m}, k = {k}");
        }
    }
    // Figure 4.7's 3 × 3 matrix meets it for every prefix except k = 3 (its first three samples
    // are √2, 1 apart; a diagonal reaches √2): kept as printed.
    let spread = prefix_spread(&dither_order(3), 3);
    for (i, &s) in spread.iter().enumerate() {
        let k = i + 2;
        let best = best_spread(3, k);
        if k == 3 {
            assert_eq!((s, best), (1.0, 2f32.sqrt()));
        } else {
            assert_eq!(s, best, "m = 3, k = {k}");
        }
    }
}

#[test]
fn general_construction_is_bayers_matrix() {
    // Bayer's closed form: the rank is the bit-reversed interleaving of (x xor y) and y.
    let closed = |m: u32, x: u32, y: u32| {
        let bits = m.ilog2();
        let (a, b) = (x ^ y, y);
        let mut v = 0u32;
        for i in 0..bits {
            v = (v << 2) | (((a >> i) & 1) << 1) | ((b >> i) & 1);
        }
        v
    };
    for m in [2u32, 4, 8] {
        let b = bayer_matrix(m);
        for y in 0..m {
            for x in 0..m {
                assert_eq!(
                    b[(y * m + x) as usize],
                    closed(m, x, y),
                    "m = {m} ({x}, {y})"
                );
            }
        }
    }
    assert_eq!(dither_matrix(8), bayer_matrix(8));
    assert_eq!(dither_matrix(2), bayer_matrix(2));
    // Figure 4.7's 4 × 4 matrix is Bayer's with ranks 0 and 1 swapped (the first sample near
    // the window's centre).
    let mut swapped = bayer_matrix(4);
    for v in &mut swapped {
        *v = match *v {
            0 => 1,
            1 => 0,
            v => v,
        };
    }
    assert_eq!(dither_matrix(4), swapped);
}

struct Fixture {
    gpu: &'static gpu::Gpu,
    renderer: SsaaRenderer,
    gbuffer: SsGBuffer,
    frame: gbuffer::Frame,
    far: f32,
    textures: TextureArray,
    materials: Vec<SsaaMaterial>,
    lights: Vec<GpuLight>,
}

impl Fixture {
    /// The checkerboard scene's supersampled G-buffer, `m × m` samples per pixel, textures
    /// filtered with up to `anisotropy`.
    fn new(m: u32, anisotropy: u32) -> Option<Self> {
        let gpu = gpu::test_device(&adaptive_ssaa::device_needs())?;
        let scene = scene::checkerboard();
        let camera = scene.camera_or_framed();
        let lights = tiled_shading::gpu_lights(&scene.lights).expect("valid lights");
        let config = SsaaConfig {
            m,
            anisotropy,
            ..Default::default()
        };
        let mut renderer =
            SsaaRenderer::new(&gpu.device, &gpu.queue, &scene, &lights, W, H, &config)
                .expect("renderer");
        renderer.set_camera(&gpu.queue, &camera).expect("camera");
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        renderer.encode_gbuffer(&mut encoder, None);
        gpu.queue.submit([encoder.finish()]);
        let gbuffer = renderer
            .targets
            .read(&gpu.device, &gpu.queue)
            .expect("read");
        let textures = renderer
            .textures
            .read(&gpu.device, &gpu.queue)
            .expect("read");
        Some(Self {
            gpu,
            renderer,
            gbuffer,
            frame: gbuffer::Frame::new(&camera, W * m, H * m),
            far: camera.far,
            textures,
            materials: SsaaMaterial::of_scene(&scene, &ArrayLayers::new(&scene)),
            lights,
        })
    }

    fn inputs(&self) -> ShadingInputs<'_> {
        ShadingInputs {
            gbuffer: &self.gbuffer,
            frame: &self.frame,
            far: self.far,
            textures: &self.textures,
            materials: &self.materials,
            lights: &self.lights,
        }
    }

    /// Runs the adaptive passes (or full supersampling) with `config` on the G-buffer.
    fn gpu(
        &mut self,
        config: &SsaaConfig,
        full: bool,
    ) -> (Image<[f32; 4]>, Image<[f32; 4]>, Image<u32>) {
        let ssaa = &mut self.renderer.ssaa;
        ssaa.set_config(&self.gpu.queue, config).expect("config");
        ssaa.set_far(&self.gpu.queue, self.far);
        let mut encoder = self.gpu.device.create_command_encoder(&Default::default());
        if full {
            ssaa.encode_full(&mut encoder, None);
        } else {
            ssaa.encode(&mut encoder, None);
        }
        self.gpu.queue.submit([encoder.finish()]);
        (
            ssaa.read_output(&self.gpu.device, &self.gpu.queue)
                .expect("read"),
            ssaa.read_first(&self.gpu.device, &self.gpu.queue)
                .expect("read"),
            ssaa.read_counts(&self.gpu.device, &self.gpu.queue)
                .expect("read"),
        )
    }
}

fn bits(img: &Image<[f32; 4]>) -> Vec<u32> {
    img.pixels().iter().flatten().map(|v| v.to_bits()).collect()
}

/// Bit-for-bit equality, reporting the number of differing pixels and the first.
fn assert_same(a: &Image<[f32; 4]>, b: &Image<[f32; 4]>, what: &str) {
    let differ: Vec<usize> = (0..a.pixels().len())
        .filter(|&i| a.pixels()[i].map(f32::to_bits) != b.pixels()[i].map(f32::to_bits))
        .collect();
    if let Some(&i) = differ.first() {
        panic!(
            "{what}: {} pixels differ, first {i}: {:?} vs {:?}",
            differ.len(),
            a.pixels()[i],
            b.pixels()[i]
        );
    }
}

fn mse(a: &Image<[f32; 4]>, b: &Image<[f32; 4]>) -> f64 {
    let sum: f64 = a
        .pixels()
        .iter()
        .zip(b.pixels())
        .map(|(p, q)| (0..3).map(|c| f64::from(p[c] - q[c]).powi(2)).sum::<f64>())
        .sum();
    sum / (3.0 * a.pixels().len() as f64)
}

#[test]
fn forcing_every_sample_equals_full_supersampling_exactly() {
    for m in [2, 3, 4] {
        let Some(mut f) = Fixture::new(m, 1) else {
            return;
        };
        let base = SsaaConfig {
            m,
            min_samples: m * m,
            anisotropy: 1,
            ..Default::default()
        };
        let (full, _, _) = f.gpu(&base, true);
        for resolve in Resolve::ALL {
            let config = SsaaConfig { resolve, ..base };
            let (image, _, counts) = f.gpu(&config, false);
            assert!(counts.pixels().iter().all(|&k| k == m * m));
            assert_same(&image, &full, &format!("m = {m}, {resolve:?}"));
        }
        // The CPU reference of full supersampling, on the same G-buffer.
        let cpu_full = cpu::shade_full(&f.inputs(), &base).expect("cpu");
        let e = mse(&cpu_full, &full);
        assert!(e < TRILINEAR_MSE, "m = {m}: CPU vs GPU full SSAA MSE {e}");
    }
}

#[test]
fn zero_constants_give_one_sample_per_pixel() {
    let Some(mut f) = Fixture::new(4, 16) else {
        return;
    };
    let config = SsaaConfig {
        constants: Constants {
            mm: 0.0,
            nc: 0.0,
            dv: 0.0,
            nv: 0.0,
        },
        shading: Some(ShadingMetric {
            c: 0.0,
            ..Default::default()
        }),
        ..Default::default()
    };
    for metric in GeometricMetric::ALL {
        for resolve in Resolve::ALL {
            let config = SsaaConfig {
                metric: Some(metric),
                resolve,
                ..config
            };
            let (image, first, counts) = f.gpu(&config, false);
            assert!(counts.pixels().iter().all(|&k| k == 1), "{metric}");
            assert_same(&image, &first, &format!("{metric} {resolve:?}"));
        }
    }
}

#[test]
fn metrics_cpu_equal_gpu() {
    // Sample counts are integers from floats: CPU and GPU must agree exactly, except where
    // the CPU's value lies within 1e-3 (relative) of a rounding boundary or its luminance
    // range within 1e-4 of the threshold — GPU sqrt, division and normalisation are not
    // correctly rounded. Such pixels are counted and must be rare.
    for m in [2, 4] {
        let Some(mut f) = Fixture::new(m, 16) else {
            return;
        };
        for metric in GeometricMetric::ALL.map(Some).into_iter().chain([None]) {
            let config = SsaaConfig {
                m,
                metric,
                ..Default::default()
            };
            let (_, first, counts) = f.gpu(&config, false);
            let inp = f.inputs();
            let cpu_counts = cpu::evaluate(&inp, &config, &first).expect("cpu");
            let mut near = 0;
            for y in 0..H {
                for x in 0..W {
                    let (a, b) = (cpu_counts.get(x, y), counts.get(x, y));
                    if a == b {
                        continue;
                    }
                    let k = cpu::pixel_metric(&inp, &config, &first, x, y);
                    let (r, t) = cpu::luminance_range(&config, &first, x, y);
                    let at_boundary = (k - k.round()).abs() <= 1e-3 * k.abs().max(1.0);
                    let at_threshold = (r - t).abs() <= 1e-4;
                    assert!(
                        at_boundary || at_threshold,
                        "m = {m} {metric:?} pixel ({x}, {y}): CPU {a} GPU {b} (k = {k}, r = {r}, t = {t})"
                    );
                    near += 1;
                }
            }
            assert!(near <= 3, "m = {m} {metric:?}: {near} boundary pixels");
            // The metric does something on this scene: the silhouettes get more samples.
            assert!(counts.pixels().iter().any(|&k| k > 1), "{metric:?}");
            assert!(counts.pixels().iter().any(|&k| k == 1), "{metric:?}");
        }
    }
}

/// CPU vs GPU image tolerance with trilinear filtering (MSE of linear radiance): texture
/// weights are fixed-point on GPUs.
const TRILINEAR_MSE: f64 = 2e-5;
/// The same with 16× anisotropic filtering, whose probes and level of detail are
/// implementation-defined (llvmpipe measured 8e-4 on the checker, which aliases most).
const ANISOTROPIC_MSE: f64 = 3e-3;

#[test]
fn images_cpu_match_gpu_and_beat_one_sample() {
    for (anisotropy, tolerance) in [(1, TRILINEAR_MSE), (16, ANISOTROPIC_MSE)] {
        let Some(mut f) = Fixture::new(4, anisotropy) else {
            return;
        };
        let config = SsaaConfig {
            anisotropy,
            ..Default::default()
        };
        let (image, first, counts) = f.gpu(&config, false);
        let (full, _, _) = f.gpu(&config, true);
        let inp = f.inputs();
        let cpu_first = cpu::shade_first(&inp, &config).expect("cpu");
        let cpu_image = cpu::shade_adaptive(&inp, &config, &first, &counts).expect("cpu");
        for (name, a, b) in [("S", &cpu_first, &first), ("adaptive", &cpu_image, &image)] {
            let e = mse(a, b);
            println!("anisotropy {anisotropy}, {name}: CPU vs GPU MSE {e:.2e}");
            assert!(
                e < tolerance,
                "anisotropy {anisotropy}, {name}: CPU vs GPU MSE {e}"
            );
        }
        let (e_adaptive, e_first) = (mse(&image, &full), mse(&first, &full));
        assert!(
            e_adaptive < 0.5 * e_first,
            "adaptive MSE {e_adaptive} vs one sample {e_first}"
        );
        // Sorted and tiled resolves: the same pixels shaded by the same function and summed in
        // the same order — bit for bit with trilinear filtering; llvmpipe's anisotropic filter
        // depends on which pixels share a SIMD group, so with anisotropy only closely.
        for resolve in [Resolve::Sorted, Resolve::Tiles] {
            let (other, _, _) = f.gpu(&SsaaConfig { resolve, ..config }, false);
            let what = format!("{resolve:?} vs loop");
            if anisotropy == 1 {
                assert_same(&other, &image, &what);
            } else {
                let e = mse(&other, &image);
                assert!(e < tolerance, "{what}: MSE {e}");
            }
        }
    }
}

#[test]
fn fxaa_cpu_matches_gpu() {
    let Some(mut f) = Fixture::new(2, 16) else {
        return;
    };
    let config = SsaaConfig {
        m: 2,
        ..Default::default()
    };
    let (_, first, _) = f.gpu(&config, false);
    let ssaa = &f.renderer.ssaa;
    let mut encoder = f.gpu.device.create_command_encoder(&Default::default());
    ssaa.encode_fxaa(&mut encoder, None);
    f.gpu.queue.submit([encoder.finish()]);
    let gpu_fxaa = ssaa.read_output(&f.gpu.device, &f.gpu.queue).expect("read");
    let cpu_fxaa = cpu::fxaa(&first);
    let worst = gpu_fxaa
        .pixels()
        .iter()
        .zip(cpu_fxaa.pixels())
        .flat_map(|(a, b)| (0..3).map(move |c| (a[c] - b[c]).abs()))
        .fold(0.0f32, f32::max);
    assert!(worst < 1e-4, "FXAA CPU vs GPU differs by {worst}");
    assert_ne!(bits(&gpu_fxaa), bits(&first), "FXAA changed nothing");
}

#[test]
fn bad_input_is_an_error() {
    let Some(gpu) = gpu::test_device(&adaptive_ssaa::device_needs()) else {
        return;
    };
    let scene = scene::checkerboard();
    let lights = tiled_shading::gpu_lights(&scene.lights).expect("valid lights");
    let bad = |w: u32, h: u32, m: u32| {
        let config = SsaaConfig {
            m,
            ..Default::default()
        };
        SsaaRenderer::new(&gpu.device, &gpu.queue, &scene, &lights, w, h, &config).err()
    };
    assert!(matches!(bad(0, 10, 4), Some(SsaaError::InvalidSize { .. })));
    assert!(matches!(
        bad(10_000, 10, 4),
        Some(SsaaError::InvalidSize { .. })
    ));
    assert!(matches!(bad(10, 10, 1), Some(SsaaError::WindowSize(1))));
    let Some(mut f) = Fixture::new(2, 16) else {
        return;
    };
    let four = SsaaConfig::default();
    assert!(f.renderer.ssaa.set_config(&f.gpu.queue, &four).is_err());
    let trilinear = SsaaConfig {
        m: 2,
        anisotropy: 1,
        ..four
    };
    assert!(
        f.renderer
            .ssaa
            .set_config(&f.gpu.queue, &trilinear)
            .is_err()
    );
    let too_many = vec![f.lights[0]; f.lights.len() + 1];
    assert!(f.renderer.ssaa.set_lights(&f.gpu.queue, &too_many).is_err());
    // CPU inputs of the wrong size.
    let small = Image::filled(3, 3, [0.0f32; 4]);
    assert!(cpu::evaluate(&f.inputs(), &SsaaConfig { m: 2, ..four }, &small).is_err());
    assert!(cpu::shade_first(&f.inputs(), &SsaaConfig { m: 3, ..four }).is_err());
}

/// The resolve writes into the caller's output buffer (`SsaaInputs::output`); a buffer too
/// small or without `STORAGE` is an error naming it, not a wgpu validation panic.
#[test]
fn caller_owned_output_is_checked() {
    use adaptive_ssaa::gpu::{GpuTextures, SsGBufferTargets, Ssaa, SsaaInputs};
    let Some(gpu) = gpu::test_device(&adaptive_ssaa::device_needs()) else {
        return;
    };
    let d = &gpu.device;
    let scene = scene::checkerboard();
    let config = SsaaConfig::default();
    let (w, h, m) = (W, H, config.m);
    let pass = gbuffer::gpu::GBufferPass::new(d).expect("pass");
    let store = gbuffer::gpu::GpuScene::upload(d, &gpu.queue, &scene, &pass).expect("scene");
    let layers = ArrayLayers::new(&scene);
    let size = layers.side(&scene, TEXTURE_SIZE);
    let textures =
        GpuTextures::new(d, &gpu.queue, &store.textures, &layers, size, 16).expect("textures");
    let targets = SsGBufferTargets::new(d, w * m, h * m).expect("targets");
    let materials = gpu::transfer::buffer_init(
        d,
        "materials",
        bytemuck::cast_slice(&SsaaMaterial::of_scene(&scene, &layers)),
        wgpu::BufferUsages::STORAGE,
    )
    .expect("materials");
    let buffer = |size, usage| {
        gpu::transfer::buffer(d, "application's output", size, usage).expect("buffer")
    };
    let bytes = u64::from(w * h) * 16;
    let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
    let make = |output: &wgpu::Buffer| {
        let inputs = SsaaInputs {
            frame: pass.frame_buffer(),
            targets: &targets,
            textures: &textures,
            materials: &materials,
            output: Some(output),
        };
        Ssaa::new(d, &inputs, &config, w, h, 4)
    };
    let mine = buffer(bytes, storage);
    assert!(make(&mine).expect("caller's output").output() == &mine);
    for (output, words) in [
        (buffer(bytes - 16, storage), "bytes"),
        (buffer(bytes, wgpu::BufferUsages::COPY_SRC), "STORAGE"),
    ] {
        let e = make(&output).err().expect("rejected").to_string();
        assert!(e.contains("SSAA output") && e.contains(words), "{e}");
    }
}
