//! Point-based GI's CPU reference (`instant_radiosity::pbgi`, Holländer 2013 §3.6.1): the
//! paraboloid convolution's exact integrals, a furnace (a receiver inside a sphere of uniform
//! radiance gathers π·L), and the one-bounce light of the original Cornell box against the
//! path tracer's.

use glam::Vec3;
use instant_radiosity::pbgi::{
    GpuGather, LitPoints, PbgiConfig, ReceiverGrid, gather_views, grid_receivers, texel_weight,
    upsample,
};
use instant_radiosity::vpl;
use manylod::Bsh;
use tiled_shading::GpuLight;

/// The weights of a tile approach ∫cos θ dω over the hemisphere = π (midpoint rule on the
/// disc: the rim's partial texels are the error, shrinking with the tile).
#[test]
fn texel_weights_integrate_the_cosine_over_the_hemisphere() {
    let sum = |tile: u32| -> f64 {
        (0..tile * tile)
            .map(|i| f64::from(texel_weight(i % tile, i / tile, tile)))
            .sum()
    };
    let pi = std::f64::consts::PI;
    let errors: Vec<f64> = [8, 32, 128].map(|t| (sum(t) - pi).abs() / pi).to_vec();
    assert!(errors[2] < 2e-3, "{errors:?}");
    assert!(
        errors[0] > errors[1] && errors[1] > errors[2],
        "finer tiles integrate better: {errors:?}"
    );
}

/// `count` points on a sphere of `radius` around the origin (a Fibonacci lattice), normals
/// pointing in.
fn inward_sphere(count: usize, radius: f32) -> (Vec<Vec3>, Vec<Vec3>) {
    let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    (0..count)
        .map(|i| {
            let y = 1.0 - 2.0 * (i as f32 + 0.5) / count as f32;
            let r = (1.0 - y * y).sqrt();
            let phi = golden * i as f32;
            let d = Vec3::new(r * phi.cos(), y, r * phi.sin());
            (d * radius, -d)
        })
        .unzip()
}

/// A receiver at the centre of a closed sphere whose surfels all leave radiance 1 sees it
/// over its whole hemisphere: E = π (the furnace). The cut draws discs of at least the
/// texel's half diagonal, so no texel of the disc stays empty; what is left is the tile's rim.
#[test]
fn a_receiver_inside_a_uniform_sphere_gathers_pi() {
    let count = 1 << 14;
    let radius = 2.0;
    let (points, normals) = inward_sphere(count, radius);
    // Each disc covers the sphere's area / count.
    let leaf_radius = 2.0 * radius / (count as f32).sqrt();
    let bsh = Bsh::build(&points, &normals, leaf_radius).expect("hierarchy");
    for tile in [16, 32] {
        let config = PbgiConfig {
            tile,
            ..PbgiConfig::default()
        };
        let lit = LitPoints::from_hierarchy(bsh.clone(), &vec![Vec3::ONE; count], 8.0, config);
        let receivers = [
            (Vec3::ZERO, Vec3::Y),
            (
                Vec3::new(0.3, -0.2, 0.1),
                Vec3::new(1.0, 1.0, 0.0).normalize(),
            ),
        ];
        for (e, r) in lit
            .gather(&receivers)
            .expect("gather")
            .iter()
            .zip(receivers)
        {
            let error = (e.x - std::f32::consts::PI).abs() / std::f32::consts::PI;
            assert!(
                error < 0.03,
                "tile {tile}, receiver {r:?}: E = {e} (error {error})"
            );
        }
    }
}

/// The original Cornell box of the shared fixtures and its view (`None`: skipped, a failure
/// in CI).
fn cornell() -> Option<(scene::Scene, scene::Camera)> {
    let Some(fixtures) = scene::shared_fixtures() else {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI needs ../shared/fixtures"
        );
        eprintln!("skipped: no ../shared/fixtures");
        return None;
    };
    let path = fixtures.join("cornell/CornellBox-Original.obj");
    let scene = scene::Scene::load(&path).expect("cornell");
    let camera = scene::preset_view(&path, &scene).expect("the Cornell view");
    Some((scene, camera))
}

