//! Helpers shared by the integration tests.

/// Writes expected, actual and 10× difference PNGs under `target/test-output/<name>` and
/// returns the folder.
pub fn write_failure(
    name: &str,
    expected: &gbuffer::Image<[f32; 4]>,
    actual: &gbuffer::Image<[f32; 4]>,
) -> String {
    let dir = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../target/test-output")
        .join(name);
    let _ = std::fs::create_dir_all(&dir);
    let diff = gbuffer::Image::from_vec(
        expected.width(),
        expected.height(),
        expected
            .pixels()
            .iter()
            .zip(actual.pixels())
            .map(|(a, b)| [0, 1, 2, 3].map(|c| ((a[c] - b[c]).abs() * 10.0).min(1.0)))
            .collect(),
    )
    .expect("same size");
    let _ = expected.write_png(&dir.join("expected.png"));
    let _ = actual.write_png(&dir.join("actual.png"));
    let _ = diff.write_png(&dir.join("difference.png"));
    dir.display().to_string()
}
