//! The `deferred` program's outputs: written atomically, and a run that fails removes the
//! outputs it had already written (no half set of files is left that looks like a result).

use std::process::Command;

mod common;

fn out_folder(name: &str) -> std::path::PathBuf {
    let dir = common::out_folder("cli-outputs", name);
    std::fs::create_dir_all(&dir).expect("folder");
    dir
}

/// `deferred --cpu` at 64×48 with `extra`.
fn deferred(out: &std::path::Path, extra: &[&str]) -> std::process::Output {
    common::deferred(&[&["--cpu", "--size", "64x48"], extra].concat(), out)
}

/// `deferred` on the GPU at 96×72 with `extra`.
fn deferred_on_gpu(out: &std::path::Path, extra: &[&str]) -> std::process::Output {
    common::deferred(&[&["--size", "96x72"], extra].concat(), out)
}

#[test]
fn a_run_writes_its_outputs_and_nothing_else() {
    let out = out_folder("ok");
    let run = deferred(&out, &[]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let mut names: Vec<_> = std::fs::read_dir(&out)
        .expect("out")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["render.exr", "render.png"]);
    // Looking straight down (the default up is along the view): the program picks another up.
    let down = deferred(&out, &["--eye", "0,5,0", "--target", "0,0,0"]);
    assert!(
        down.status.success(),
        "{}",
        String::from_utf8_lossy(&down.stderr)
    );
    // The path-traced ground truth writes the same two files.
    let reference = deferred(&out, &["--reference", "4", "--max-bounces", "2"]);
    assert!(
        reference.status.success(),
        "{}",
        String::from_utf8_lossy(&reference.stderr)
    );
    assert!(String::from_utf8_lossy(&reference.stdout).contains("4 samples per pixel, 2 bounces"));
}

