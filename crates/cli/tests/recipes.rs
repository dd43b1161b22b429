//! Every recipe under `fixtures/recipes/` renders as a short, small sequence (on llvmpipe in
//! CI), command-line flags override a recipe's keys, and a bad recipe is refused with a line
//! that names the file and the key.

use std::path::{Path, PathBuf};

fn recipes() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/recipes");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("fixtures/recipes")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    files
}

mod common;
use common::deferred;

fn out_folder(name: &str) -> PathBuf {
    common::out_folder("cli-recipes", name)
}

#[test]
fn every_shipped_recipe_renders_a_short_sequence() {
    let files = recipes();
    assert!(files.len() >= 4, "{files:?}");
    if gpu::test_device(&pipeline::device_needs()).is_none() {
        return;
    }
    for recipe in files {
        let name = recipe
            .file_stem()
            .expect("name")
            .to_string_lossy()
            .into_owned();
        let out = out_folder(&name);
        let path = recipe.to_string_lossy().into_owned();
        let run = deferred(
            &["--recipe", &path, "--size", "64x48", "--frames", "2"],
            &out,
        );
        let stdout = String::from_utf8_lossy(&run.stdout);
        assert!(
            run.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&run.stderr)
        );
        // The command line's --size and --frames override the recipe's.
        assert!(stdout.contains("64x48"), "{name}: {stdout}");
        let csv = std::fs::read_to_string(out.join("timings.csv")).expect("timings.csv");
        assert_eq!(csv.lines().count(), 3, "{name}: two frames\n{csv}");
        assert!(out.join("frames/frame-00001.png").is_file(), "{name}");
    }
}

#[test]
fn a_bad_recipe_is_refused_with_the_file_and_key() {
    let dir = out_folder("bad");
    std::fs::create_dir_all(&dir).expect("folder");
    for (text, expected) in [
        ("sise = \"64x48\"\n", "unknown key \"sise\""),
        ("size = [\"64x48\", { a = 1 }]\n", "size: a table"),
        ("size = \"64x48\"\nvpls = 0\n", "VPL count"),
        ("this is not toml", "recipe"),
    ] {
        let file = dir.join("bad.toml");
        std::fs::write(&file, text).expect("recipe");
        let run = deferred(
            &["--cpu", "--recipe", &file.to_string_lossy()],
            &dir.join("out"),
        );
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert!(!run.status.success(), "{text:?} was accepted");
        assert!(stderr.contains(expected), "{text:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
        assert!(
            !dir.join("out").exists(),
            "{text:?}: a refused recipe wrote outputs"
        );
    }
}

#[test]
fn a_recipe_value_starting_with_a_minus_is_a_value() {
    // A camera at x < 0 (what the viewer saves often): `--eye -1,…` would read as a flag.
    let dir = out_folder("negative");
    std::fs::create_dir_all(&dir).expect("folder");
    let file = dir.join("camera.toml");
    std::fs::write(
        &file,
        "size = \"32x24\"\neye = \"-0.2,0.3,-0.5\"\ntarget = \"0.3,0.27,0.3\"\nexposure = -0.5\n",
    )
    .expect("recipe");
    let run = deferred(
        &["--cpu", "--recipe", &file.to_string_lossy()],
        &dir.join("out"),
    );
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(dir.join("out/render.png").is_file());
}
