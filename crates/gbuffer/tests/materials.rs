//! Each part of the glTF material against what the specification says it does, on the CPU
//! twin and (where a device exists) the GPU: expectations come from glTF 2.0 §3.9 and hand
//! arithmetic, not from the code's output.

use gbuffer::{GBuffer, TextureOptions, cpu, gpu::run_with, normal, unpack_material};
use glam::{Vec2, Vec3, Vec4};
use scene::{AlphaMode, Camera, Material, Mesh, Sampler, Scene, Texture, TextureRef, UvTransform};

const SIZE: u32 = 16;

fn texture(name: &str, width: u32, texels: &[[u8; 4]], sampler: Sampler) -> Texture {
    Texture {
        name: name.into(),
        width,
        height: texels.len() as u32 / width,
        rgba8: texels.concat(),
        sampler,
    }
}

/// The square (−1, −1)…(1, 1) in the plane z = 0, wound counter-clockwise seen from +z, with
/// glTF's texture coordinates (u along +x, v down: (0, 0) at the top left).
fn square(material: u32) -> Mesh {
    let corners =
        [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)].map(|(x, y)| Vec3::new(x, y, 0.0));
    let mut mesh = Mesh::quad("square", corners, material);
    mesh.uvs = corners
        .iter()
        .map(|c| Vec2::new(c.x * 0.5 + 0.5, 0.5 - c.y * 0.5))
        .collect();
    mesh
}

/// A camera on the z axis at `z` looking at the origin, the square filling the view.
fn camera(z: f32) -> Camera {
    Camera {
        eye: Vec3::new(0.0, 0.0, z),
        target: Vec3::ZERO,
        up: Vec3::Y,
        fov_y: 0.5,
        near: 0.1,
        far: 10.0,
    }
}

fn scene(mesh: Mesh, material: Material, textures: Vec<Texture>) -> Scene {
    let mut s = Scene {
        meshes: vec![mesh],
        materials: vec![material],
        textures,
        ..Default::default()
    };
    s.complete_tangents();
    s.validate().expect("valid scene");
    s
}

/// The CPU twin's G-buffer and, where a test device exists, the GPU's.
fn gbuffers(s: &Scene, camera: &Camera) -> Vec<(&'static str, GBuffer)> {
    let options = TextureOptions::default();
    let mut out = vec![(
        "CPU",
        cpu::rasterize_with(s, camera, (SIZE, SIZE), &options)
            .expect("cpu")
            .gbuffer,
    )];
    if let Some(gpu) = gpu::test_device(&gbuffer::device_needs()) {
        out.push((
            "GPU",
            run_with(gpu, s, camera, (SIZE, SIZE), false, &options).expect("gpu"),
        ));
    }
    out
}

fn centre_normal(gb: &GBuffer) -> Vec3 {
    normal::unpack_octahedral(gb.normal.get(SIZE / 2, SIZE / 2))
}

/// A 1 × 1 normal map holding tangent-space normal `n`, stored as glTF says (`n · ½ + ½`).
fn normal_map(n: Vec3) -> Texture {
    let e = |c: f32| ((c * 0.5 + 0.5) * 255.0).round() as u8;
    texture(
        "normal",
        1,
        &[[e(n.x), e(n.y), e(n.z), 255]],
        Sampler::default(),
    )
}

/// glTF §3.9.3: the normal map's (x, y, z) are coordinates along the tangent, the bitangent
/// (w · normal × tangent) and the normal. On the square with u along +x and v down, the
/// tangent is +x and the bitangent −y (MikkTSpace, w = −1). Seen from behind (double-sided),
/// the whole frame turns with the normal.
#[test]
fn normal_map_tilts_the_normal_in_the_tangent_frame() {
    let (s30, c30) = (0.5f32, 0.75f32.sqrt());
    let cases = [
        (Vec3::new(s30, 0.0, c30), 1.0, 3.0, Vec3::new(s30, 0.0, c30)),
        (
            Vec3::new(0.0, s30, c30),
            1.0,
            3.0,
            Vec3::new(0.0, -s30, c30),
        ),
        // Scale ½ halves x and y before normalising.
        (
            Vec3::new(s30, 0.0, c30),
            0.5,
            3.0,
            Vec3::new(0.25, 0.0, c30).normalize(),
        ),
        (
            Vec3::new(s30, 0.0, c30),
            1.0,
            -3.0,
            -Vec3::new(s30, 0.0, c30),
        ),
    ];
    for (map, scale, eye_z, want) in cases {
        let material = Material {
            normal_texture: Some(TextureRef::new(0)),
            normal_scale: scale,
            ..Default::default()
        };
        let s = scene(square(0), material, vec![normal_map(map)]);
        assert_eq!(s.meshes[0].tangents[0], Vec4::new(1.0, 0.0, 0.0, -1.0));
        for (side, gb) in gbuffers(&s, &camera(eye_z)) {
            let got = centre_normal(&gb);
            // 8-bit components: within 0.5°.
            assert!(
                normal::angle_deg(got, want) < 0.5,
                "{side}: map {map}, scale {scale}, eye z {eye_z}: {got} vs {want}"
            );
        }
    }
}

