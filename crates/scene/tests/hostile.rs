//! Hand-written hostile glTF files: each must be a clear error, never a panic, an endless
//! walk or an allocation without bound.

mod common;

use common::base64;
use std::path::Path;

/// 36 bytes of three positions, then three u16 indices `indices` (padded to 44 bytes).
fn buffer(indices: [u16; 3]) -> String {
    let mut b: Vec<u8> = [0f32, 0., 0., 1., 0., 0., 0., 1., 0.]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    b.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    b.extend([0, 0]);
    format!("data:application/octet-stream;base64,{}", base64(&b))
}

/// One indexed triangle (no normals), with `nodes` as the node array and `roots` the scene.
fn gltf(indices: [u16; 3], nodes: &str, roots: &str) -> String {
    format!(
        r#"{{"asset":{{"version":"2.0"}},"buffers":[{{"uri":"{}","byteLength":44}}],
"bufferViews":[{{"buffer":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":6}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
{{"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],
"nodes":{nodes},"scenes":[{{"nodes":{roots}}}],"scene":0}}"#,
        buffer(indices)
    )
}

fn load(name: &str, text: &str) -> Result<scene::Scene, String> {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("hostile");
    std::fs::create_dir_all(&dir).expect("folder");
    let file = dir.join(format!("{name}.gltf"));
    std::fs::write(&file, text).expect("gltf");
    scene::Scene::load(&file).map_err(|e| e.to_string())
}

#[test]
fn the_triangle_itself_loads() {
    let s = load("ok", &gltf([0, 1, 2], r#"[{"mesh":0}]"#, "[0]")).expect("valid");
    assert_eq!(s.triangle_count(), 1);
}

#[test]
fn an_index_out_of_range_without_normals_is_an_error() {
    let e = load("index", &gltf([0, 1, 7], r#"[{"mesh":0}]"#, "[0]")).expect_err("index 7");
    assert!(e.contains("index 7 out of range"), "{e}");
}

#[test]
fn node_cycles_are_an_error() {
    let e = load(
        "self",
        &gltf([0, 1, 2], r#"[{"mesh":0,"children":[0]}]"#, "[0]"),
    )
    .expect_err("a node that is its own child");
    assert!(e.contains("cycle"), "{e}");
    let e = load(
        "cycle",
        &gltf(
            [0, 1, 2],
            r#"[{"children":[1]},{"mesh":0,"children":[0]}]"#,
            "[0]",
        ),
    )
    .expect_err("a two-node cycle");
    assert!(e.contains("cycle"), "{e}");
}

#[test]
fn a_node_reused_on_many_levels_is_bounded() {
    // Node i has node i + 1 twice as its child: 2^40 paths to the last node.
    let nodes: Vec<String> = (0..40)
        .map(|i| format!(r#"{{"children":[{0},{0}]}}"#, i + 1))
        .chain([r#"{"mesh":0}"#.to_string()])
        .collect();
    let start = std::time::Instant::now();
    let e = load(
        "explode",
        &gltf([0, 1, 2], &format!("[{}]", nodes.join(",")), "[0]"),
    )
    .expect_err("2^40 instances");
    assert!(e.contains("node instances"), "{e}");
    assert!(start.elapsed().as_secs() < 30, "took {:?}", start.elapsed());
}

/// The triangle of [`gltf`] with its accessors and buffer views replaced (buffer 0 holds 36
/// bytes of positions, then indices 0, 1, 2 as u16 and two bytes of padding).
fn with_accessors(views: &str, accessors: &str, attributes: &str, indices: &str) -> String {
    format!(
        r#"{{"asset":{{"version":"2.0"}},"buffers":[{{"uri":"{}","byteLength":44}}],
"bufferViews":{views},"accessors":{accessors},
"meshes":[{{"primitives":[{{"attributes":{attributes}{indices}}}]}}],
"nodes":[{{"mesh":0}}],"scenes":[{{"nodes":[0]}}],"scene":0}}"#,
        buffer([0, 1, 2])
    )
}

const VIEWS: &str = r#"[{"buffer":0,"byteLength":36},{"buffer":0,"byteOffset":36,"byteLength":6}]"#;
const POSITIONS: &str =
    r#"{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}"#;

#[test]
fn accessors_of_the_wrong_type_or_size_are_errors() {
    // Accessor 0 is POSITION, 1 the one under test: a line of the table, used as indices
    // unless the line names an attribute.
    let cases: Vec<&str> = include_str!("hostile/accessors.tsv")
        .lines()
        .filter(|l| !l.starts_with('#'))
        .collect();
    assert_eq!(cases.len(), 14, "accessors.tsv lost cases");
    for line in cases {
        let [case, under_test, attribute, why] = line.split('\t').collect::<Vec<_>>()[..] else {
            panic!("accessors.tsv: four tab-separated fields expected in {line:?}");
        };
        let (attributes, indices) = if attribute == "-" {
            (r#"{"POSITION":0}"#.to_string(), r#","indices":1"#)
        } else {
            (format!(r#"{{"POSITION":0,"{attribute}":1}}"#), "")
        };
        let text = with_accessors(
            VIEWS,
            &format!("[{POSITIONS},{under_test}]"),
            &attributes,
            indices,
        );
        let e = load(&format!("accessor-{}", case.replace(' ', "-")), &text).expect_err(case);
        assert!(e.contains(why), "{case}: {e}");
    }
    // POSITION itself of a wrong type, and a byteStride smaller than the element.
    for (case, views, positions, why) in [
        (
            "scalar positions",
            VIEWS,
            POSITIONS.replace("VEC3", "SCALAR"),
            "must be Vec3",
        ),
        (
            "mat4 positions",
            VIEWS,
            POSITIONS.replace("VEC3", "MAT4"),
            "must be Vec3",
        ),
        (
            "u8 positions",
            VIEWS,
            POSITIONS.replace("5126", "5121"),
            "must be Vec3",
        ),
        (
            "a stride below the element",
            r#"[{"buffer":0,"byteLength":36,"byteStride":4},{"buffer":0,"byteOffset":36,"byteLength":6}]"#,
            POSITIONS.to_string(),
            "byteStride 4 is smaller than the 12-byte element",
        ),
        (
            "a view past its buffer",
            r#"[{"buffer":0,"byteLength":36,"byteOffset":12},{"buffer":0,"byteOffset":36,"byteLength":6}]"#,
            POSITIONS.to_string(),
            "reaches past the 44 bytes of buffer 0",
        ),
    ] {
        let indices = r#"{"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}"#;
        let text = with_accessors(
            views,
            &format!("[{positions},{indices}]"),
            r#"{"POSITION":0}"#,
            r#","indices":1"#,
        );
        let e = load(&format!("accessor-{}", case.replace(' ', "-")), &text).expect_err(case);
        assert!(e.contains(why), "{case}: {e}");
    }
}

#[test]
fn sparse_accessors_and_normalized_texture_coordinates_are_read() {
    // NORMAL: sparse without a buffer view, zeros except element 1 (the u16 at byte 38 of the
    // buffer), which takes the 12 bytes at offset 12 of view 0: the position (1, 0, 0).
    let normals = r#"{"componentType":5126,"count":3,"type":"VEC3","sparse":{"count":1,"indices":{"bufferView":1,"byteOffset":2,"componentType":5123},"values":{"bufferView":0,"byteOffset":12}}}"#;
    // TEXCOORD_0: normalized u16 pairs over the bytes of 1.0f32 (00 00 80 3f) at offset 12.
    let uvs = r#"{"bufferView":0,"byteOffset":12,"componentType":5123,"count":3,"type":"VEC2","normalized":true}"#;
    let text = with_accessors(
        r#"[{"buffer":0,"byteLength":36},{"buffer":0,"byteOffset":36,"byteLength":8}]"#,
        &format!("[{POSITIONS},{normals},{uvs}]"),
        r#"{"POSITION":0,"NORMAL":1,"TEXCOORD_0":2}"#,
        "",
    );
    let s = load("sparse", &text).expect("a sparse accessor");
    let mesh = &s.meshes[0];
    // Zero normals become +Y (`normalize_or`).
    assert_eq!(mesh.normals[1], glam::Vec3::X);
    assert_eq!(mesh.normals[0], glam::Vec3::Y);
    assert_eq!(mesh.uvs[0], glam::Vec2::new(0.0, 16256.0 / 65535.0));
}

fn load_file(name: &str, text: &[u8]) -> Result<scene::Scene, String> {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("hostile")
        .join(name);
    std::fs::create_dir_all(&dir).expect("folder");
    let file = dir.join(name);
    std::fs::write(&file, text).expect("file");
    scene::Scene::load(&file).map_err(|e| e.to_string())
}

#[test]
fn obj_and_mtl_errors_name_their_line() {
    const V: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    let cases = [
        (
            format!("{V}f 1\n"),
            "line 4: a face needs at least three vertices, got 1",
        ),
        (
            format!("{V}f 1 2\n"),
            "line 4: a face needs at least three vertices, got 2",
        ),
        (
            format!("{V}f 1 2 4\n"),
            "line 4: face vertex \"4\": position index 4 outside 1..=3",
        ),
        (format!("{V}f 1 2 -4\n"), "position index -4 outside 1..=3"),
        (
            format!("{V}f 1/1 2/1 3/1\n"),
            "texture coordinate index 1 outside 1..=0",
        ),
        (format!("{V}f 1 2 x\n"), "\"x\" is not an index"),
        (
            format!("v 0 0 nan\n{V}f 1 2 3\n"),
            "line 1: a vertex position needs 3 finite numbers",
        ),
        (
            format!("v 0 0 1e39\n{V}f 1 2 3\n"),
            "line 1: a vertex position needs 3 finite numbers",
        ),
        (
            format!("{V}vn 0 1\nf 1 2 3\n"),
            "line 4: a normal needs 3 finite numbers",
        ),
        (
            format!("{V}vt 0.5 inf\nf 1 2 3\n"),
            "line 4: a texture coordinate needs 1 finite numbers",
        ),
    ];
    for (text, why) in &cases {
        let e = load_file("t.obj", text.as_bytes()).expect_err(why);
        assert!(e.contains(why), "{why}: {e}");
    }
    let e = load_file("bytes.obj", b"v 0 0 0\n\xff\xfe\n").expect_err("not UTF-8");
    assert!(e.contains("not UTF-8"), "{e}");
    // The faces tobj reads after the check are the triangles of the file.
    let s = load_file(
        "ok.obj",
        format!("{V}v 1 1 0\nf 1 2 3 4\nf -4 -3 -2\n").as_bytes(),
    )
    .expect("valid OBJ");
    assert_eq!(s.triangle_count(), 3);
    for (mtl, why) in [
        (
            "newmtl m\nKd nan 0 0\n",
            "m.mtl line 2: Kd needs three finite numbers",
        ),
        (
            "newmtl m\nKd 0.5\n",
            "m.mtl line 2: Kd needs three finite numbers",
        ),
        (
            "newmtl m\nNs nan\n",
            "m.mtl line 2: Ns needs a finite number",
        ),
        ("newmtl m\nd\n", "m.mtl line 2: d needs a finite number"),
    ] {
        let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
            .join("hostile")
            .join("mtl");
        std::fs::create_dir_all(&dir).expect("folder");
        std::fs::write(dir.join("m.mtl"), mtl).expect("mtl");
        let obj = dir.join("m.obj");
        std::fs::write(&obj, format!("mtllib m.mtl\n{V}usemtl m\nf 1 2 3\n")).expect("obj");
        let e = scene::Scene::load(&obj)
            .map(|_| ())
            .expect_err(why)
            .to_string();
        assert!(e.contains(why), "{why}: {e}");
    }
}

#[test]
fn ply_headers_that_would_panic_or_loop_are_errors() {
    let body = "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    let head = |elements: &str| format!("ply\nformat ascii 1.0\n{elements}end_header\n{body}");
    let vertex = "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n";
    let face = "element face 1\nproperty list uchar int vertex_indices\n";
    let s = load_file("ok.ply", head(&format!("{vertex}{face}")).as_bytes()).expect("valid PLY");
    assert_eq!(s.triangle_count(), 1);
    for (text, why) in [
        (
            head(&format!("{vertex}element face 99999999999999999999999\n")),
            "line 7: a number too large",
        ),
        (
            "ply\nformat ascii 99999999999999999999.0\nend_header\n".to_string(),
            "line 2: a number too large",
        ),
        (
            head(&format!(
                "{vertex}{face}element nothing 18446744073709551615\n"
            )),
            "is not a number of at most",
        ),
        (
            head(&format!("{vertex}{face}element nothing 3\n")),
            "line 9: 3 elements without properties",
        ),
        (
            head(&format!(
                "{vertex}element face 1000\nproperty list uchar int vertex_indices\n"
            )),
            "count \"1000\"",
        ),
        (
            "ply\nformat ascii 1.0\nelement vertex 3\n".to_string(),
            "no end_header",
        ),
        (
            head(&format!("{vertex}{face}")).replace("3 0 1 2", "2 0 1"),
            "at least three vertices, got 2",
        ),
    ] {
        let e = load_file("bad.ply", text.as_bytes()).expect_err(why);
        assert!(e.contains(why), "{why}: {e}");
    }
}

#[cfg(unix)]
#[test]
fn a_scene_file_that_is_not_a_regular_file_is_refused() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("hostile")
        .join("device");
    std::fs::create_dir_all(&dir).expect("folder");
    let link = dir.join("zero.obj");
    let _ = std::fs::remove_file(&link);
    std::os::unix::fs::symlink("/dev/zero", &link).expect("link");
    let e = scene::Scene::load(&link)
        .map(|_| ())
        .expect_err("/dev/zero read as a scene");
    assert!(e.to_string().contains("not a regular file"), "{e}");
}

#[test]
fn scenes_too_large_or_without_extent_are_errors() {
    for (text, why) in [
        (
            "v 1e30 0 0\nv 0 1e30 0\nv 0 0 1e30\nf 1 2 3\n",
            "coordinates reach 1e30, beyond the ±1e15",
        ),
        (
            "v 1 1 1\nv 1 1 1\nv 1 1 1\nf 1 2 3\n",
            "every vertex is at [1, 1, 1]",
        ),
    ] {
        let e = load_file("extent.obj", text.as_bytes()).expect_err(why);
        assert!(e.contains(why), "{why}: {e}");
    }
}

/// A material built in code with a transmission outside [0, 1] or an index of refraction
/// below 1 (or not finite) is refused, naming the value.
#[test]
fn impossible_transmission_and_ior_are_errors() {
    let glass = |transmission, ior| scene::Material {
        name: "glass".into(),
        transmission,
        ior,
        ..Default::default()
    };
    assert!(glass(1.0, 1.5).validate().is_ok());
    for (m, what) in [
        (glass(1.5, 1.5), "transmission 1.5"),
        (glass(-0.1, 1.5), "transmission -0.1"),
        (glass(0.5, 0.5), "refraction 0.5"),
        (glass(0.5, f32::NAN), "refraction NaN"),
    ] {
        let e = m.validate().expect_err(what).to_string();
        assert!(e.contains(what), "{e}");
    }
}
