//! Every scene in ../shared/fixtures loads; bad input gives an error naming the file.

use std::path::PathBuf;

use scene::{AlphaMode, Sampler, Scene, SceneError, SceneErrorKind, UvTransform, Wrap};

fn fixtures() -> Option<PathBuf> {
    let dir = scene::shared_fixtures();
    if dir.is_none() {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI is set but ../shared/fixtures is missing"
        );
        eprintln!("skipping: ../shared/fixtures not found (set DEFERRED_FIXTURES)");
    }
    dir
}

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("scene-tests-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir.join(name)
}

/// The error of loading a file `name` holding `text`.
fn load_error(name: &str, text: &str) -> SceneError {
    let p = tmp(name);
    std::fs::write(&p, text).expect("write");
    Scene::load(&p).expect_err(name)
}

/// (path under fixtures, triangles as counted in SOURCES.md).
const FIXTURES: &[(&str, usize)] = &[
    ("sponza/dabrovic/sponza.gltf", 66_454),
    ("gltf/DamagedHelmet/DamagedHelmet.glb", 0),
    ("stanford/stanford-bunny.obj", 69_451),
    ("stanford/dragon-100k.ply", 100_000),
    ("cornell/CornellBox-Original.obj", 36),
    ("cornell/CornellBox-Empty-RG.obj", 12),
    ("cornell/CornellBox-Mirror.obj", 36),
    ("cornell/CornellBox-Sphere.obj", 2_188),
    ("cornell/CornellBox-Glossy.obj", 1_112),
    ("subdiv/fandisk.obj", 12_946),
    ("subdiv/spot/spot_triangulated.obj", 5_856),
    ("subdiv/spot/spot_quadrangulated.obj", 5_856),
    ("subdiv/spot/spot_control_mesh.obj", 0),
];

#[test]
fn every_fixture_scene_loads_with_its_documented_triangle_count() {
    let Some(dir) = fixtures() else { return };
    for &(file, tris) in FIXTURES {
        let s = Scene::load(dir.join(file)).unwrap_or_else(|e| panic!("{e}"));
        assert!(s.triangle_count() > 0, "{file}");
        if tris > 0 {
            assert_eq!(s.triangle_count(), tris, "{file}");
        }
        let b = s.bounds();
        assert!(
            b.min.is_finite() && b.max.is_finite() && b.diagonal() > 0.0,
            "{file}"
        );
    }
}

#[test]
fn sponza_bounds_match_its_position_accessors() {
    // x and z as SOURCES.md gives them; y from the POSITION accessors' min/max in
    // sponza.gltf (−0.9067…15.6533: SOURCES.md's −1.00 is the normals' minimum).
    let Some(dir) = fixtures() else { return };
    let b = Scene::load(dir.join("sponza/dabrovic/sponza.gltf"))
        .expect("sponza")
        .bounds();
    assert!(
        (b.min.x + 17.40).abs() < 0.01 && (b.max.x - 17.42).abs() < 0.01,
        "{b:?}"
    );
    assert!(
        (b.min.z + 7.80).abs() < 0.01 && (b.max.z - 7.80).abs() < 0.01,
        "{b:?}"
    );
    assert!(
        (b.min.y + 0.906_689).abs() < 1e-4 && (b.max.y - 15.653_312).abs() < 1e-4,
        "{b:?}"
    );
}

#[test]
fn damaged_helmet_has_its_base_colour_texture() {
    let Some(dir) = fixtures() else { return };
    let s = Scene::load(dir.join("gltf/DamagedHelmet/DamagedHelmet.glb")).expect("helmet");
    assert_eq!(s.triangle_count(), 46_356 / 3); // 46,356 indices in the glTF
    let m = &s.materials[s.meshes[0].material as usize];
    let t = &s.textures[m.base_color_texture.expect("base colour texture").texture as usize];
    assert_eq!((t.width, t.height), (2048, 2048));
}