/// The lamp of `scene` as 16 hemispherical lights (what the renderer lights it with).
fn lamp(scene: &scene::Scene) -> Vec<GpuLight> {
    let (lights, _, _) = vpl::primary_lights_sampled(scene, 16);
    lights.iter().map(GpuLight::from).collect()
}

/// A pixel, its linear albedo and its receiver (position, normal).
type Pixel = ((u32, u32), Vec3, (Vec3, Vec3));

/// Every pixel of a `w × h` G-buffer of `scene` that shows a surface: `(x, y)`, its linear
/// albedo, and the receiver (position, normal).
fn receivers(scene: &scene::Scene, camera: &scene::Camera, (w, h): (u32, u32)) -> Vec<Pixel> {
    let gb = gbuffer::cpu::rasterize(scene, camera, w, h)
        .expect("G-buffer")
        .gbuffer;
    let frame = gbuffer::Frame::new(camera, w, h);
    let mut out = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let depth = gb.linear_depth.get(x, y);
            if depth <= 0.0 {
                continue;
            }
            let p = gbuffer::position::from_view_ray(&frame, x, y, depth);
            let n = gbuffer::normal::unpack_octahedral(gb.normal.get(x, y));
            // The G-buffer's albedo bytes are linear (unorm8).
            let a = gb.albedo.get(x, y);
            let albedo = Vec3::from_array([0, 1, 2].map(|c| f32::from(a[c]) / 255.0));
            out.push(((x, y), albedo, (p, n)));
        }
    }
    out
}

/// The original Cornell box at 48×48, lit by its lamp as 16 hemispherical lights: PBGI's
/// one-bounce radiance `ρ/π · E` at every pixel, and gathered at every 4th pixel and
/// upsampled, against the path tracer's one-bounce light alone (`min_bounces = max_bounces =
/// 1`, pixel centres, Lambert lobe, 512 spp). Both see the
/// same lamp up to its stand-ins; the bounds (the mean within 20 %, 8×8 blocks within 25 %
/// relative RMS) leave room for the splat's discretisation (the next test) and catch a wrong
/// solid angle or cosine weight, which is off by 30 % or more.
#[test]
fn cornell_one_bounce_matches_the_path_tracer() {
    let Some((scene, camera)) = cornell() else {
        return;
    };
    let (w, h) = (48u32, 48u32);

    let truth = {
        let config = scene::reference::ReferenceConfig {
            max_bounces: 1,
            min_bounces: 1,
            jitter: false,
            specular: false,
            ..Default::default()
        };
        let mut pt = scene::reference::PathTracer::new(&scene, camera, w, h, &scene.lights, config);
        pt.add_samples(512);
        pt.image()
    };

    let lit = LitPoints::new(&scene, &lamp(&scene), &PbgiConfig::default()).expect("surfels");
    let pixels = receivers(&scene, &camera, (w, h));
    let points: Vec<(Vec3, Vec3)> = pixels.iter().map(|p| p.2).collect();
    let irradiance = lit.gather(&points).expect("gather");
    let mut estimate = vec![Vec3::ZERO; (w * h) as usize];
    for (&((x, y), albedo, _), e) in pixels.iter().zip(&irradiance) {
        estimate[(y * w + x) as usize] = albedo * *e * std::f32::consts::FRAC_1_PI;
    }
    let (mean_error, block_error) = errors(&estimate, &truth, w);
    println!(
        "PBGI at every pixel against the path tracer: mean error {mean_error:.3}, 8×8 blocks relative RMS {block_error:.3}"
    );
    assert!(mean_error <= 0.20, "mean error {mean_error}");
    assert!(block_error <= 0.25, "block error {block_error}");

    // Every 4th pixel gathered, the frame upsampled edge-aware: the same bounds (its
    // interpolation blurs the light within surfaces only).
    let gb = gbuffer::cpu::rasterize(&scene, &camera, w, h)
        .expect("G-buffer")
        .gbuffer;
    let frame = gbuffer::Frame::new(&camera, w, h);
    let grid = ReceiverGrid::new((w, h), 4).expect("grid");
    let sparse = lit
        .gather(&grid_receivers(&gb, &frame, &grid))
        .expect("gather");
    let indirect = upsample(&gb, &frame, &grid, &sparse).expect("upsample");
    let mut upsampled = vec![Vec3::ZERO; (w * h) as usize];
    for &((x, y), albedo, _) in &pixels {
        let p = indirect.get(x, y);
        upsampled[(y * w + x) as usize] = albedo * Vec3::new(p[0], p[1], p[2]);
    }
    let (mean_error, block_error) = errors(&upsampled, &truth, w);
    println!(
        "PBGI every 4th pixel, upsampled, against the path tracer: mean error {mean_error:.3}, 8×8 blocks relative RMS {block_error:.3}"
    );
    assert!(mean_error <= 0.20, "upsampled mean error {mean_error}");
    assert!(block_error <= 0.25, "upsampled block error {block_error}");
}

