//! Adaptive supersampling reads the scene's one texture store: the texture array is drawn from
//! it (against its CPU twin), the supersampled G-buffer evaluates the glTF material exactly as
//! the G-buffer pass does (same samples, same normals, roughness, metallic and occlusion), and
//! full supersampling equals an independent reference: the G-buffer pass rendered at the
//! sample resolution, every sample shaded here and each window averaged.

use adaptive_ssaa::gpu::{SsaaRenderer, TEXTURE_SIZE};
use adaptive_ssaa::{ArrayLayers, SsaaConfig, TextureArray, unpack_tint};
use gbuffer::normal::unpack_octahedral;
use gbuffer::{GBuffer, Image, TextureOptions, position, unpack_albedo, unpack_material};
use glam::{Vec3, Vec4Swizzles};
use tiled_shading::lighting::{Surface, shade_light};

const W: u32 = 96;
const H: u32 = 64;

struct Gallery {
    gpu: &'static gpu::Gpu,
    scene: scene::Scene,
    camera: scene::Camera,
    lights: Vec<tiled_shading::GpuLight>,
}

impl Gallery {
    fn new() -> Option<Self> {
        let gpu = gpu::test_device(&adaptive_ssaa::device_needs())?;
        let scene = scene::material_gallery();
        let camera = scene.camera_or_framed();
        let lights = tiled_shading::gpu_lights(&scene.lights).expect("valid lights");
        Some(Self {
            gpu,
            scene,
            camera,
            lights,
        })
    }

    /// The renderer with its supersampled G-buffer drawn.
    fn renderer(&self, config: &SsaaConfig) -> SsaaRenderer {
        let (d, q) = (&self.gpu.device, &self.gpu.queue);
        let mut r =
            SsaaRenderer::new(d, q, &self.scene, &self.lights, W, H, config).expect("renderer");
        r.set_camera(q, &self.camera).expect("camera");
        let mut encoder = d.create_command_encoder(&Default::default());
        r.encode_gbuffer(&mut encoder, None);
        q.submit([encoder.finish()]);
        r
    }

    /// The G-buffer pass at the sample resolution of window side `m`.
    fn gbuffer(&self, m: u32, anisotropy: u32) -> GBuffer {
        let options = TextureOptions {
            max_anisotropy: anisotropy,
        };
        gbuffer::gpu::run_with(
            self.gpu,
            &self.scene,
            &self.camera,
            (W * m, H * m),
            false,
            &options,
        )
        .expect("G-buffer")
    }
}

#[test]
fn texture_array_is_drawn_from_the_store() {
    let Some(g) = Gallery::new() else { return };
    let r = g.renderer(&SsaaConfig::default());
    let layers = ArrayLayers::new(&g.scene);
    // White, then the textures read in sRGB: the checker, tiles and holes (base colour) and
    // the rings (emissive); not the metallic-roughness, normal or occlusion textures.
    let sources: Vec<_> = layers
        .sources
        .iter()
        .map(|t| t.map(|t| t as usize))
        .collect();
    assert_eq!(sources, [None, Some(0), Some(1), Some(5), Some(6)]);
    let gpu = r.textures.read(&g.gpu.device, &g.gpu.queue).expect("read");
    let cpu = TextureArray::new(&g.scene, &layers, layers.side(&g.scene, TEXTURE_SIZE));
    assert_eq!(
        (gpu.size, gpu.layers, gpu.levels()),
        (cpu.size, cpu.layers, cpu.levels())
    );
    // The checker is 256 texels wide, the rest are magnified with the hardware's fixed-point
    // bilinear weights; each level is drawn from the one below as stored, so one step of
    // rounding per level may carry up (as `gbuffer`'s mip chains), a quarter step on average.
    let (mut total, mut count) = (0u64, 0u64);
    for (level, (a, b)) in gpu.mips.iter().zip(&cpu.mips).enumerate() {
        for (layer, (a, b)) in a.iter().zip(b).enumerate() {
            let worst = a.iter().zip(b).map(|(x, y)| x.abs_diff(*y)).max();
            assert!(
                worst <= Some(level.max(1) as u8),
                "level {level} layer {layer}: off by {worst:?}"
            );
            total += a
                .iter()
                .zip(b)
                .map(|(x, y)| u64::from(x.abs_diff(*y)))
                .sum::<u64>();
            count += a.len() as u64;
        }
    }
    let mean = total as f64 / count as f64;
    assert!(mean <= 0.25, "off by {mean:.3} on average");
}