/// glTF §3.9.2: roughness = factor × G, metallic = factor × B of the (linear)
/// metallic-roughness texture.
#[test]
fn metallic_roughness_texture_scales_the_factors() {
    let material = Material {
        metallic_roughness_texture: Some(TextureRef::new(0)),
        roughness: 0.5,
        metallic: 1.0,
        ..Default::default()
    };
    let mr = texture("mr", 1, &[[0, 128, 255, 255]], Sampler::default());
    let s = scene(square(0), material, vec![mr]);
    for (side, gb) in gbuffers(&s, &camera(3.0)) {
        let (roughness, metallic, id) = unpack_material(gb.material.get(SIZE / 2, SIZE / 2));
        let want = (0.5f32 * 128.0 / 255.0 * 255.0).round() / 255.0;
        assert_eq!((roughness, metallic, id), (want, 1.0, 0), "{side}");
    }
}

/// A two-texel texture (black | white, nearest filtering) read at u = ¼ through set 0 and
/// u = ¾ through set 1: the material's `uv_set` picks the texel, a transform offset of ½
/// moves set 1 back onto black, and the vertex colour multiplies the base colour.
#[test]
fn coordinate_set_transform_and_vertex_colour_choose_the_colour() {
    let nearest = Sampler {
        mag_linear: false,
        min_linear: false,
        mipmaps: None,
        ..Sampler::default()
    };
    let two = texture("two", 2, &[[0, 0, 0, 255], [255, 255, 255, 255]], nearest);
    let mut mesh = square(0);
    mesh.uvs = vec![Vec2::new(0.25, 0.5); 4];
    mesh.uvs1 = vec![Vec2::new(0.75, 0.5); 4];
    mesh.colors = vec![Vec4::new(0.5, 1.0, 1.0, 1.0); 4];
    for (uv_set, offset, want) in [
        (0, 0.0, [0, 0, 0]),
        (1, 0.0, [128, 255, 255]),
        (1, 0.5, [0, 0, 0]),
    ] {
        let material = Material {
            base_color: Vec4::ONE,
            base_color_texture: Some(TextureRef {
                texture: 0,
                uv_set,
                transform: UvTransform {
                    offset: Vec2::new(offset, 0.0),
                    ..UvTransform::IDENTITY
                },
            }),
            ..Default::default()
        };
        let s = scene(mesh.clone(), material, vec![two.clone()]);
        for (side, gb) in gbuffers(&s, &camera(3.0)) {
            let got = gb.albedo.get(SIZE / 2, SIZE / 2);
            assert_eq!(&got[..3], &want, "{side}: set {uv_set}, offset {offset}");
        }
    }
}

/// glTF §3.9.4–3.9.5: the G-buffer's emission is factor × emissive texture (sRGB), its alpha
/// the occlusion `1 + strength · (R − 1)` of the (linear) occlusion texture.
#[test]
fn emission_and_occlusion_are_stored_per_pixel() {
    let material = Material {
        emissive_texture: Some(TextureRef::new(0)),
        emissive: Vec3::new(1.0, 2.0, 4.0),
        occlusion_texture: Some(TextureRef::new(1)),
        occlusion_strength: 0.5,
        ..Default::default()
    };
    let textures = vec![
        texture("emissive", 1, &[[128, 128, 128, 255]], Sampler::default()),
        texture("occlusion", 1, &[[0, 0, 0, 255]], Sampler::default()),
    ];
    let s = scene(square(0), material, textures);
    let e = scene::srgb_to_linear(128.0 / 255.0);
    let want = [e, 2.0 * e, 4.0 * e, 0.5];
    for (side, gb) in gbuffers(&s, &camera(3.0)) {
        let got = gb.emission.get(SIZE / 2, SIZE / 2);
        for k in 0..4 {
            // Half floats; a GPU may decode an sRGB texel within a third of its step.
            assert!(
                (got[k] - want[k]).abs() <= 0.01 * want[k],
                "{side}: {got:?} vs {want:?}"
            );
        }
    }
}