/// The relative error of `estimate`'s mean luminance against `truth`'s, and the relative RMS
/// over 8×8 blocks (of `width`-pixel rows) that the truth lights.
fn errors(estimate: &[Vec3], truth: &[Vec3], width: u32) -> (f64, f64) {
    let luminance = |c: Vec3| f64::from(c.dot(Vec3::new(0.2126, 0.7152, 0.0722)));
    let mean = |img: &[Vec3]| img.iter().map(|&c| luminance(c)).sum::<f64>() / img.len() as f64;
    let (m_est, m_truth) = (mean(estimate), mean(truth));
    let height = truth.len() as u32 / width;
    let block = 8;
    let mut squared = 0.0;
    let mut blocks = 0;
    for by in 0..height / block {
        for bx in 0..width / block {
            let sum = |img: &[Vec3]| -> f64 {
                (0..block * block)
                    .map(|i| {
                        let (x, y) = (bx * block + i % block, by * block + i / block);
                        luminance(img[(y * width + x) as usize])
                    })
                    .sum()
            };
            let (e, t) = (sum(estimate), sum(truth));
            if t > 0.0 {
                squared += ((e - t) / t).powi(2);
                blocks += 1;
            }
        }
    }
    (
        (m_est - m_truth).abs() / m_truth,
        (squared / f64::from(blocks)).sqrt(),
    )
}

/// The splat against what it approximates: the brute-force gather over the same lit surfels —
/// every surfel a disc of `area / count` seen by a visibility ray, `L · cos θ_r cos θ_s / d² ·
/// A` (2^12 surfels, 24×24 receivers). The discs over-cover silhouettes (a disc of at least
/// the texel's half diagonal wins the whole texel), so PBGI reads brighter; refining the view
/// (tile ×2, ε ÷2) must bring it closer, and the finest within 10 %.
#[test]
fn the_splat_converges_to_the_brute_force_gather() {
    let Some((scene, camera)) = cornell() else {
        return;
    };
    let lights = lamp(&scene);
    let pixels = receivers(&scene, &camera, (24, 24));
    let points: Vec<(Vec3, Vec3)> = pixels.iter().map(|p| p.2).collect();

    let (positions, indices) = tiled_shading::rays::scene_mesh(&scene);
    let bvh = tiled_shading::rays::RayBvh::new((&positions, &indices)).expect("BVH");
    let albedos = instant_radiosity::near_field::triangle_albedos(&scene);
    let log2 = 12;
    let count = 1usize << log2;
    let surfels = manylod::surfels::sample(&positions, &indices, count, 1).expect("surfels");
    let (centres, normals) = manylod::surfels::evaluate(&surfels, &positions, &indices);
    let area = manylod::surfels::mesh_area(&positions, &indices);
    let reach = 2.0 * scene.bounds().diagonal();
    let radiance: Vec<Vec3> = surfels
        .iter()
        .zip(centres.iter().zip(&normals))
        .map(|(s, (&p, &n))| {
            let word = albedos[s.triangle as usize];
            let rho = Vec3::from_array([0, 8, 16].map(|k| ((word >> k) & 255) as f32 / 255.0));
            let e = instant_radiosity::near_field::direct_irradiance(&bvh, &lights, reach, (p, n));
            rho * e * std::f32::consts::FRAC_1_PI
        })
        .collect();
    let share = area / count as f32;
    let brute: f32 = points
        .iter()
        .map(|&(p, n)| {
            let origin = p + n * scene::reference::ray_lift(p);
            centres
                .iter()
                .zip(&normals)
                .zip(&radiance)
                .map(|((&q, &m), &l)| {
                    let d = q - origin;
                    let d2 = d.length_squared().max(share);
                    let dir = d.normalize();
                    let (cos_r, cos_s) = (n.dot(dir), -m.dot(dir));
                    if cos_r <= 0.0 || cos_s <= 0.0 || bvh.occluded(origin, d * 0.999) {
                        return 0.0;
                    }
                    l.y * cos_r * cos_s / d2 * share
                })
                .sum::<f32>()
        })
        .sum();
    let ratios: Vec<f32> = [(16, 2.0), (32, 1.0), (64, 0.5)]
        .iter()
        .map(|&(tile, epsilon)| {
            let config = PbgiConfig {
                tile,
                epsilon,
                points_log2: log2,
            };
            let lit = LitPoints::new(&scene, &lights, &config).expect("surfels");
            let e: f32 = lit
                .gather(&points)
                .expect("gather")
                .iter()
                .map(|e| e.y)
                .sum();
            e / brute
        })
        .collect();
    println!("PBGI / brute-force gather (tile 16 ε 2, 32 ε 1, 64 ε 0.5): {ratios:?}");
    let off: Vec<f32> = ratios.iter().map(|r| (r - 1.0).abs()).collect();
    assert!(off[0] > off[1] && off[1] > off[2], "{ratios:?}");
    assert!(off[2] <= 0.10, "{ratios:?}");
}