#[test]
fn cornell_obj_keeps_its_emissive_light() {
    let Some(dir) = fixtures() else { return };
    let s = Scene::load(dir.join("cornell/CornellBox-Original.obj")).expect("cornell");
    assert!(
        s.materials
            .iter()
            .any(|m| m.name == "light" && m.emissive.x == 17.0)
    );
}

/// `Ks 0 0 0` states a material without specular reflection (the Cornell box's, which the
/// path tracer and the renderer then both shade Lambert only); any other or no `Ks` keeps
/// the default dielectric specular.
#[test]
fn obj_black_ks_means_no_specular() {
    std::fs::write(
        tmp("ks.mtl"),
        "newmtl matte\nKd 1 0 0\nKs 0 0 0\nnewmtl shiny\nKd 1 0 0\nKs 0.5 0.5 0.5\n\
         newmtl plain\nKd 1 0 0\n",
    )
    .expect("mtl");
    let obj = tmp("ks.obj");
    std::fs::write(
        &obj,
        "mtllib ks.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl matte\nf 1 2 3\nusemtl shiny\n\
         f 1 2 3\nusemtl plain\nf 1 2 3\n",
    )
    .expect("obj");
    let s = Scene::load(&obj).expect("obj");
    let specular = |name: &str| {
        s.materials
            .iter()
            .find(|m| m.name == name)
            .map(|m| m.specular)
    };
    assert_eq!(specular("matte"), Some(0.0));
    assert_eq!(specular("shiny"), Some(1.0));
    assert_eq!(specular("plain"), Some(1.0));
}

#[test]
fn missing_file_names_the_file() {
    let e = Scene::load("/no/such/scene.gltf").unwrap_err();
    assert!(e.to_string().contains("/no/such/scene.gltf"), "{e}");
    assert!(matches!(e.kind, SceneErrorKind::Io(_)));
}

#[test]
fn unknown_extension_is_an_error() {
    let e = load_error("scene.xyz", "hello");
    assert!(
        matches!(e.kind, SceneErrorKind::UnsupportedFormat(_)),
        "{e}"
    );
}

#[test]
fn truncated_gltf_buffer_is_an_error() {
    let Some(dir) = fixtures() else { return };
    let src = dir.join("sponza/dabrovic");
    let gltf = tmp("truncated.gltf");
    std::fs::copy(src.join("sponza.gltf"), &gltf).expect("copy");
    let bin = std::fs::read(src.join("sponza.bin")).expect("bin");
    std::fs::write(tmp("sponza.bin"), &bin[..bin.len() / 2]).expect("write");
    let e = Scene::load(&gltf).unwrap_err();
    assert!(e.to_string().contains("truncated.gltf"), "{e}");
    assert!(matches!(e.kind, SceneErrorKind::Gltf(_)), "{e}");
}

#[test]
fn gltf_without_meshes_is_an_error() {
    let e = load_error(
        "empty.gltf",
        r#"{"asset":{"version":"2.0"},"scenes":[{"nodes":[0]}],"nodes":[{}],"scene":0}"#,
    );
    assert!(matches!(e.kind, SceneErrorKind::NoMeshes), "{e}");
}

#[test]
fn undecodable_texture_is_an_error() {
    let dir = tmp("badtex");
    std::fs::create_dir_all(&dir).expect("dir");
    std::fs::write(dir.join("m.mtl"), "newmtl m\nKd 1 1 1\nmap_Kd broken.png\n").expect("mtl");
    std::fs::write(dir.join("broken.png"), b"\x89PNG\r\n\x1a\nnot really").expect("png");
    std::fs::write(
        dir.join("t.obj"),
        "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl m\nf 1 2 3\n",
    )
    .expect("obj");
    let e = Scene::load(dir.join("t.obj")).unwrap_err();
    assert!(matches!(e.kind, SceneErrorKind::Texture { .. }), "{e}");
    assert!(e.to_string().contains("broken.png"), "{e}");
}

#[test]
fn nan_positions_are_an_error() {
    let e = load_error("nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n");
    assert!(
        e.to_string().contains("finite numbers") && e.to_string().contains("line 2"),
        "{e}"
    );
}