/// glTF §3.9.6: `MASK` keeps fragments whose alpha reaches the cutoff; the renderer's `BLEND`
/// policy (ordered dither) keeps, of alpha ½, exactly 8 of each 4 × 4 block of pixels.
#[test]
fn alpha_modes_cover_as_stated() {
    for (mode, want) in [
        (AlphaMode::Mask { cutoff: 0.5 }, 0),
        (AlphaMode::Mask { cutoff: 0.3 }, SIZE * SIZE),
        (AlphaMode::Opaque, SIZE * SIZE),
        (AlphaMode::Blend, SIZE * SIZE / 2),
    ] {
        let alpha = if mode == AlphaMode::Blend { 0.5 } else { 0.4 };
        let material = Material {
            base_color: Vec4::new(1.0, 1.0, 1.0, alpha),
            alpha_mode: mode,
            ..Default::default()
        };
        let s = scene(square(0), material, vec![]);
        // Close enough that the square covers every pixel.
        for (side, gb) in gbuffers(&s, &camera(1.5)) {
            let covered = gb
                .material
                .pixels()
                .iter()
                .filter(|&&m| m != gbuffer::NO_MATERIAL)
                .count() as u32;
            assert_eq!(covered, want, "{side}: {mode:?}");
        }
    }
}

/// glTF §3.9.6 `doubleSided`: a one-sided material's back faces are culled; a two-sided one
/// is seen from both sides.
#[test]
fn one_sided_materials_cull_back_faces() {
    for (double_sided, eye_z, seen) in
        [(false, 3.0, true), (false, -3.0, false), (true, -3.0, true)]
    {
        let material = Material {
            double_sided,
            ..Default::default()
        };
        let s = scene(square(0), material, vec![]);
        for (side, gb) in gbuffers(&s, &camera(eye_z)) {
            let covered = gb.material.get(SIZE / 2, SIZE / 2) != gbuffer::NO_MATERIAL;
            assert_eq!(
                covered, seen,
                "{side}: double-sided {double_sided}, eye z {eye_z}"
            );
        }
    }
}

/// The mip chains the GPU draws at load equal the CPU twin's (`LinearTexture::mipmapped`) for a
/// non-power-of-two texture in both colour spaces: level 0 exactly; below it, each level is
/// drawn from the one above as stored (where a side is odd, with the hardware's fixed-point
/// bilinear weights), so one step of rounding per level may carry down: at most `level`
/// steps (at least 1), a quarter step on average.
#[test]
fn gpu_mip_chains_match_the_cpu_twin() {
    let Some(gpu) = gpu::test_device(&gbuffer::device_needs()) else {
        return;
    };
    let (w, h) = (37u32, 20u32);
    let mut state = 12345u32;
    let texels: Vec<[u8; 4]> = (0..w * h)
        .map(|_| {
            std::array::from_fn(|_| {
                state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                (state >> 24) as u8
            })
        })
        .collect();
    let t = texture("noise", w, &texels, Sampler::default());
    // Read as base colour (sRGB) and as metallic-roughness (linear).
    let material = Material {
        base_color_texture: Some(TextureRef::new(0)),
        metallic_roughness_texture: Some(TextureRef::new(0)),
        ..Default::default()
    };
    let s = scene(square(0), material, vec![t.clone()]);
    let store = gbuffer::gpu::MaterialTextures::upload(
        &gpu.device,
        &gpu.queue,
        &s,
        &TextureOptions::default(),
    )
    .expect("upload");
    for space in [scene::ColorSpace::Srgb, scene::ColorSpace::Linear] {
        let twin = scene::LinearTexture::with_space(&t, space).mipmapped();
        let uploaded = store.get(0, space).expect("uploaded");
        assert_eq!(uploaded.texture.mip_level_count(), twin.levels());
        assert_eq!(twin.levels(), 6, "37 × 20 down to 1 × 1");
        let (mut total, mut count) = (0, 0);
        for level in 0..twin.levels() {
            let (lw, lh, want) = twin.level(level).expect("level");
            let got = gpu::transfer::read_texture_level(
                &gpu.device,
                &gpu.queue,
                &uploaded.texture,
                wgpu::TextureAspect::All,
                level,
            )
            .expect("read");
            assert_eq!(got.len(), (lw * lh * 4) as usize);
            let steps: Vec<i32> = got
                .iter()
                .zip(want)
                .map(|(&a, &b)| (i32::from(a) - i32::from(b)).abs())
                .collect();
            let worst = steps.iter().copied().max().unwrap_or(0);
            let allowed = if level == 0 { 0 } else { level.max(1) as i32 };
            assert!(worst <= allowed, "{space:?} level {level}: off by {worst}");
            (total, count) = (total + steps.iter().sum::<i32>(), count + steps.len());
        }
        let mean = f64::from(total) / count as f64;
        assert!(mean <= 0.25, "{space:?}: off by {mean:.3} on average");
    }
}

