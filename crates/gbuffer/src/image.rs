//! `Image<T>`: the one CPU image type of the workspace (row-major, origin top-left).

use std::path::Path;

/// A `width × height` image, row-major from the top-left pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct Image<T> {
    width: u32,
    height: u32,
    data: Vec<T>,
}

/// Errors converting or writing images.
#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    /// Data length does not match the size.
    #[error("image of {width}×{height} needs {expected} pixels, got {got}")]
    Size {
        /// Width.
        width: u32,
        /// Height.
        height: u32,
        /// Pixels needed.
        expected: usize,
        /// Pixels given.
        got: usize,
    },
    /// PNG encoding or file error.
    #[error("{path}: {message}")]
    Write {
        /// File.
        path: String,
        /// Problem.
        message: String,
    },
}

impl<T: Copy> Image<T> {
    /// An image with every pixel set to `value`.
    pub fn filled(width: u32, height: u32, value: T) -> Self {
        Self {
            width,
            height,
            data: vec![value; width as usize * height as usize],
        }
    }

    /// Wraps row-major pixels; fails if the length is not `width × height`.
    pub fn from_vec(width: u32, height: u32, data: Vec<T>) -> Result<Self, ImageError> {
        let expected = width as usize * height as usize;
        if data.len() != expected {
            return Err(ImageError::Size {
                width,
                height,
                expected,
                got: data.len(),
            });
        }
        Ok(Self {
            width,
            height,
            data,
        })
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The pixel at (x, y). Panics when out of bounds, like slice indexing.
    pub fn get(&self, x: u32, y: u32) -> T {
        self.data[y as usize * self.width as usize + x as usize]
    }

    /// Sets the pixel at (x, y).
    pub fn set(&mut self, x: u32, y: u32, value: T) {
        self.data[y as usize * self.width as usize + x as usize] = value;
    }

    /// All pixels, row-major.
    pub fn pixels(&self) -> &[T] {
        &self.data
    }

    /// All pixels, mutable.
    pub fn pixels_mut(&mut self) -> &mut [T] {
        &mut self.data
    }

    /// Applies `f` to every pixel.
    pub fn map<U: Copy>(&self, f: impl Fn(T) -> U) -> Image<U> {
        Image {
            width: self.width,
            height: self.height,
            data: self.data.iter().map(|&p| f(p)).collect(),
        }
    }
}

pub use scene::{linear_to_srgb, srgb_to_linear};

impl Image<[f32; 4]> {
    /// Linear RGB as 8-bit sRGB, three bytes a pixel (clamped to \[0, 1\]; alpha dropped).
    pub fn to_srgb8(&self) -> Vec<u8> {
        self.data
            .iter()
            .flat_map(|p| [p[0], p[1], p[2]].map(|c| (linear_to_srgb(c) * 255.0).round() as u8))
            .collect()
    }

    /// Writes linear RGB as an 8-bit sRGB PNG ([`Image::to_srgb8`]).
    pub fn write_png(&self, path: &Path) -> Result<(), ImageError> {
        let bytes = self.to_srgb8();
        write_atomically(path, |tmp| {
            image::save_buffer_with_format(
                tmp,
                &bytes,
                self.width,
                self.height,
                image::ExtendedColorType::Rgb8,
                image::ImageFormat::Png,
            )
            .map_err(|e| e.to_string())
        })
    }

    /// Writes `expected.png` (`self`), `actual.png` and `difference.png` (10× the absolute
    /// difference, RGBA) into `dir`, creating it: what a failed image comparison leaves to
    /// look at. Returns `dir` as text for the failure message; a failed write says why there.
    pub fn write_comparison(&self, actual: &Self, dir: &Path) -> String {
        let diff = self
            .data
            .iter()
            .zip(&actual.data)
            .map(|(a, b)| [0, 1, 2, 3].map(|c| ((a[c] - b[c]).abs() * 10.0).min(1.0)))
            .collect();
        let write = || -> Result<(), String> {
            std::fs::create_dir_all(dir).map_err(|e| e.to_string())?;
            let diff = Image::from_vec(self.width, self.height, diff).map_err(|e| e.to_string())?;
            for (file, image) in [
                ("expected", self),
                ("actual", actual),
                ("difference", &diff),
            ] {
                image
                    .write_png(&dir.join(format!("{file}.png")))
                    .map_err(|e| e.to_string())?;
            }
            Ok(())
        };
        match write() {
            Ok(()) => dir.display().to_string(),
            Err(e) => format!("{} (not written: {e})", dir.display()),
        }
    }