#[test]
fn ply_with_out_of_range_index_is_an_error() {
    let e = load_error(
        "bad.ply",
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n",
    );
    assert!(e.to_string().contains("out of range"), "{e}");
}

#[test]
fn garbage_and_truncated_files_never_panic() {
    let Some(dir) = fixtures() else { return };
    let sources = [
        "cornell/CornellBox-Original.obj",
        "stanford/dragon-100k.ply",
        "gltf/DamagedHelmet/DamagedHelmet.glb",
    ];
    for src in sources {
        let bytes = std::fs::read(dir.join(src)).expect("fixture");
        let ext = src.rsplit('.').next().expect("ext");
        for (k, cut) in [7usize, 100, 1000, bytes.len() / 3, bytes.len() - 1]
            .into_iter()
            .enumerate()
        {
            let p = tmp(&format!("cut{k}.{ext}"));
            std::fs::write(&p, &bytes[..cut.min(bytes.len())]).expect("write");
            let _ = Scene::load(&p); // an error or a (partial but valid) scene, never a panic
        }
    }
}

#[test]
fn command_line_lights_parse_and_reject_bad_input() {
    let l: scene::Light = "point:0,1,0,5".parse().expect("point");
    assert!(matches!(l, scene::Light::Point { radius, .. } if radius == 5.0));
    assert!(
        "spot:0,1,0,0,-1,0,4,20,30,1,1,1,2"
            .parse::<scene::Light>()
            .is_ok()
    );
    assert!("dir:0,-1,0".parse::<scene::Light>().is_ok());
    for bad in [
        "point:0,1,0",
        "point:0,1,0,-1",
        "laser:1,2,3",
        "dir:0,0,0",
        "point:a,b,c,d",
        "point:0,nan,0,1",
        "spot:0,1,0,0,-1,0,4,40,30",
    ] {
        assert!(bad.parse::<scene::Light>().is_err(), "{bad} accepted");
    }
}

#[test]
fn bvh_closest_and_any_hit_on_the_cornell_box() {
    let s = scene::cornell_box();
    let bvh = scene::Bvh::build(&s);
    // Straight down from under the ceiling at the box centre: the floor is at y = 0 unless a
    // block is in the way; (0.1, y, 0.5) is clear of both blocks.
    let hit = bvh
        .closest_hit(glam::Vec3::new(0.1, 0.5, 0.5), glam::Vec3::NEG_Y, 10.0)
        .expect("floor");
    assert!(
        (hit.position.y).abs() < 1e-5 && (hit.t - 0.5).abs() < 1e-5,
        "{hit:?}"
    );
    assert_eq!(s.meshes[hit.mesh as usize].name, "room");
    // Above the tall block (top at y = 0.33).
    let hit = bvh
        .closest_hit(glam::Vec3::new(0.37, 0.5, 0.35), glam::Vec3::NEG_Y, 10.0)
        .expect("block");
    assert!((hit.position.y - 0.33).abs() < 1e-5, "{hit:?}");
    assert!(bvh.any_hit(glam::Vec3::new(0.37, 0.5, 0.35), glam::Vec3::NEG_Y, 0.2));
    assert!(!bvh.any_hit(glam::Vec3::new(0.37, 0.5, 0.35), glam::Vec3::NEG_Y, 0.1));
    // Leaving through the open front (z < 0), above both blocks, hits nothing.
    assert!(
        bvh.closest_hit(glam::Vec3::new(0.1, 0.45, 0.3), glam::Vec3::NEG_Z, 10.0)
            .is_none()
    );
    assert!(
        bvh.closest_hit(glam::Vec3::ZERO, glam::Vec3::ZERO, 1.0)
            .is_none()
    );
}

fn scene_files(dir: &std::path::Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("readable fixtures").flatten() {
        let p = entry.path();
        if p.is_dir() {
            scene_files(&p, out);
        } else if p
            .extension()
            .is_some_and(|e| ["obj", "ply", "gltf", "glb"].contains(&e.to_string_lossy().as_ref()))
        {
            out.push(p);
        }
    }
}

