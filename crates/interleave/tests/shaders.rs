//! Every WGSL file and every specialised variant of this crate validates with naga; no GPU.

#[test]
fn every_shader_variant_validates() {
    gpu::shader::assert_valid(
        &interleave::SHADERS,
        env!("CARGO_MANIFEST_DIR"),
        &interleave::gpu::shader_variants(),
    );
}