/// The GPU gather (cut, nearest-node splat, convolution) against the CPU reference on the
/// Cornell box: the same irradiance per receiver up to the float rounding of a few splat
/// depths (a texel whose nearest node differs changes a receiver by about one texel's share).
#[test]
fn gpu_gather_matches_the_cpu() {
    let Some((scene, camera)) = cornell() else {
        return;
    };
    let Some(gpu) = gpu::test_device(&instant_radiosity::device_needs()) else {
        return;
    };
    let config = PbgiConfig {
        points_log2: 14,
        ..PbgiConfig::default()
    };
    let lit = LitPoints::new(&scene, &lamp(&scene), &config).expect("surfels");
    let points: Vec<(Vec3, Vec3)> = receivers(&scene, &camera, (24, 24))
        .iter()
        .map(|p| p.2)
        .collect();
    let want = lit.gather(&points).expect("CPU gather");
    let mut gather = GpuGather::new(&gpu.device, &lit, &points, 1 << 22).expect("GPU gather");
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    gather.encode(&mut encoder, None);
    gpu.queue.submit([encoder.finish()]);
    let got = gather
        .read_irradiance(&gpu.device, &gpu.queue)
        .expect("irradiance");
    assert_eq!(got.len(), want.len());
    let close = got
        .iter()
        .zip(&want)
        .filter(|(g, w)| (**g - **w).abs().max_element() <= 1e-3 * w.max_element().max(1e-3))
        .count();
    let worst = got
        .iter()
        .zip(&want)
        .map(|(g, w)| (*g - *w).abs().max_element() / w.max_element().max(1e-3))
        .fold(0.0f32, f32::max);
    println!(
        "GPU vs CPU gather: {close} of {} receivers within 1e-3, worst {worst:.4}",
        got.len()
    );
    assert!(close * 100 >= got.len() * 98, "{close} of {}", got.len());
    assert!(worst <= 0.02, "worst relative difference {worst}");
}