#[test]
fn every_scene_file_under_fixtures_loads() {
    let Some(dir) = fixtures() else { return };
    let mut files = Vec::new();
    scene_files(&dir, &mut files);
    assert!(files.len() >= 70, "only {} scene files found", files.len());
    for f in files {
        let s = Scene::load(&f).unwrap_or_else(|e| panic!("{e}"));
        assert!(s.triangle_count() > 0, "{}", f.display());
    }
}

/// The five texture roles of DamagedHelmet's one material, as its JSON names them
/// (baseColorTexture 0, metallicRoughnessTexture 1, emissiveTexture 2, occlusionTexture 3,
/// normalTexture 4), each through TEXCOORD_0 untransformed, with the default sampler.
#[test]
fn damaged_helmet_has_all_five_texture_roles() {
    let Some(dir) = fixtures() else { return };
    let s = Scene::load(dir.join("gltf/DamagedHelmet/DamagedHelmet.glb")).expect("helmet");
    let m = &s.materials[s.meshes[0].material as usize];
    let roles: Vec<(&str, u32)> = m.textures().map(|(r, t)| (r, t.texture)).collect();
    assert_eq!(
        roles,
        [
            ("base colour", 0),
            ("metallic-roughness", 1),
            ("normal", 4),
            ("occlusion", 3),
            ("emissive", 2)
        ]
    );
    assert!(
        m.textures()
            .all(|(_, t)| t.uv_set == 0 && t.transform == UvTransform::IDENTITY)
    );
    assert_eq!((m.normal_scale, m.occlusion_strength), (1.0, 1.0));
    assert_eq!(m.emissive, glam::Vec3::ONE);
    assert_eq!(m.alpha_mode, AlphaMode::Opaque);
    assert!(!m.double_sided);
    assert!(s.textures.iter().all(|t| t.sampler == Sampler::default()));
    // The file has no TANGENT: MikkTSpace's, unit, perpendicular to the normals, w = ±1.
    let mesh = &s.meshes[0];
    assert_eq!(mesh.tangents.len(), mesh.positions.len());
    for (t, n) in mesh.tangents.iter().zip(&mesh.normals) {
        let xyz = t.truncate();
        assert!((xyz.length() - 1.0).abs() < 1e-3, "{t}");
        assert!(xyz.dot(*n).abs() < 1e-3, "{t} against {n}");
        assert!(t.w.abs() == 1.0, "{t}");
    }
}

