//! A scene reads only regular files inside its own folder (after `..`, percent-decoding and
//! symbolic links), never more bytes than it declares: each case below would load a triangle
//! if the loader read the file it names outside the folder, so a passing case proves the file
//! was not used.

mod common;

use common::base64;
use std::path::{Path, PathBuf};

/// A fresh folder `<tmp>/<name>` holding `outside/tri.bin` (a valid triangle buffer) and an
/// empty `scene/` folder.
fn layout(name: &str) -> (PathBuf, PathBuf) {
    let root = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("folder-rule")
        .join(name);
    let _ = std::fs::remove_dir_all(&root);
    let (outside, scene) = (root.join("outside"), root.join("scene"));
    std::fs::create_dir_all(&outside).expect("outside folder");
    std::fs::create_dir_all(scene.join("sub")).expect("scene folder");
    std::fs::write(outside.join("tri.bin"), triangle()).expect("buffer");
    std::fs::write(outside.join("m.mtl"), "newmtl red\nKd 1 0 0\n").expect("mtl");
    (outside, scene)
}

/// Three `vec3<f32>` positions: 36 bytes.
fn triangle() -> Vec<u8> {
    [0f32, 0., 0., 1., 0., 0., 0., 1., 0.]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect()
}

/// A glTF of one triangle whose buffer (36 bytes declared) is `uri`.
fn gltf(uri: &str) -> String {
    format!(
        r#"{{"asset":{{"version":"2.0"}},"buffers":[{{"uri":{uri:?},"byteLength":36}}],
"bufferViews":[{{"buffer":0,"byteLength":36}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}],
"nodes":[{{"mesh":0}}],"scenes":[{{"nodes":[0]}}],"scene":0}}"#
    )
}

fn load_gltf(scene: &Path, uri: &str) -> Result<scene::Scene, String> {
    let file = scene.join("scene.gltf");
    std::fs::write(&file, gltf(uri)).expect("gltf");
    scene::Scene::load(&file).map_err(|e| e.to_string())
}

#[test]
fn gltf_buffers_outside_the_folder_are_refused() {
    let (outside, scene) = layout("gltf");
    let absolute = outside.join("tri.bin").display().to_string();
    let cases = [
        ("../outside/tri.bin", "outside the scene's folder"),
        ("%2e%2e/outside/tri.bin", "outside the scene's folder"),
        ("..%2Foutside%2Ftri.bin", "outside the scene's folder"),
        ("sub/../../outside/tri.bin", "outside the scene's folder"),
        (absolute.as_str(), "absolute paths are not read"),
        (&format!("file://{absolute}"), "only relative paths"),
        ("/dev/zero", "absolute paths are not read"),
        ("https://example.com/tri.bin", "only relative paths"),
        ("%ff%fe.bin", "not UTF-8"),
    ];
    for (uri, why) in cases {
        let e = load_gltf(&scene, uri)
            .err()
            .unwrap_or_else(|| panic!("{uri} was read"));
        assert!(e.contains(why), "{uri}: {e}");
    }
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink(outside.join("tri.bin"), scene.join("link.bin")).expect("link");
        refused(
            load_gltf(&scene, "link.bin"),
            "a link out of the folder was read",
            "outside the scene's folder",
        );
        std::os::unix::fs::symlink(&outside, scene.join("out")).expect("link");
        refused(
            load_gltf(&scene, "out/tri.bin"),
            "a linked folder was read",
            "outside the scene's folder",
        );
    }
}

