//! Every WGSL file of this crate validates with naga, and the VPL shading in the
//! specialisation its kernel uses; no GPU.

#[test]
fn every_shader_validates() {
    gpu::shader::assert_valid(
        &instant_radiosity::SHADERS,
        env!("CARGO_MANIFEST_DIR"),
        &[("vpl_shading.wgsl", instant_radiosity::gpu::shading_rays())],
    );
}
