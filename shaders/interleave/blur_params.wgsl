// The blur's uniform block (Segovia 2006 §4.5), shared by `blur.wgsl` and
// `discontinuity_blur.wgsl`.

struct BlurParams {
    // (1, 0) for the horizontal pass, (0, 1) for the vertical one.
    direction: vec2<i32>,
    radius: i32,
    _pad: i32,
    // Gaussian weights of taps 0..=radius (radius ≤ 8), four per vector.
    weights: array<vec4<f32>, 3>,
}
