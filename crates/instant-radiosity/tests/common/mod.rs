//! What the GPU-against-CPU-twin tests share.

/// Pixels whose RGB agree within f16 rounding (2⁻⁸ relative, 10⁻³ absolute near zero): a
/// receiver or ray exactly at an edge may go either way between two twins, so tests ask for
/// most pixels, not all.
pub fn agreeing_pixels(got: &[[f32; 4]], want: &[[f32; 4]]) -> usize {
    got.iter()
        .zip(want)
        .filter(|(a, b)| {
            (0..3).all(|k| (a[k] - b[k]).abs() <= 2f32.powi(-8) * b[k].abs().max(1e-3))
        })
        .count()
}