/// Receivers made on the GPU from an uploaded G-buffer (every 8th pixel of the Cornell box at
/// 64×48): the same views as the CPU twin's, the same irradiance as the CPU gather of them, and
/// the same upsampled frame.
#[test]
fn gpu_receivers_and_upsampling_match_the_cpu() {
    let Some((scene, camera)) = cornell() else {
        return;
    };
    let Some(gpu) = gpu::test_device(&instant_radiosity::device_needs()) else {
        return;
    };
    let (d, q) = (&gpu.device, &gpu.queue);
    let size = (64, 48);
    let config = PbgiConfig {
        points_log2: 14,
        ..PbgiConfig::default()
    };
    let lit = LitPoints::new(&scene, &lamp(&scene), &config).expect("surfels");
    let gb = gbuffer::cpu::rasterize(&scene, &camera, size.0, size.1)
        .expect("G-buffer")
        .gbuffer;
    let frame = gbuffer::Frame::new(&camera, size.0, size.1);
    let grid = ReceiverGrid::new(size, 8).expect("grid");
    let points = grid_receivers(&gb, &frame, &grid);
    assert!(
        points.iter().filter(|p| p.1 != Vec3::Y).count() > grid.len() / 2,
        "most cells show a wall"
    );
    let uploaded = gbuffer::gpu::UploadedGBuffer::new(d, q, &gb, &frame).expect("upload");
    // Made for the grid's count with placeholder receivers: the kernel writes the views.
    let placeholder = vec![(Vec3::ZERO, Vec3::Y); grid.len()];
    let mut gather = GpuGather::new(d, &lit, &placeholder, 1 << 21).expect("gather");
    let output = gpu::transfer::texture_2d(
        d,
        "pbgi output",
        size.0,
        size.1,
        interleave::gpu::IRRADIANCE_FORMAT,
        gpu::transfer::STORAGE_ANY,
    );
    gather
        .bind_frame(d, &grid, &uploaded.frame, uploaded.textures(), &output)
        .expect("receivers");
    let mut encoder = d.create_command_encoder(&Default::default());
    gather.encode(&mut encoder, None);
    q.submit([encoder.finish()]);
    let views: Vec<manylod::view::GpuView> =
        gpu::transfer::read_pod(d, q, gather.views_buffer()).expect("views");
    let want: Vec<manylod::view::GpuView> = gather_views(&points, config.tile)
        .iter()
        .map(manylod::View::gpu)
        .collect();
    for (i, (g, w)) in views.iter().zip(&want).enumerate() {
        let close = |a: &[f32], b: &[f32]| a.iter().zip(b).all(|(x, y)| (x - y).abs() <= 1e-4);
        assert!(
            close(&g.eye, &w.eye)
                && close(g.transform.as_flattened(), w.transform.as_flattened())
                && close(g.planes.as_flattened(), w.planes.as_flattened())
                && g.kind == w.kind
                && g.size == w.size
                && g.pixels_per_radian == w.pixels_per_radian
                && g.rim == w.rim,
            "receiver {i}: GPU view {g:?} vs CPU {w:?}"
        );
    }
    let got = gather.read_irradiance(d, q).expect("irradiance");
    let want = lit.gather(&points).expect("CPU gather");
    let worst = got
        .iter()
        .zip(&want)
        .map(|(g, w)| (*g - *w).abs().max_element() / w.max_element().max(1e-3))
        .fold(0.0f32, f32::max);
    assert!(worst <= 0.02, "worst relative difference {worst}");

    // The upsampled frame: the CPU twin of the GPU's irradiance, up to f16 and that 2 %.
    let upsampled = interleave::gpu::download_image::<[half::f16; 4]>(d, q, &output)
        .expect("output")
        .map(|p| p.map(half::f16::to_f32));
    let twin = upsample(&gb, &frame, &grid, &got).expect("CPU upsample");
    let far = upsampled
        .pixels()
        .iter()
        .zip(twin.pixels())
        .filter(|(g, w)| (0..3).any(|c| (g[c] - w[c]).abs() > 2e-3 * w[c].abs().max(1e-2)))
        .count();
    assert_eq!(far, 0, "{far} pixels differ beyond f16 rounding");
}

