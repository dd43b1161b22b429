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

/// The visibility buffer's narrow variants (`Atomics::Narrow`, for devices without 64-bit
/// atomics) declare no 64-bit type or literal, so they build where `SHADER_INT64` is missing.
#[test]
fn the_narrow_visibility_variants_use_no_64_bit_integer() {
    let narrow = gbuffer::gpu::visibility::shader_variants()
        .into_iter()
        .filter(|(_, s)| s.to_string().contains("WIDE_ATOMICS=false"));
    let mut checked = 0;
    for (file, specialisation) in narrow {
        let source = gbuffer::SHADERS
            .specialised(file, &specialisation)
            .expect("source");
        for (n, line) in source.lines().enumerate() {
            let code = line.split("//").next().unwrap_or_default();
            let wide = code
                .split(|c: char| !c.is_ascii_alphanumeric() && c != '_')
                .any(|token| {
                    matches!(token, "i64" | "u64")
                        || (token.ends_with("li") || token.ends_with("lu"))
                            && token.starts_with(|c: char| c.is_ascii_digit())
                });
            assert!(!wide, "{file} {specialisation}, line {}: {line}", n + 1);
        }
        checked += 1;
    }
    assert_eq!(checked, 4, "two files, two passes each");
}
