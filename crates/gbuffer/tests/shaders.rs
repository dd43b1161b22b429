//! Every WGSL file of this crate validates with naga, in every variant its kernels build; no
//! GPU.

#[test]
fn every_shader_validates() {
    gpu::shader::assert_valid(
        &gbuffer::SHADERS,
        env!("CARGO_MANIFEST_DIR"),
        &gbuffer::gpu::visibility::shader_variants(),
    );
}