/// The upsampling is a partition of unity: a field of one irradiance everywhere upsamples to
/// that irradiance / π on every surface pixel (0 on the background), whichever receivers
/// count as the pixel's surface.
#[test]
fn upsampling_keeps_a_constant_field() {
    let Some((scene, camera)) = cornell() else {
        return;
    };
    let size = (64, 48);
    let gb = gbuffer::cpu::rasterize(&scene, &camera, size.0, size.1)
        .expect("G-buffer")
        .gbuffer;
    let frame = gbuffer::Frame::new(&camera, size.0, size.1);
    let grid = ReceiverGrid::new(size, 8).expect("grid");
    let e = Vec3::new(1.0, 2.0, 3.0);
    let image = upsample(&gb, &frame, &grid, &vec![e; grid.len()]).expect("upsample");
    for (i, p) in image.pixels().iter().enumerate() {
        let (x, y) = (i as u32 % size.0, i as u32 / size.0);
        let want = if gb.linear_depth.get(x, y) > 0.0 {
            e * std::f32::consts::FRAC_1_PI
        } else {
            Vec3::ZERO
        };
        assert!(
            (Vec3::new(p[0], p[1], p[2]) - want).abs().max_element() < 1e-5,
            "pixel ({x}, {y}): {p:?}, want {want}"
        );
    }
}

/// The surfels lit on the GPU (leaves by shadow rays, nodes by level means) against
/// `LitPoints::new` with the same lights: set up with all 16 lamp samples, then relit on the
/// GPU with the first 8 (`set_lights`), the radiance of every node equals the CPU's for those
/// 8, up to the odd shadow ray that grazes an edge the other way.
#[test]
fn gpu_lighting_matches_the_cpu() {
    let Some((scene, camera)) = cornell() else {
        return;
    };
    let Some(gpu) = gpu::test_device(&instant_radiosity::device_needs()) else {
        return;
    };
    let (d, q) = (&gpu.device, &gpu.queue);
    let config = PbgiConfig {
        points_log2: 12,
        ..PbgiConfig::default()
    };
    let lights = lamp(&scene);
    let lit = LitPoints::new(&scene, &lights, &config).expect("surfels");
    let half = LitPoints::new(&scene, &lights[..8], &config).expect("surfels");
    let points: Vec<(Vec3, Vec3)> = receivers(&scene, &camera, (8, 8))
        .iter()
        .map(|p| p.2)
        .collect();
    let mut gather = GpuGather::new(d, &lit, &points, 1 << 20).expect("gather");
    gather
        .light_on_gpu(d, &scene, &lit, &lights)
        .expect("lighting");
    gather.set_lights(q, &lights[..8]).expect("lights");
    assert!(
        gather.set_lights(q, &lamp(&scene).repeat(2)).is_err(),
        "more lights than set up"
    );
    let mut encoder = d.create_command_encoder(&Default::default());
    gather.encode(&mut encoder, None);
    q.submit([encoder.finish()]);
    let got: Vec<[f32; 4]> = gpu::transfer::read_pod(d, q, gather.radiance()).expect("radiance");
    assert_eq!(got.len(), half.radiance.len());
    let close = got
        .iter()
        .zip(&half.radiance)
        .filter(|(g, w)| {
            (Vec3::new(g[0], g[1], g[2]) - **w).abs().max_element()
                <= 1e-3 * w.max_element().max(1e-3)
        })
        .count();
    println!(
        "GPU vs CPU surfel lighting: {close} of {} nodes within 1e-3",
        got.len()
    );
    assert!(close * 100 >= got.len() * 99, "{close} of {}", got.len());
    let sum = |v: &mut dyn Iterator<Item = f32>| v.sum::<f32>();
    let (g, w) = (
        sum(&mut got.iter().map(|g| g[1])),
        sum(&mut half.radiance.iter().map(|w| w.y)),
    );
    assert!((g - w).abs() <= 1e-3 * w, "total {g} vs {w}");
    // The root is the mean of all leaves.
    let leaves = &half.radiance[half.radiance.len() / 2..];
    let mean = leaves.iter().copied().sum::<Vec3>() / leaves.len() as f32;
    assert!(
        (Vec3::new(got[0][0], got[0][1], got[0][2]) - mean)
            .abs()
            .max_element()
            <= 1e-3 * mean.max_element()
    );
}
