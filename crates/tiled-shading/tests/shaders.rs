//! Every WGSL file and every specialised variant of this crate validates with naga; no GPU.

#[test]
fn every_shader_variant_validates() {
    gpu::shader::assert_valid(
        &tiled_shading::SHADERS,
        env!("CARGO_MANIFEST_DIR"),
        &tiled_shading::gpu::shader_variants(),
    );
}
