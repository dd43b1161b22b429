//! Writes the pictures of docs/interleave.md with the CPU reference (runs anywhere):
//! a split normal buffer (Segovia 2006 Figure 3b), a discontinuity buffer (Figure 3e) and
//! interleaved irradiance before and after the edge-aware blur (Figures 3d, 3f).
//!
//! `cargo run --release -p interleave --example pictures -- [OUT_DIR]` (default docs/images).

use std::path::PathBuf;

use gbuffer::{Image, normal::unpack_octahedral};
use glam::Vec3;
use interleave::{Blur, BlurVariant, Pattern, SplitLayout, SplitVariant, Thresholds, cpu};

fn main() -> anyhow::Result<()> {
    let out = PathBuf::from(std::env::args().nth(1).unwrap_or_else(|| "docs/images".into()));
    std::fs::create_dir_all(&out)?;
    let (w, h) = (640, 480);
    let scene = scene::spheres_on_plane(12);
    let gb = gbuffer::cpu::rasterize(&scene, &scene.camera_or_framed(), w, h)?.gbuffer;
    let pattern = Pattern::new(4, 4)?;
    let layout = SplitLayout::new(w, h, pattern)?;

    // Figure 3b: the normal buffer split into 4×4 sub-buffers.
    let colour = |word: u32, depth: f32| {
        if depth == 0.0 {
            [0.0; 4]
        } else {
            let n = unpack_octahedral(word) * 0.5 + Vec3::splat(0.5);
            [n.x, n.y, n.z, 1.0]
        }
    };
    let normals: Image<[f32; 4]> = Image::from_vec(
        w,
        h,
        gb.normal
            .pixels()
            .iter()
            .zip(gb.linear_depth.pixels())
            .map(|(&n, &d)| colour(n, d))
            .collect(),
    )?;
    normals.write_png(&out.join("interleave-normals.png"))?;
    cpu::split(&normals, &layout, SplitVariant::Tiled)?
        .write_png(&out.join("interleave-split-normals.png"))?;

    // Figure 3e: the discontinuity buffer (red: normals, green: depth).
    let disc = cpu::discontinuity(&gb.linear_depth, &gb.normal, &Thresholds::default())?;
    disc.map(|p| [f32::from(p[0]) / 255.0, f32::from(p[1]) / 255.0, 0.0, 1.0])
        .write_png(&out.join("interleave-discontinuities.png"))?;

    // Figures 3c–f: 256 directional lights from the upper hemisphere, dealt in turn to the 16
    // sub-buffers (16 each); gathered irradiance before and after a 7×7 fast blur.
    let count = 256;
    let lights: Vec<cpu::SubsetLight> = (0..count)
        .map(|k| {
            // Golden-angle spiral over the hemisphere; subset s = k / 16 takes every 16th
            // point of it (s, s + 16, ...), a representative sample of the whole sky.
            let l = (k % 16) * 16 + k / 16;
            let z = 1.0 - (l as f32 + 0.5) / count as f32;
            let (r, a) = ((1.0 - z * z).sqrt(), l as f32 * 2.399_963);
            let warm = [1.0, 0.85, 0.7];
            let c = if a.cos() > 0.3 { warm } else { [0.5, 0.6, 1.0] };
            cpu::SubsetLight {
                direction: [r * a.cos(), z, r * a.sin(), 0.0],
                color: [c[0] * 0.12, c[1] * 0.12, c[2] * 0.12, 0.0],
            }
        })
        .collect();
    let irradiance = cpu::shade_subsets(&gb.linear_depth, &gb.normal, &lights, &layout)?;
    irradiance.write_png(&out.join("interleave-irradiance.png"))?;
    let blurred = cpu::blur(&irradiance, &disc, &Blur::new(7, BlurVariant::Fast)?)?;
    blurred.write_png(&out.join("interleave-irradiance-blurred.png"))?;
    println!("wrote the pictures to {}", out.display());
    Ok(())
}
