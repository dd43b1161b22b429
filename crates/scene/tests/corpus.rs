//! A deterministic hostile corpus: small valid scenes in every format (glTF with a data URI,
//! glTF + .bin, GLB, OBJ + MTL, ASCII and binary PLY) truncated at many lengths and mutated
//! by seeded byte flips, loaded in process. Every case must end in a scene or an error within a
//! bounded time — never a panic (which fails this test) or a hang. `HOSTILE_FULL=1` runs 20×
//! more mutants.

mod common;

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// xorshift64*: the corpus is the same on every run and machine.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

fn triangle_bytes() -> Vec<u8> {
    let mut b: Vec<u8> = [0f32, 0., 0., 1., 0., 0., 0., 1., 0.]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    b.extend([0u16, 1, 2].iter().flat_map(|i| i.to_le_bytes()));
    b.extend([0, 0]);
    b
}

fn gltf_json(uri: Option<&str>) -> String {
    let uri = uri.map_or(String::new(), |u| format!(r#","uri":"{u}""#));
    format!(
        r#"{{"asset":{{"version":"2.0"}},"buffers":[{{"byteLength":44{uri}}}],
"bufferViews":[{{"buffer":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":6}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
{{"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}}],
"materials":[{{"pbrMetallicRoughness":{{"baseColorFactor":[1,0.5,0.2,1]}}}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1,"material":0}}]}}],
"nodes":[{{"mesh":0,"translation":[0,0,-2]}},{{"children":[0]}}],"scenes":[{{"nodes":[1]}}],"scene":0}}"#
    )
}

fn glb() -> Vec<u8> {
    let mut json = gltf_json(None).into_bytes();
    json.resize(json.len().div_ceil(4) * 4, b' ');
    let bin = triangle_bytes();
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut b = Vec::new();
    b.extend(b"glTF");
    b.extend(2u32.to_le_bytes());
    b.extend((total as u32).to_le_bytes());
    b.extend((json.len() as u32).to_le_bytes());
    b.extend(b"JSON");
    b.extend(&json);
    b.extend((bin.len() as u32).to_le_bytes());
    b.extend(b"BIN\0");
    b.extend(&bin);
    b
}

fn ply_binary() -> Vec<u8> {
    let mut b = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n\
property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\n\
end_header\n"
        .to_vec();
    b.extend(triangle_bytes()[..36].iter());
    b.push(3);
    b.extend([0i32, 1, 2].iter().flat_map(|i| i.to_le_bytes()));
    b
}

/// (file name, bytes, companion files written beside it unmutated).
fn sources() -> Vec<(&'static str, Vec<u8>, Vec<(&'static str, Vec<u8>)>)> {
    let data = format!(
        "data:application/octet-stream;base64,{}",
        common::base64(&triangle_bytes())
    );
    vec![
        ("data.gltf", gltf_json(Some(&data)).into_bytes(), vec![]),
        (
            "split.gltf",
            gltf_json(Some("tri.bin")).into_bytes(),
            vec![("tri.bin", triangle_bytes())],
        ),
        ("binary.glb", glb(), vec![]),
        (
            "tri.obj",
            b"mtllib m.mtl\no tri\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\n\
usemtl red\nf 1/1/1 2/2/1 3/3/1\n"
                .to_vec(),
            vec![("m.mtl", b"newmtl red\nKd 1 0 0\nNs 20\nd 1\n".to_vec())],
        ),
        (
            "m.mtl",
            b"newmtl red\nKd 1 0 0\nKs 0.5 0.5 0.5\nNs 20\nd 1\n".to_vec(),
            vec![(
                "tri.obj",
                b"mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n".to_vec(),
            )],
        ),
        (
            "ascii.ply",
            b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"
                .to_vec(),
            vec![],
        ),
        ("binary.ply", ply_binary(), vec![]),
        // Animated: a skin with an animation (glTF text), morph targets (GLB).
        (
            "skin.gltf",
            animated("SimpleSkin/glTF-Embedded/SimpleSkin.gltf"),
            vec![],
        ),
        (
            "morph.glb",
            animated("AnimatedMorphCube/AnimatedMorphCube.glb"),
            vec![],
        ),
    ]
}