#[test]
fn supersampled_gbuffer_evaluates_the_material_as_the_gbuffer() {
    let Some(g) = Gallery::new() else { return };
    let m = 2;
    let config = SsaaConfig {
        m,
        ..Default::default()
    };
    let r = g.renderer(&config);
    let ss = r.targets.read(&g.gpu.device, &g.gpu.queue).expect("read");
    let gb = g.gbuffer(m, config.anisotropy);
    let mut covered = 0;
    for (i, (&depth, &reference)) in ss
        .linear_depth
        .pixels()
        .iter()
        .zip(gb.linear_depth.pixels())
        .enumerate()
    {
        // The same rasterisation, alpha test (MASK holes, dithered BLEND) and culling.
        assert_eq!(depth.to_bits(), reference.to_bits(), "sample {i}: depth");
        if depth <= 0.0 {
            continue;
        }
        covered += 1;
        assert_eq!(
            ss.normal.pixels()[i],
            gb.normal.pixels()[i],
            "sample {i}: normal"
        );
        assert_eq!(
            ss.material.pixels()[i],
            gb.material.pixels()[i],
            "sample {i}: roughness, metallic, id"
        );
        let (_, occlusion) = unpack_tint(ss.tint.pixels()[i]);
        let expected = gb.emission.pixels()[i][3];
        assert!(
            // Unorm8 against half precision.
            (occlusion - expected).abs() <= 1.0 / 255.0,
            "sample {i}: occlusion {occlusion} vs {expected}"
        );
    }
    assert!(covered > ss.linear_depth.pixels().len() / 3, "{covered}");
}

/// Radiance of G-buffer pixel `(x, y)` as the SSAA shading defines it, from the G-buffer
/// pass's targets: every light, ambient × occlusion, emission.
fn shade_gbuffer_pixel(
    gb: &GBuffer,
    frame: &gbuffer::Frame,
    lights: &[tiled_shading::GpuLight],
    ambient: Vec3,
    (x, y): (u32, u32),
) -> Vec3 {
    let depth = gb.linear_depth.get(x, y);
    if depth <= 0.0 {
        return Vec3::ZERO;
    }
    let (albedo, specular) = unpack_albedo(gb.albedo.get(x, y));
    let (roughness, metallic, _) = unpack_material(gb.material.get(x, y));
    let p = position::from_view_ray(frame, x, y, depth);
    let surface = Surface {
        p,
        n: unpack_octahedral(gb.normal.get(x, y)),
        v: (frame.eye.xyz() - p).normalize(),
        albedo,
        roughness,
        metallic,
        specular,
    };
    let (mut diffuse, mut glossy) = (Vec3::ZERO, Vec3::ZERO);
    for light in lights {
        let (d, s) = shade_light(light, &surface);
        diffuse += d;
        glossy += s;
    }
    let [er, eg, eb, occlusion] = gb.emission.get(x, y);
    albedo * (1.0 - metallic) * (ambient * occlusion + diffuse) + glossy + Vec3::new(er, eg, eb)
}

#[test]
fn full_supersampling_equals_the_gbuffer_shaded_and_averaged() {
    let Some(g) = Gallery::new() else { return };
    let m = 2;
    // Every sample of every window, each filtered over one sample step (footprint m/√m² = 1),
    // trilinear: the G-buffer pass at the sample resolution filters the same footprints.
    let config = SsaaConfig {
        m,
        min_samples: m * m,
        anisotropy: 1,
        ..Default::default()
    };
    let r = g.renderer(&config);
    let (d, q) = (&g.gpu.device, &g.gpu.queue);
    let mut encoder = d.create_command_encoder(&Default::default());
    r.ssaa.encode(&mut encoder, None);
    q.submit([encoder.finish()]);
    let image = r.ssaa.read_output(d, q).expect("read");
    let gb = g.gbuffer(m, 1);
    let frame = gbuffer::Frame::new(&g.camera, W * m, H * m);
    let reference: Vec<Vec3> = (0..W * H)
        .map(|i| {
            let (x, y) = (i % W, i / W);
            let window = (0..m * m).map(|s| {
                let at = (x * m + s % m, y * m + s / m);
                shade_gbuffer_pixel(&gb, &frame, &g.lights, config.ambient, at)
            });
            window.sum::<Vec3>() / (m * m) as f32
        })
        .collect();
    let reference = Image::from_vec(W, H, reference).expect("image");
    let (mut sum, mut diff, mut outliers) = (0.0, 0.0, 0);
    for (a, b) in image.pixels().iter().zip(reference.pixels()) {
        let a = Vec3::new(a[0], a[1], a[2]);
        sum += b.element_sum() as f64;
        diff += (a - *b).abs().element_sum() as f64;
        // The G-buffer quantises albedo to linear 8 bits after the product, SSAA multiplies the
        // array texel in float: a few 8-bit steps of albedo.
        if (a - *b).abs().max_element() > 0.03 * b.max_element() + 0.02 {
            outliers += 1;
        }
    }
    let relative = diff / sum;
    eprintln!("mean |SSAA − reference| / mean = {relative:.4}, {outliers} outlier pixels");
    assert!(relative < 0.01, "relative difference {relative}");
    assert!(outliers <= (W * H / 200) as usize, "{outliers} outliers");
}
