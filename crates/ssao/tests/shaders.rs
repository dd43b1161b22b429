//! Every WGSL file of this crate validates with naga; no GPU.

#[test]
fn every_shader_validates() {
    let untiled = gpu::shader::Specialisation::default().set("TILE_CAPACITY", "1u");
    gpu::shader::assert_valid(
        &ssao::SHADERS,
        env!("CARGO_MANIFEST_DIR"),
        &[("estimators.wgsl", untiled)],
    );
}