#[test]
fn gltf_buffers_inside_the_folder_load_and_are_bounded() {
    let (_, scene) = layout("gltf-inside");
    std::fs::write(scene.join("sub/tri.bin"), triangle()).expect("buffer");
    for uri in [
        "sub/tri.bin",
        "sub/../sub/tri.bin",
        "./sub/tri.bin",
        "sub%2Ftri.bin",
    ] {
        let s = load_gltf(&scene, uri).unwrap_or_else(|e| panic!("{uri}: {e}"));
        assert_eq!(s.triangle_count(), 1, "{uri}");
    }
    let data = format!(
        "data:application/octet-stream;base64,{}",
        base64(&triangle())
    );
    assert_eq!(
        load_gltf(&scene, &data).expect("data URI").triangle_count(),
        1
    );
    // A file far longer than the 36 bytes declared is not read (a /dev/zero-like buffer).
    let mut long = triangle();
    long.resize(1 << 20, 0);
    std::fs::write(scene.join("long.bin"), long).expect("buffer");
    refused(
        load_gltf(&scene, "long.bin"),
        "read past the declared length",
        "more than the 39 allowed",
    );
    std::fs::create_dir_all(scene.join("dir.bin")).expect("folder");
    refused(
        load_gltf(&scene, "dir.bin"),
        "a folder was read as a buffer",
        "not a regular file",
    );
    refused(
        load_gltf(&scene, "missing.bin"),
        "a missing buffer",
        "no such file",
    );
}

/// Asserts that `loaded` failed (else panics with `what`) with an error that says `why`.
fn refused(loaded: Result<scene::Scene, String>, what: &str, why: &str) {
    let e = loaded.err().unwrap_or_else(|| panic!("{what}"));
    assert!(e.contains(why), "{what}: {e}");
}

fn load_obj(scene: &Path, obj: &str, mtl: Option<&str>) -> Result<scene::Scene, String> {
    if let Some(mtl) = mtl {
        std::fs::write(scene.join("m.mtl"), mtl).expect("mtl");
    }
    let file = scene.join("scene.obj");
    std::fs::write(&file, obj).expect("obj");
    scene::Scene::load(&file).map_err(|e| e.to_string())
}

const TRIANGLE_OBJ: &str =
    "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl red\nf 1/1 2/2 3/3\n";

#[test]
fn obj_materials_and_textures_outside_the_folder_are_refused() {
    let (outside, scene) = layout("obj");
    refused(
        load_obj(
            &scene,
            &format!("mtllib ../outside/m.mtl\n{TRIANGLE_OBJ}"),
            None,
        ),
        "a material library outside the folder was read",
        "outside the scene's folder",
    );
    let absolute = outside.join("m.mtl").display().to_string();
    refused(
        load_obj(&scene, &format!("mtllib {absolute}\n{TRIANGLE_OBJ}"), None),
        "an absolute material library was read",
        "absolute paths are not read",
    );
    std::fs::write(outside.join("t.png"), b"not read").expect("texture");
    let mtl = "newmtl red\nKd 1 0 0\nmap_Kd ../outside/t.png\n";
    refused(
        load_obj(&scene, &format!("mtllib m.mtl\n{TRIANGLE_OBJ}"), Some(mtl)),
        "a texture outside the folder was read",
        "outside the scene's folder",
    );
}

#[test]
fn obj_inside_the_folder_loads_and_bad_colours_name_their_line() {
    let (_, scene) = layout("obj-inside");
    let s = load_obj(
        &scene,
        &format!("mtllib m.mtl\n{TRIANGLE_OBJ}"),
        Some("newmtl red\nKd 1 0 0\n"),
    )
    .expect("inside the folder");
    assert_eq!(s.materials[0].base_color.x, 1.0);
    // A missing library costs only the materials.
    let s = load_obj(&scene, &format!("mtllib none.mtl\n{TRIANGLE_OBJ}"), None).expect("loads");
    assert_eq!(s.triangle_count(), 1);
    for (colour, line) in [("Kd 0.5", 2), ("Ks", 2), ("Ka 1 nan 0", 2), ("Ke 1 2 x", 2)] {
        let mtl = format!("newmtl red\n{colour}\n");
        let e = load_obj(&scene, &format!("mtllib m.mtl\n{TRIANGLE_OBJ}"), Some(&mtl))
            .err()
            .unwrap_or_else(|| panic!("{colour:?} accepted"));
        assert!(e.contains(&format!("line {line}")), "{colour:?}: {e}");
    }
}