    /// Writes linear RGBA as a 32-bit float OpenEXR file.
    pub fn write_exr(&self, path: &Path) -> Result<(), ImageError> {
        let w = self.width as usize;
        write_atomically(path, |tmp| {
            exr::prelude::write_rgba_file(tmp, w, self.height as usize, |x, y| {
                let p = self.data[y * w + x];
                (p[0], p[1], p[2], p[3])
            })
            .map_err(|e| e.to_string())
        })
    }
}

/// Writes `path` atomically: `write` fills a temporary file beside it, which then replaces
/// `path` by a rename — a reader never sees a half-written file, a failed write leaves the old
/// file (or none) and no temporary behind, and a symbolic link at `path` is replaced, not
/// followed. Errors name `path`.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), String>,
) -> Result<(), ImageError> {
    let fail = |message: String| ImageError::Write {
        path: path.display().to_string(),
        message,
    };
    let name = path
        .file_name()
        .ok_or_else(|| fail("not a file path".into()))?
        .to_string_lossy();
    let tmp = path.with_file_name(format!(".{name}.{}.tmp", std::process::id()));
    // A leftover (or planted) temporary is replaced, never written through.
    let _ = std::fs::remove_file(&tmp);
    let written = write(&tmp).and_then(|()| std::fs::rename(&tmp, path).map_err(|e| e.to_string()));
    if let Err(message) = written {
        let _ = std::fs::remove_file(&tmp);
        return Err(fail(message));
    }
    Ok(())
}

/// Peak signal-to-noise ratio in dB between two images' RGB, after clamping to \[0, 1\] and
/// the sRGB transfer function (what a PNG shows). Infinite for identical images.
pub fn psnr(a: &Image<[f32; 4]>, b: &Image<[f32; 4]>) -> f64 {
    let to = |c: f32| f64::from(linear_to_srgb(c));
    let mse = a
        .pixels()
        .iter()
        .zip(b.pixels())
        .map(|(p, q)| (0..3).map(|c| (to(p[c]) - to(q[c])).powi(2)).sum::<f64>())
        .sum::<f64>()
        / (a.pixels().len() * 3).max(1) as f64;
    if mse == 0.0 {
        f64::INFINITY
    } else {
        -10.0 * mse.log10()
    }
}

/// How far an image is from a ground truth (issue 21's measure): over the pixels the truth
/// lights, emitters and the pixels around them excluded.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Accuracy {
    /// Relative mean absolute luminance error: `Σ|L − L*| / Σ L*`.
    pub error: f64,
    /// Mean luminance ratio − 1 (positive: too bright).
    pub bias: f64,
    /// Relative RMS luminance error: `√(Σ(L − L*)² / n) / (Σ L* / n)` (Segovia 2006 §6.3's
    /// convergence measure).
    pub rms: f64,
    /// Pixels compared.
    pub pixels: usize,
}

/// [`Accuracy`] of `image` against `truth` (same size; linear RGB, Rec. 709 luminance),
/// ignoring pixels where the truth is black, and emitters: pixels brighter than
/// `emitter_luminance` in either image and their 8 neighbours (a path tracer averages an
/// emitter's edge over the pixel, a rasteriser takes one sample: at small sizes those edge
/// pixels would dominate the error). A non-finite pixel of `image` counts as black.
pub fn accuracy(
    truth: &Image<[f32; 4]>,
    image: &Image<[f32; 4]>,
    emitter_luminance: f32,
) -> Accuracy {
    let lum = |p: &[f32; 4]| f64::from(0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]);
    let (w, h) = (truth.width() as i64, truth.height() as i64);
    let bright = |x: i64, y: i64| {
        (0..w).contains(&x)
            && (0..h).contains(&y)
            && [truth, image]
                .iter()
                .any(|i| lum(&i.get(x as u32, y as u32)) > f64::from(emitter_luminance))
    };
    let near_emitter =
        |x: i64, y: i64| (-1..=1).any(|dy| (-1..=1).any(|dx| bright(x + dx, y + dy)));
    let (mut diff, mut squared, mut sum_truth, mut sum_image, mut pixels) = (0.0, 0.0, 0.0, 0.0, 0);
    for (i, (t, x)) in truth.pixels().iter().zip(image.pixels()).enumerate() {
        let (lt, lx) = (lum(t), lum(x));
        let (px, py) = (i as i64 % w, i as i64 / w);
        if lt <= 0.0 || near_emitter(px, py) {
            continue;
        }
        // A non-finite pixel is wholly wrong, never skipped.
        let lx = if lx.is_finite() { lx } else { 0.0 };
        diff += (lx - lt).abs();
        squared += (lx - lt) * (lx - lt);
        sum_truth += lt;
        sum_image += lx;
        pixels += 1;
    }
    let total = sum_truth.max(f64::MIN_POSITIVE);
    Accuracy {
        error: diff / total,
        bias: sum_image / total - 1.0,
        rms: (squared * pixels as f64).sqrt() / total,
        pixels,
    }
}
