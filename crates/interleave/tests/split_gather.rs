//! Split and gather (Segovia 2006 §3): gather ∘ split = identity bit for bit, sub-buffer
//! contents checked independently of the crate's index arithmetic, CPU == GPU for every
//! variant and texel format.

use gbuffer::Image;
use gpu::wgpu::TextureFormat;
use interleave::{Block, InterleaveError, Pattern, SplitLayout, SplitVariant, cpu, gpu as igpu};
use proptest::prelude::*;

/// Sub-buffer (i, j) must hold exactly the pixels with x mod n = i, y mod m = j, in row order,
/// starting at its top-left texel and followed by zero padding. Computed from the definition
/// only (pixel values are their row-major index + 1, so zero is padding).
fn check_sub_buffers(width: u32, height: u32, pattern: Pattern, split: &Image<u32>) {
    let (n, m) = (pattern.n, pattern.m);
    let (sw, sh) = (split.width() / n, split.height() / m);
    assert_eq!((sw * n, sh * m), (split.width(), split.height()));
    for j in 0..m {
        for i in 0..n {
            let cols = (0..width).filter(|x| x % n == i).count() as u32;
            let rows = (0..height).filter(|y| y % m == j).count() as u32;
            let expected: Vec<u32> = (0..height)
                .filter(|y| y % m == j)
                .flat_map(|y| {
                    (0..width)
                        .filter(|x| x % n == i)
                        .map(move |x| y * width + x + 1)
                })
                .collect();
            let mut held = Vec::new();
            for v in 0..sh {
                for u in 0..sw {
                    let t = split.get(i * sw + u, j * sh + v);
                    if u < cols && v < rows {
                        held.push(t);
                    } else {
                        assert_eq!(t, 0, "padding texel ({u}, {v}) of sub-buffer ({i}, {j})");
                    }
                }
            }
            assert_eq!(held, expected, "sub-buffer ({i}, {j})");
        }
    }
}

fn numbered(width: u32, height: u32) -> Image<u32> {
    Image::from_vec(width, height, (1..=width * height).collect()).expect("size")
}

fn variants(pattern: Pattern, a: u32, b: u32) -> Vec<SplitVariant> {
    let mut v = vec![
        SplitVariant::OnePass,
        SplitVariant::TwoPass(Block {
            p: a * pattern.n,
            q: b * pattern.m,
        }),
    ];
    if pattern.count() <= interleave::TILE_TEXELS {
        v.push(SplitVariant::Tiled);
    }
    v
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn cpu_split_is_the_definition_and_gather_inverts_it(
        width in 1u32..90, height in 1u32..90, n in 1u32..10, m in 1u32..10, a in 1u32..9, b in 1u32..9,
    ) {
        let pattern = Pattern::new(n, m).expect("pattern");
        let layout = SplitLayout::new(width, height, pattern).expect("layout");
        let image = numbered(width, height);
        for variant in variants(pattern, a, b) {
            let split = cpu::split(&image, &layout, variant).expect("split");
            check_sub_buffers(width, height, pattern, &split);
            prop_assert_eq!(&cpu::gather(&split, &layout, variant).expect("gather"), &image, "{:?}", variant);
        }
    }
}

#[test]
fn paper_figure_2_two_pass_example() -> Result<(), InterleaveError> {
    // Figure 2: a 3×2 pattern, the image cut into 2×2 blocks; here 12×8 pixels, 6×4 blocks.
    let pattern = Pattern::new(3, 2)?;
    let layout = SplitLayout::new(12, 8, pattern)?;
    let image = numbered(12, 8);
    let block = Block { p: 6, q: 4 };
    let geometry = cpu::BlockGeometry::new(&layout, block);
    let blocks = cpu::split_block_splitting(&image, &geometry);
    // Figure 2c: block (0, 0)'s sub-block (1, 0) holds pixels (1, 0), (4, 0), (1, 2), (4, 2).
    assert_eq!(
        [
            blocks.get(2, 0),
            blocks.get(3, 0),
            blocks.get(2, 1),
            blocks.get(3, 1)
        ],
        [2, 5, 26, 29]
    );
    let split = cpu::split_block_translation(&blocks, &geometry);
    assert_eq!(split, cpu::split_one_pass(&image, &layout));
    Ok(())
}

#[test]
fn bad_input_is_an_error() {
    assert!(Pattern::new(0, 4).is_err());
    assert!(SplitLayout::new(0, 4, Pattern { n: 2, m: 2 }).is_err());
    let layout = SplitLayout::new(8, 8, Pattern { n: 4, m: 2 }).expect("layout");
    let image = numbered(8, 8);
    let bad_block = SplitVariant::TwoPass(Block { p: 6, q: 4 });
    assert!(matches!(
        cpu::split(&image, &layout, bad_block),
        Err(InterleaveError::Block { .. })
    ));
    let wrong = numbered(7, 8);
    assert!(matches!(
        cpu::split(&wrong, &layout, SplitVariant::OnePass),
        Err(InterleaveError::Mismatch { .. })
    ));
    let big = SplitLayout::new(66, 64, Pattern { n: 33, m: 32 }).expect("layout");
    assert!(matches!(
        cpu::split(&numbered(66, 64), &big, SplitVariant::Tiled),
        Err(InterleaveError::TileTooSmall { .. })
    ));
    // One-pass and two-pass still handle it.
    let split = cpu::split(&numbered(66, 64), &big, SplitVariant::OnePass).expect("split");
    check_sub_buffers(66, 64, big.pattern, &split);
}

