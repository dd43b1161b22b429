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