#[test]
fn a_failed_run_removes_the_outputs_it_wrote() {
    let out = out_folder("fail");
    // A folder where a later output goes: render.png and render.exr are written first, then
    // the stage dump fails.
    std::fs::create_dir_all(out.join("stages/gbuffer-depth.png")).expect("obstacle");
    let run = deferred(&out, &["--dump-stages"]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(!run.status.success(), "the run should fail");
    assert!(
        stderr.contains("gbuffer-depth.png"),
        "the error names the file: {stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
    for partial in ["render.png", "render.exr", "stages/gbuffer-normal.png"] {
        assert!(!out.join(partial).exists(), "{partial} was left behind");
    }
    // A sequence that fails after it made its folders leaves none of them: here its second
    // frame cannot be written.
    let fresh = common::out_folder("cli-outputs", "fail-sequence");
    let nested = fresh.join("deeper");
    std::fs::create_dir_all(nested.join("frames/frame-00001.png")).expect("obstacle");
    let run = common::deferred(&["--cpu", "--size", "16x12", "--frames", "3"], &nested);
    assert!(!run.status.success(), "the sequence should fail");
    assert!(
        !nested.join("frames/frame-00000.png").exists(),
        "frame 0 was left behind"
    );
    // Before any frame: a bad camera key is refused and the folders it would make are not.
    let never = fresh.join("never/made");
    let run = common::deferred(
        &["--cpu", "--frames", "2", "--camera-key", "1:0,0,0:0,0,0"],
        &never,
    );
    assert!(
        !run.status.success(),
        "a camera looking at its own eye is refused"
    );
    assert!(
        !fresh.join("never").exists(),
        "a refused run made its folders"
    );
}

/// VPL visibility for many VPLs renders on a device whose storage bindings are 128 MiB (the
/// software adapter in CI, and many GPUs): the views are batched to fit (the batched atlas is
/// the one batch's: `instant-radiosity/tests/shadow_batches.rs`).
#[test]
fn many_vpl_shadow_maps_render_within_the_device_limits() {
    // The shared test-device rule: skipped with a reason without an adapter, a failure in CI.
    if gpu::test_device(&pipeline::device_needs()).is_none() {
        return;
    }
    for (mode, vpls) in [("manylod", "1024"), ("ism", "4096"), ("ssm", "1024")] {
        let out = out_folder(&format!("vpl-shadows-{mode}"));
        let run = deferred_on_gpu(&out, &["--vpls", vpls, "--vpl-shadows", mode]);
        assert!(
            run.status.success(),
            "--vpl-shadows {mode} --vpls {vpls}: {}",
            String::from_utf8_lossy(&run.stderr)
        );
        assert!(out.join("render.png").is_file() && out.join("vpl-shadow-atlas.png").is_file());
    }
}

/// Exact visibility by rays — the direct lights' (`--ray-shadows`) and the VPLs'
/// (`--vpl-shadows rays`) — renders on the GPU (no atlas to write) and is refused on the CPU
/// with a clear line.
#[test]
fn exact_shadows_by_rays_render_on_the_gpu_and_are_refused_on_the_cpu() {
    let out = out_folder("rays-cpu");
    let run = deferred(&out, &["--ray-shadows"]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(
        !run.status.success() && stderr.contains("--ray-shadows"),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
    if gpu::test_device(&pipeline::device_needs()).is_none() {
        return;
    }
    let out = out_folder("rays");
    let run = deferred_on_gpu(
        &out,
        &["--vpls", "256", "--vpl-shadows", "rays", "--ray-shadows"],
    );
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(out.join("render.png").is_file() && !out.join("vpl-shadow-atlas.png").exists());
}

/// `--visibility` draws the G-buffer through the visibility buffer and says so;
/// `--visibility=auto` measures both paths, the visibility path per split between the
/// rasterisers, and names the one it kept with every time; both are
/// refused with `--cpu`.
#[test]
fn the_visibility_buffer_is_chosen_or_measured() {
    let out = out_folder("visibility-cpu");
    let run = deferred(&out, &["--visibility"]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(
        !run.status.success() && stderr.contains("--visibility"),
        "{stderr}"
    );
    let needs = pipeline::device_needs().and(&gbuffer::gpu::visibility::device_needs());
    let Some(gpu) = gpu::test_device(&needs) else {
        return;
    };
    let out = out_folder("visibility");
    let run = deferred_on_gpu(&out, &["--visibility"]);
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(stdout.contains("gbuffer: visibility buffer"), "{stdout}");
    // llvmpipe has no binding arrays: the resolve by material tiles.
    let resolve = ["resolve in one dispatch", "resolve by material tiles"];
    assert!(resolve.iter().any(|r| stdout.contains(r)), "{stdout}");
    if !gpu.has_timestamps() {
        return;
    }
    let run = deferred_on_gpu(&out, &["--visibility=auto"]);
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let line = stdout
        .lines()
        .find(|l| l.starts_with("gbuffer:"))
        .unwrap_or_else(|| panic!("no gbuffer line: {stdout}"));
    assert!(
        line.contains("chosen: visibility buffer")
            && line.contains(", hardware ")
            && line.contains("splits tried, ms: none: "),
        "{line}"
    );
}

/// Supersampling is a stage of the frame: with VPLs, a light-count heatmap of the sample
/// tiles, the per-pass table with the supersampled passes, and the sample counts.
#[test]
fn supersampling_composes_with_the_frame() {
    if gpu::test_device(&pipeline::device_needs()).is_none() {
        return;
    }
    let out = out_folder("ssaa");
    let run = deferred_on_gpu(
        &out,
        &[
            "--ssaa",
            "4",
            "--adaptive",
            "--vpls",
            "64",
            "--shading",
            "tiled-cones",
            "--heatmap",
        ],
    );
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    for pass in ["ss gbuffer", "ss resolve (adaptive)", "), samples", "SNSM"] {
        assert!(stdout.contains(pass), "no {pass} in {stdout}");
    }
    assert!(stdout.contains("ssaa:    adaptive 4x4"), "{stdout}");
    for file in ["render.png", "ssaa-samples.png", "heatmap.png"] {
        assert!(out.join(file).is_file(), "no {file}");
    }
    let heatmap = image::open(out.join("heatmap.png")).expect("heatmap");
    assert_eq!(
        (heatmap.width(), heatmap.height()),
        (384, 288),
        "sample tiles"
    );
}

/// The VPLs' near field (`--near-field`) needs VPLs, is refused on the CPU with a clear line,
/// and renders on the GPU.
#[test]
fn near_field_needs_vpls_and_a_gpu() {
    let out = out_folder("near-field-cpu");
    for args in [
        &["--near-field"][..],
        &["--near-field", "--vpls", "64"], // `deferred` adds --cpu
    ] {
        let run = deferred(&out, args);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert!(!run.status.success(), "{args:?} succeeded");
        assert!(
            stderr.contains("--near-field") || stderr.contains("--vpls"),
            "{args:?}: {stderr}"
        );
        assert!(!stderr.contains("panicked"), "{stderr}");
    }
    if gpu::test_device(&pipeline::device_needs()).is_none() {
        return;
    }
    let out = out_folder("near-field");
    let run = deferred_on_gpu(
        &out,
        &["--vpls", "256", "--vpl-shadows", "rays", "--near-field"],
    );
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(out.join("render.png").is_file());
}

/// `deferred` without arguments renders the first-impression Cornell box (shadows, VPL light
/// with visibility, tone mapping) into ./out and says what it used.
#[test]
fn a_bare_run_renders_the_first_impression() {
    if gpu::test_device(&pipeline::device_needs()).is_none() {
        return;
    }
    let dir = out_folder("bare");
    let run = Command::new(env!("CARGO_BIN_EXE_deferred"))
        .current_dir(&dir)
        .env_remove("RUST_BACKTRACE")
        .output()
        .expect("the deferred program runs");
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    for line in [
        "first-impression",
        "shadows: shadow maps",
        "visibility: ManyLoD",
        "output:",
    ] {
        assert!(stdout.contains(line), "{line:?} missing:\n{stdout}");
    }
    assert!(dir.join("out/render.png").is_file() && dir.join("out/render.exr").is_file());
}