/// A one-triangle glTF written here with every material feature the model holds: a second
/// texture-coordinate set, tangents, vertex colours, `KHR_texture_transform`, a sampler, a
/// normal scale, an occlusion strength, MASK with its cutoff, `doubleSided`,
/// `KHR_materials_transmission` and `KHR_materials_ior`;
/// `base_color_info` is the base colour's `textureInfo`.
fn featured_gltf(name: &str, base_color_info: &str) -> PathBuf {
    let dir = tmp(name);
    std::fs::create_dir_all(&dir).expect("dir");
    let mut bin: Vec<u8> = Vec::new();
    let mut floats = |v: &[f32]| {
        for x in v {
            bin.extend_from_slice(&x.to_le_bytes());
        }
    };
    floats(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]); // POSITION, 36 B
    floats(&[0.0, 0.0, 1.0, 0.0, 0.0, 1.0]); // TEXCOORD_0, 24 B
    floats(&[0.5, 0.5, 1.0, 0.5, 0.5, 1.0]); // TEXCOORD_1, 24 B
    floats(&[1.0, 0.0, 0.0, -1.0].repeat(3)); // TANGENT, 48 B
    floats(&[1.0, 0.5, 0.25, 1.0].repeat(3)); // COLOR_0, 48 B
    std::fs::write(dir.join("t.bin"), &bin).expect("bin");
    image::RgbaImage::from_pixel(2, 2, image::Rgba([200, 100, 50, 255]))
        .save(dir.join("t.png"))
        .expect("png");
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"extensionsUsed":["KHR_texture_transform","KHR_materials_transmission","KHR_materials_ior"],
        "buffers":[{{"uri":"t.bin","byteLength":180}}],
        "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":24}},
          {{"buffer":0,"byteOffset":60,"byteLength":24}},{{"buffer":0,"byteOffset":84,"byteLength":48}},
          {{"buffer":0,"byteOffset":132,"byteLength":48}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
          {{"bufferView":1,"componentType":5126,"count":3,"type":"VEC2"}},
          {{"bufferView":2,"componentType":5126,"count":3,"type":"VEC2"}},
          {{"bufferView":3,"componentType":5126,"count":3,"type":"VEC4"}},
          {{"bufferView":4,"componentType":5126,"count":3,"type":"VEC4"}}],
        "images":[{{"uri":"t.png"}}],
        "samplers":[{{"wrapS":33071,"wrapT":33648,"magFilter":9728,"minFilter":9728}}],
        "textures":[{{"source":0,"sampler":0}}],
        "materials":[{{"name":"featured","pbrMetallicRoughness":{{"baseColorTexture":{base_color_info},
            "metallicRoughnessTexture":{{"index":0}}}},
          "normalTexture":{{"index":0,"scale":0.5}},"occlusionTexture":{{"index":0,"strength":0.25}},
          "emissiveTexture":{{"index":0,"texCoord":1}},"emissiveFactor":[1,1,1],
          "alphaMode":"MASK","alphaCutoff":0.3,"doubleSided":true,
          "extensions":{{"KHR_materials_transmission":{{"transmissionFactor":0.75}},"KHR_materials_ior":{{"ior":1.33}}}}}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"TEXCOORD_0":1,"TEXCOORD_1":2,"TANGENT":3,"COLOR_0":4}},"material":0}}]}}],
        "nodes":[{{"mesh":0}}],"scenes":[{{"nodes":[0]}}],"scene":0}}"#
    );
    let path = dir.join("featured.gltf");
    std::fs::write(&path, json).expect("gltf");
    path
}

#[test]
fn gltf_material_features_load_as_the_file_states() {
    let path = featured_gltf(
        "featured",
        r#"{"index":0,"texCoord":0,"extensions":{"KHR_texture_transform":
            {"offset":[0.5,0],"rotation":0.25,"scale":[2,3],"texCoord":1}}}"#,
    );
    let s = Scene::load(&path).expect("featured");
    let m = &s.materials[s.meshes[0].material as usize];
    let base = m.base_color_texture.expect("base colour");
    // The extension's texCoord overrides the info's.
    assert_eq!(base.uv_set, 1);
    assert_eq!(
        base.transform,
        UvTransform {
            offset: glam::Vec2::new(0.5, 0.0),
            rotation: 0.25,
            scale: glam::Vec2::new(2.0, 3.0)
        }
    );
    assert_eq!(m.emissive_texture.expect("emissive").uv_set, 1);
    assert_eq!((m.normal_scale, m.occlusion_strength), (0.5, 0.25));
    assert_eq!(m.alpha_mode, AlphaMode::Mask { cutoff: 0.3 });
    assert!(m.double_sided);
    assert_eq!((m.transmission, m.ior), (0.75, 1.33));
    assert_eq!(m.textures().count(), 5);
    assert_eq!(
        s.textures[0].sampler,
        Sampler {
            wrap_u: Wrap::ClampToEdge,
            wrap_v: Wrap::MirroredRepeat,
            mag_linear: false,
            min_linear: false,
            mipmaps: None,
        }
    );
    let mesh = &s.meshes[0];
    assert_eq!(mesh.uvs1[1], glam::Vec2::new(1.0, 0.5));
    assert_eq!(mesh.tangents, vec![glam::Vec4::new(1.0, 0.0, 0.0, -1.0); 3]);
    assert_eq!(mesh.colors, vec![glam::Vec4::new(1.0, 0.5, 0.25, 1.0); 3]);
}