/// The G-buffer albedo as linear RGB.
fn albedo_image(gb: &GBuffer) -> Vec<Vec3> {
    gb.albedo
        .pixels()
        .iter()
        .map(|p| Vec3::new(p[0].into(), p[1].into(), p[2].into()) / 255.0)
        .collect()
}

/// ꟻLIP (Andersson et al. 2020, the `nv-flip` crate) of `test` against `reference`, both
/// linear RGB of `w × h`, sRGB-encoded.
fn flip(reference: &[Vec3], test: &[Vec3], (w, h): (u32, u32)) -> f32 {
    let srgb = |img: &[Vec3]| -> Vec<u8> {
        img.iter()
            .flat_map(|c| {
                c.to_array()
                    .map(|v| (scene::linear_to_srgb(v) * 255.0).round() as u8)
            })
            .collect()
    };
    let map = nv_flip::flip(
        nv_flip::FlipImageRgb8::with_data(w, h, &srgb(reference)),
        nv_flip::FlipImageRgb8::with_data(w, h, &srgb(test)),
        nv_flip::DEFAULT_PIXELS_PER_DEGREE,
    );
    nv_flip::FlipPool::from_image(&map).mean()
}

/// The checkerboard's ground plane seen at a grazing angle (texture minified up to ~100× along
/// the view), against a 16×-supersampled reference (4 × 4 samples per pixel, each filtered at
/// its own footprint, box-averaged in linear space): anisotropic filtering (16) is closest,
/// trilinear blurs the distance, level 0 alone aliases — in ꟻLIP, the CPU twin, and the GPU
/// within its implementation's filter (Vulkan leaves the anisotropic footprint to it).
#[test]
fn anisotropic_filtering_is_closest_to_supersampling() {
    let s = scene::checkerboard();
    let camera = s.camera.expect("camera");
    let (w, h) = (160u32, 90u32);
    let k = 4u32;
    let albedo = |scene: &Scene, size: (u32, u32), anisotropy: u32| {
        let options = TextureOptions {
            max_anisotropy: anisotropy,
        };
        albedo_image(
            &cpu::rasterize_with(scene, &camera, size, &options)
                .expect("cpu")
                .gbuffer,
        )
    };
    let fine = albedo(&s, (w * k, h * k), 16);
    let reference: Vec<Vec3> = (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let sum: Vec3 = (0..k * k)
                .map(|j| fine[((y * k + j / k) * w * k + x * k + j % k) as usize])
                .sum();
            sum / (k * k) as f32
        })
        .collect();
    let mut level0 = s.clone();
    level0.textures[0].sampler.mipmaps = None;
    let (aniso, trilinear, aliased) = (
        flip(&reference, &albedo(&s, (w, h), 16), (w, h)),
        flip(&reference, &albedo(&s, (w, h), 1), (w, h)),
        flip(&reference, &albedo(&level0, (w, h), 1), (w, h)),
    );
    eprintln!(
        "ꟻLIP vs 16× supersampling: anisotropic {aniso:.4}, trilinear {trilinear:.4}, level 0 {aliased:.4}"
    );
    assert!(
        aniso < trilinear && aniso < aliased,
        "{aniso} {trilinear} {aliased}"
    );
    // Measured with llvmpipe's Mesa 22.3: 0.031, 0.061, 0.099.
    assert!(aniso < 0.05, "anisotropic ꟻLIP {aniso}");
    if let Some(gpu) = gpu::test_device(&gbuffer::device_needs()) {
        let options = TextureOptions { max_anisotropy: 16 };
        let on_gpu = run_with(gpu, &s, &camera, (w, h), false, &options).expect("gpu");
        let gpu_flip = flip(&reference, &albedo_image(&on_gpu), (w, h));
        eprintln!("GPU anisotropic ꟻLIP {gpu_flip:.4}");
        // llvmpipe: 0.047.
        assert!(gpu_flip < trilinear, "GPU {gpu_flip}");
    }
}
