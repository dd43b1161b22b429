//! `deferred --frames N`: an animated scene rendered as a sequence on the GPU (skinning in the
//! frame) and on the CPU (the skinning's twin) gives the same frames; the frames move; the
//! timings table and trace hold one frame per row / every pass.

use std::path::{Path, PathBuf};

mod common;

fn out_folder(name: &str) -> PathBuf {
    common::out_folder("cli-sequence", name)
}

fn sequence(out: &Path, extra: &[&str]) {
    let cesium = scene::shared_fixtures()
        .expect("the tests need ../shared/fixtures")
        .join("animated/CesiumMan/CesiumMan.glb");
    let cesium = cesium.to_string_lossy().into_owned();
    let mut args = vec![
        "--scene", &cesium, "--size", "96x72", "--frames", "4", "--fps", "6",
    ];
    args.extend(["--orbit", "20"]);
    args.extend(extra);
    let run = common::deferred(&args, out);
    assert!(
        run.status.success(),
        "{extra:?}: {}",
        String::from_utf8_lossy(&run.stderr)
    );
}

fn frame(out: &Path, k: u32) -> Vec<f32> {
    let png = out.join(format!("frames/frame-{k:05}.png"));
    let img = image::open(&png)
        .unwrap_or_else(|e| panic!("{}: {e}", png.display()))
        .to_rgb8();
    img.as_raw().iter().map(|&c| f32::from(c) / 255.0).collect()
}

fn mean_abs(a: &[f32], b: &[f32]) -> f32 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).sum::<f32>() / a.len() as f32
}

#[test]
fn an_animated_sequence_renders_alike_on_the_gpu_and_the_cpu() {
    let cpu = out_folder("cpu");
    sequence(&cpu, &["--cpu"]);
    let csv = std::fs::read_to_string(cpu.join("timings.csv")).expect("timings.csv");
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines.len(), 5, "a header and one row per frame:\n{csv}");
    assert!(
        lines[0].starts_with("frame,time_s,") && lines[0].ends_with(",total"),
        "{csv}"
    );
    assert!(
        lines[2].starts_with("1,0.166667,"),
        "frame 1 at 1/6 s:\n{csv}"
    );
    let svg = std::fs::read_to_string(cpu.join("timings.svg")).expect("timings.svg");
    assert!(
        svg.starts_with("<svg") && svg.contains("gbuffer"),
        "the plot names the passes"
    );
    let gif = image::codecs::gif::GifDecoder::new(std::io::BufReader::new(
        std::fs::File::open(cpu.join("preview.gif")).expect("preview.gif"),
    ))
    .expect("a GIF");
    let frames = image::AnimationDecoder::into_frames(gif)
        .collect_frames()
        .expect("its frames");
    assert_eq!(frames.len(), 4, "one preview frame per frame");
    // Things move: a frozen sequence would give equal frames.
    let (f0, f2) = (frame(&cpu, 0), frame(&cpu, 2));
    assert!(
        mean_abs(&f0, &f2) > 2e-3,
        "frames 0 and 2 are alike: nothing moves"
    );
    if gpu::test_device(&pipeline::device_needs()).is_none() {
        return;
    }
    let gpu = out_folder("gpu");
    sequence(&gpu, &[]);
    let trace: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(gpu.join("trace.json")).expect("trace"))
            .expect("the trace is JSON");
    let events = trace["traceEvents"].as_array().expect("events");
    for k in 0..4 {
        assert!(
            events
                .iter()
                .any(|e| e["name"] == "skinning" && e["args"]["frame"] == k),
            "frame {k} has a skinning pass in the trace"
        );
        let d = mean_abs(&frame(&gpu, k), &frame(&cpu, k));
        assert!(
            d < 2.0 / 255.0,
            "frame {k}: GPU and CPU differ by {d} on average"
        );
    }
}

/// `--subdiv` on an animated scene subdivides the moving meshes every frame from their posed
/// control meshes, uniformly or adaptively for the frame's camera (`--subdiv-pixels`): on the
/// GPU (skinning, then subdivision in the frame) as on the CPU (the rig's and the
/// subdivision's twins), and the frames move.
#[test]
fn a_subdivided_animated_sequence_renders_alike_on_the_gpu_and_the_cpu() {
    let plain = out_folder("subdiv-none");
    sequence(&plain, &["--cpu"]);
    for (name, subdiv, pass) in [
        ("uniform", &["--subdiv", "2"][..], "main step: evaluate"),
        (
            "adaptive",
            &["--subdiv", "3", "--subdiv-pixels", "1"][..],
            "main step: evaluate adaptive",
        ),
    ] {
        let cpu = out_folder(&format!("subdiv-{name}-cpu"));
        sequence(&cpu, &[&["--cpu"], subdiv].concat());
        let (f0, f2) = (frame(&cpu, 0), frame(&cpu, 2));
        assert!(
            mean_abs(&f0, &f2) > 2e-3,
            "{name}: frames 0 and 2 are alike"
        );
        // Subdivided, the character differs from its control mesh.
        let d = mean_abs(&frame(&plain, 1), &frame(&cpu, 1));
        assert!(d > 1e-4, "{name}: subdivision changes nothing: {d}");
        if gpu::test_device(&pipeline::device_needs()).is_none() {
            continue;
        }
        let gpu = out_folder(&format!("subdiv-{name}-gpu"));
        sequence(&gpu, subdiv);
        let csv = std::fs::read_to_string(gpu.join("timings.csv")).expect("timings.csv");
        assert!(
            csv.lines().next().is_some_and(|h| h.contains(pass)),
            "{name}: the subdivision is a pass of every frame:\n{csv}"
        );
        for k in 0..4 {
            let d = mean_abs(&frame(&gpu, k), &frame(&cpu, k));
            assert!(
                d < 2.0 / 255.0,
                "{name}: frame {k}: GPU and CPU differ by {d} on average"
            );
        }
    }
}