/// A texture read through TEXCOORD_2 is refused with the material and role named.
#[test]
fn a_third_texture_coordinate_set_is_refused() {
    let path = featured_gltf("texcoord2", r#"{"index":0,"texCoord":2}"#);
    let e = Scene::load(&path).expect_err("TEXCOORD_2");
    let text = e.to_string();
    assert!(
        text.contains("TEXCOORD_2") && text.contains("featured") && text.contains("base colour"),
        "{text}"
    );
}

/// An OBJ material's `norm` normal map (with `-bm`), `map_Ke` and `d` load into the same
/// model; a texture file used twice is decoded once.
#[test]
fn mtl_normal_emissive_and_dissolve_load() {
    let dir = tmp("mtlroles");
    std::fs::create_dir_all(&dir).expect("dir");
    image::RgbaImage::from_pixel(2, 2, image::Rgba([128, 128, 255, 255]))
        .save(dir.join("n.png"))
        .expect("png");
    std::fs::write(
        dir.join("m.mtl"),
        "newmtl m\nKd 1 1 1\nd 0.5\nmap_Kd n.png\nnorm -bm 0.75 n.png\nmap_Ke n.png\n",
    )
    .expect("mtl");
    std::fs::write(
        dir.join("t.obj"),
        "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl m\nf 1 2 3\n",
    )
    .expect("obj");
    let s = Scene::load(dir.join("t.obj")).expect("obj");
    let m = &s.materials[s.meshes[0].material as usize];
    assert_eq!(s.textures.len(), 1, "one file, one texture");
    assert_eq!(m.normal_texture.map(|t| t.texture), Some(0));
    assert_eq!(m.normal_scale, 0.75);
    assert_eq!(m.emissive_texture.map(|t| t.texture), Some(0));
    assert_eq!(m.emissive, glam::Vec3::ONE);
    assert_eq!(m.alpha_mode, AlphaMode::Blend);
    assert_eq!(m.base_color.w, 0.5);
}

/// A material that reads TEXCOORD_1 on a mesh without that set is refused, the mesh and the
/// role named.
#[test]
fn a_missing_second_texture_coordinate_set_is_refused() {
    let path = featured_gltf("no-texcoord1", r#"{"index":0}"#);
    let json = std::fs::read_to_string(&path).expect("read");
    std::fs::write(&path, json.replace(r#""TEXCOORD_1":2,"#, "")).expect("write");
    let text = Scene::load(&path).expect_err("no TEXCOORD_1").to_string();
    assert!(
        text.contains("TEXCOORD_1") && text.contains("emissive"),
        "{text}"
    );
}

/// A glTF whose emission overflows f32 (1e39 parses as infinity) or is negative is refused
/// with the material named (factors with a range, such as roughness, the loader clamps); the
/// same checks run on a scene built in code.
#[test]
fn non_finite_material_factors_are_refused() {
    let gltf = |material: &str| {
        format!(
            r#"{{"asset":{{"version":"2.0"}},"buffers":[{{"byteLength":36,"uri":"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}}],
            "bufferViews":[{{"buffer":0,"byteLength":36}}],
            "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}}],
            "materials":[{material}],
            "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"material":0}}]}}],
            "nodes":[{{"mesh":0}}],"scenes":[{{"nodes":[0]}}],"scene":0}}"#
        )
    };
    for (name, material, says) in [
        (
            "huge.gltf",
            r#"{"name":"huge","emissiveFactor":[1e39,0,0]}"#,
            "emission",
        ),
        (
            "negative.gltf",
            r#"{"name":"negative","emissiveFactor":[-1,0,0]}"#,
            "emission",
        ),
    ] {
        let e = load_error(name, &gltf(material)).to_string();
        let material_name = name.trim_end_matches(".gltf");
        assert!(e.contains(says) && e.contains(material_name), "{name}: {e}");
    }
    let mut s = scene::cornell_box();
    s.materials[0].normal_scale = f32::NAN;
    let e = s.validate().expect_err("NaN normal scale").to_string();
    assert!(
        e.contains("normal scale") && e.contains(&s.materials[0].name),
        "{e}"
    );
}