/// The bytes of an animated fixture of `../shared/fixtures/animated`.
fn animated(path: &str) -> Vec<u8> {
    let file = scene::shared_fixtures()
        .expect("the tests need ../shared/fixtures")
        .join("animated")
        .join(path);
    std::fs::read(&file).unwrap_or_else(|e| panic!("{}: {e}", file.display()))
}

/// One mutant of `bytes`: a bit flip, a random byte, a run of digits (huge numbers), a
/// deleted or a duplicated span.
fn mutate(bytes: &[u8], rng: &mut Rng) -> Vec<u8> {
    let mut b = bytes.to_vec();
    for _ in 0..1 + rng.below(3) {
        let i = rng.below(b.len());
        match rng.below(5) {
            0 => b[i] ^= 1 << rng.below(8),
            1 => b[i] = rng.next() as u8,
            2 => {
                let digits: Vec<u8> = (0..1 + rng.below(24))
                    .map(|_| b'0' + rng.below(10) as u8)
                    .collect();
                b.splice(i..i, digits);
            }
            3 => {
                let end = (i + 1 + rng.below(16)).min(b.len());
                b.drain(i..end);
            }
            _ => {
                let end = (i + 1 + rng.below(16)).min(b.len());
                let span = b[i..end].to_vec();
                b.splice(i..i, span);
            }
        }
        if b.is_empty() {
            b.push(b'\n');
        }
    }
    b
}

/// The mutated and truncated cases of `source`, `mutants` seeded mutants plus up to 48
/// truncation lengths spread over the file.
fn cases(bytes: &[u8], mutants: usize, seed: u64) -> Vec<Vec<u8>> {
    let mut rng = Rng(seed | 1);
    let lengths = (0..48).map(|k| k * bytes.len() / 48);
    lengths
        .map(|n| bytes[..n].to_vec())
        .chain((0..mutants).map(|_| mutate(bytes, &mut rng)))
        .collect()
}

fn folder(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("corpus")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("folder");
    dir
}

#[test]
fn mutated_and_truncated_scenes_load_or_fail_cleanly() {
    let mutants = if std::env::var_os("HOSTILE_FULL").is_some() {
        4000
    } else {
        200
    };
    let (mut loaded, mut refused) = (0, 0);
    for (i, (name, bytes, companions)) in sources().into_iter().enumerate() {
        let dir = folder(name);
        for (file, data) in &companions {
            std::fs::write(dir.join(file), data).expect("companion");
        }
        // The MTL is mutated under its OBJ: the scene to load is the OBJ beside it.
        let target = if name.ends_with(".mtl") {
            "tri.obj"
        } else {
            name
        };
        std::fs::write(dir.join(name), &bytes).expect("source");
        scene::Scene::load(dir.join(target))
            .unwrap_or_else(|e| panic!("the unmutated {name} must load: {e}"));
        for (k, case) in cases(&bytes, mutants, 0x5eed + i as u64)
            .into_iter()
            .enumerate()
        {
            std::fs::write(dir.join(name), &case).expect("case");
            let start = Instant::now();
            match scene::Scene::load(dir.join(target)) {
                Ok(s) => {
                    loaded += 1;
                    // Whatever loads holds only finite positions and indices in range.
                    for m in &s.meshes {
                        assert!(m.positions.iter().all(|p| p.is_finite()), "{name} case {k}");
                        assert!(m.indices.iter().all(|&i| (i as usize) < m.positions.len()));
                    }
                    // What moves can be posed at any time of any clip without a panic.
                    if let Some(rig) = &s.rig {
                        for clip in (0..rig.clips.len()).map(Some).chain([None]) {
                            for t in [0.0, 0.37, 1e6] {
                                let pose = rig.pose(clip, t);
                                for d in &rig.deformers {
                                    assert_eq!(
                                        rig.deform(d, &pose).positions.len(),
                                        d.positions.len()
                                    );
                                }
                            }
                        }
                    }
                }
                Err(e) => {
                    refused += 1;
                    assert!(
                        !e.to_string().is_empty(),
                        "{name} case {k}: an empty message"
                    );
                }
            }
            assert!(
                start.elapsed() < Duration::from_secs(5),
                "{name} case {k} took {:?}",
                start.elapsed()
            );
        }
    }
    println!("corpus: {loaded} cases loaded, {refused} refused with an error, 0 panics");
    assert!(
        refused > loaded,
        "the corpus should be mostly invalid: {loaded} loaded, {refused} refused"
    );
}
