//! GPU skinning against its CPU twin (`Rig::deform`) on every animated fixture at several
//! times, and the shader's structs against their Rust mirrors.

use glam::{Vec3, Vec4};
use pipeline::skinning::{GpuDeformer, GpuSkinVertex, Skinning};

/// Byte size and member offsets of WGSL struct `name` in `skinning.wgsl`, as naga lays it out.
fn wgsl_layout(name: &str) -> (u32, Vec<u32>) {
    let source = pipeline::SHADERS.source("skinning.wgsl").expect("source");
    let module = naga::front::wgsl::parse_str(&source).expect("parses");
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).expect("layout");
    let (handle, ty) = module
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some(name))
        .expect("struct");
    let naga::TypeInner::Struct { members, .. } = &ty.inner else {
        panic!("{name} is not a struct")
    };
    (
        layouter[handle].size,
        members.iter().map(|m| m.offset).collect(),
    )
}

#[test]
fn shader_structs_match_their_rust_mirrors() {
    use std::mem::{offset_of, size_of};
    let (size, offsets) = wgsl_layout("SkinVertex");
    assert_eq!(size as usize, size_of::<GpuSkinVertex>());
    assert_eq!(
        offsets,
        [
            offset_of!(GpuSkinVertex, position),
            offset_of!(GpuSkinVertex, vertex),
            offset_of!(GpuSkinVertex, normal),
            offset_of!(GpuSkinVertex, deformer),
            offset_of!(GpuSkinVertex, tangent),
            offset_of!(GpuSkinVertex, joints),
            offset_of!(GpuSkinVertex, weights),
        ]
        .map(|o| o as u32)
    );
    let (size, _) = wgsl_layout("Deformer");
    assert_eq!(size as usize, size_of::<GpuDeformer>());
    assert_eq!(
        size_of::<gbuffer::gpu::GpuAttributes>(),
        4 * 15,
        "ATTRIBUTE_FLOATS of skinning.wgsl"
    );
}

#[test]
fn gpu_skinning_matches_the_cpu_twin() {
    let Some(gpu) = gpu::test_device(&pipeline::device_needs()) else {
        return;
    };
    let fixtures = scene::shared_fixtures().expect("the tests need ../shared/fixtures");
    let skinning = Skinning::new(&gpu.device).expect("pipeline");
    let pass = gbuffer::gpu::GBufferPass::new(&gpu.device).expect("G-buffer pass");
    for file in [
        "SimpleSkin/SimpleSkin.glb",
        "RiggedSimple/RiggedSimple.glb",
        "CesiumMan/CesiumMan.glb",
        "Fox/glTF/Fox.gltf",
        "BoxAnimated/BoxAnimated.glb",
        "AnimatedMorphCube/AnimatedMorphCube.glb",
    ] {
        let scene = scene::Scene::load(fixtures.join("animated").join(file)).expect(file);
        let rig = scene.rig.as_ref().expect("a rig");
        let uploaded =
            gbuffer::gpu::GpuScene::upload(&gpu.device, &gpu.queue, &scene, &pass).expect(file);
        let bound = skinning.bind(&gpu.device, rig, &uploaded).expect("binds");
        let scale = scene.bounds().diagonal();
        let clip = &rig.clips[rig.clips.len() - 1];
        for k in 0..4 {
            let t = clip.duration * (0.1 + 0.27 * k as f32);
            let pose = rig.pose(Some(rig.clips.len() - 1), t);
            bound.set_pose(&gpu.queue, rig, &pose);
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            bound.encode(&mut encoder, None);
            gpu.queue.submit([encoder.finish()]);
            let [positions, attributes] = uploaded.vertex_buffers();
            let p: Vec<[f32; 3]> =
                gpu::transfer::read_pod(&gpu.device, &gpu.queue, positions).expect("positions");
            let a: Vec<gbuffer::gpu::GpuAttributes> =
                gpu::transfer::read_pod(&gpu.device, &gpu.queue, attributes).expect("attributes");
            for d in &rig.deformers {
                let cpu = rig.deform(d, &pose);
                let base = uploaded.base_vertex(d.mesh as usize).expect("mesh") as usize;
                for v in 0..cpu.positions.len() {
                    let (gp, ga) = (Vec3::from(p[base + v]), &a[base + v]);
                    let what = format!("{file} t = {t:.3} s vertex {v}");
                    assert!(
                        gp.distance(cpu.positions[v]) <= 2e-6 * scale,
                        "{what}: position {gp} vs CPU {}",
                        cpu.positions[v]
                    );
                    let n = Vec3::from(ga.normal);
                    assert!(
                        n.dot(cpu.normals[v]) > 0.9999,
                        "{what}: normal {n} vs {}",
                        cpu.normals[v]
                    );
                    if let Some(t) = cpu.tangents.get(v) {
                        let g = Vec4::from(ga.tangent);
                        assert!(
                            g.truncate().dot(t.truncate()) > 0.9999 && g.w == t.w,
                            "{what}: tangent {g} vs {t}"
                        );
                    }
                }
            }
        }
    }
}
