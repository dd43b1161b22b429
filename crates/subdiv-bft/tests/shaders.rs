//! Every WGSL file of this crate validates with naga; no GPU.

#[test]
fn every_shader_validates() {
    gpu::shader::assert_valid(
        &subdiv_bft::SHADERS,
        env!("CARGO_MANIFEST_DIR"),
        &subdiv_bft::gpu::shader_variants(),
    );
}