/// Random texels of one format, as raw bytes of `texel` bytes each. Float formats get values
/// that are not NaN (a float texel passes through the shader as a number).
fn texels(format: TextureFormat, count: usize, seed: u64) -> Vec<u8> {
    let mut state = seed | 1;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let texel = format.block_copy_size(None).expect("colour format") as usize;
    let mut out = Vec::with_capacity(count * texel);
    while out.len() < count * texel {
        match format {
            TextureFormat::R32Float | TextureFormat::Rg32Float | TextureFormat::Rgba32Float => {
                let v = f32::from_bits(next() as u32);
                let v = if v.is_nan() { 1.5 } else { v };
                out.extend_from_slice(&v.to_le_bytes());
            }
            TextureFormat::Rgba16Float => {
                let v = half::f16::from_bits(next() as u16);
                let v = if v.is_nan() { half::f16::ONE } else { v };
                out.extend_from_slice(&v.to_le_bytes());
            }
            _ => out.push(next() as u8),
        }
    }
    out
}

const FORMATS: [TextureFormat; 8] = [
    TextureFormat::R32Uint,
    TextureFormat::R32Float,
    TextureFormat::Rgba8Unorm,
    TextureFormat::Rgba8Sint,
    TextureFormat::Rgba16Float,
    TextureFormat::Rg32Uint,
    TextureFormat::Rgba32Uint,
    TextureFormat::Rgba32Float,
];

/// CPU and GPU split of `format` texels, compared as raw bytes; then the GPU gather.
fn gpu_round_trip<T: bytemuck::Pod + Default + Send + Sync + PartialEq + std::fmt::Debug>(
    gpu: &gpu::Gpu,
    format: TextureFormat,
    layout: &SplitLayout,
    variant: SplitVariant,
    seed: u64,
) {
    let bytes = texels(format, (layout.width * layout.height) as usize, seed);
    let image: Image<T> = Image::from_vec(
        layout.width,
        layout.height,
        bytemuck::pod_collect_to_vec(&bytes),
    )
    .expect("image");
    let expected = cpu::split(&image, layout, variant).expect("cpu split");
    let split = igpu::run_split(gpu, &image, format, layout, variant).expect("gpu split");
    assert!(
        split == expected,
        "{format:?} {variant:?} {layout:?}: GPU split differs from CPU"
    );
    let back = igpu::run_gather(gpu, &split, format, layout, variant).expect("gpu gather");
    assert!(
        back == image,
        "{format:?} {variant:?} {layout:?}: GPU gather(split) is not the image"
    );
}

fn gpu_case(
    gpu: &gpu::Gpu,
    format: TextureFormat,
    layout: &SplitLayout,
    variant: SplitVariant,
    seed: u64,
) {
    match format.block_copy_size(None) {
        Some(4) => gpu_round_trip::<u32>(gpu, format, layout, variant, seed),
        Some(8) => gpu_round_trip::<[u32; 2]>(gpu, format, layout, variant, seed),
        Some(16) => gpu_round_trip::<[u32; 4]>(gpu, format, layout, variant, seed),
        other => panic!("unexpected texel size {other:?}"),
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(20))]

    #[test]
    fn gpu_split_equals_cpu_and_gather_inverts_it(
        width in 1u32..150, height in 1u32..150, n in 1u32..9, m in 1u32..9,
        a in 1u32..9, b in 1u32..9, format in 0usize..FORMATS.len(), seed in any::<u64>(),
    ) {
        let Some(gpu) = gpu::test_device(&interleave::device_needs()) else { return Ok(()) };
        let pattern = Pattern::new(n, m).expect("pattern");
        let layout = SplitLayout::new(width, height, pattern).expect("layout");
        for variant in variants(pattern, a, b) {
            gpu_case(gpu, FORMATS[format], &layout, variant, seed);
        }
    }
}

#[test]
fn gpu_every_format_and_the_paper_patterns() {
    let Some(gpu) = gpu::test_device(&interleave::device_needs()) else {
        return;
    };
    for (k, format) in FORMATS.into_iter().enumerate() {
        for (n, m) in [(2, 2), (4, 4), (8, 6), (8, 8)] {
            let layout = SplitLayout::new(67, 45, Pattern { n, m }).expect("layout");
            for variant in variants(layout.pattern, 2, 2) {
                gpu_case(gpu, format, &layout, variant, k as u64 * 977 + u64::from(n));
            }
        }
    }
}

#[test]
fn gpu_rejects_bad_formats_and_texel_sizes() {
    let Some(gpu) = gpu::test_device(&interleave::device_needs()) else {
        return;
    };
    let layout = SplitLayout::new(8, 8, Pattern { n: 2, m: 2 }).expect("layout");
    let image = numbered(8, 8);
    assert!(matches!(
        igpu::run_split(
            gpu,
            &image,
            TextureFormat::Depth32Float,
            &layout,
            SplitVariant::OnePass
        ),
        Err(InterleaveError::Format(_))
    ));
    assert!(matches!(
        igpu::run_split(
            gpu,
            &image,
            TextureFormat::Rgba32Uint,
            &layout,
            SplitVariant::OnePass
        ),
        Err(InterleaveError::TexelSize { .. })
    ));
}
