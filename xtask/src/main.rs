//! Project tasks.
//!
//! - `cargo xtask test [ARGS]`: makes sure a Vulkan driver exists (installs Mesa's software
//!   Vulkan, Debian package `mesa-vulkan-drivers`, with apt when none is found), then runs the
//!   whole test suite in release mode (`cargo test --workspace --release [ARGS]`).
//! - `cargo xtask bench [ARGS]`: runs the GPU benchmarks (`deferred-bench [ARGS]`,
//!   `interleave-bench [ARGS]`, `indirect-bench [ARGS]`, `tiled-bench [ARGS]`, `ssaa-bench [ARGS]`, `subdiv-bench [ARGS]` and `manylod-bench [ARGS]`, reports
//!   under docs/bench/) and the CPU criterion benches.
//! - `cargo xtask bft [--level L] [--max-valence N] [-o FILE]`: builds the Loop basis-function
//!   tables and writes their versioned binary file (default `target/bft/loop-l5-v18.bft`).
//! - `cargo xtask subdiv-fixtures`: regenerates `fixtures/subdiv/*.f32`, Loop subdivision of
//!   the shared closed meshes by MeshLab, checked against trimesh (`xtask/loop_reference.py`).

use std::{
    path::{Path, PathBuf},
    process::Command,
};

use anyhow::{Context, Result, bail};

fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map_or_else(|| PathBuf::from("."), Path::to_path_buf)
}

fn run(cmd: &mut Command) -> Result<()> {
    eprintln!("xtask: running {cmd:?}");
    let status = cmd
        .status()
        .with_context(|| format!("could not start {cmd:?}"))?;
    if !status.success() {
        bail!("{cmd:?} failed with {status}");
    }
    Ok(())
}

/// Vulkan ICD manifests where the loader looks for drivers.
fn vulkan_driver_present() -> bool {
    if std::env::var_os("VK_DRIVER_FILES")
        .or_else(|| std::env::var_os("VK_ICD_FILENAMES"))
        .is_some()
    {
        return true;
    }
    [
        "/usr/share/vulkan/icd.d",
        "/etc/vulkan/icd.d",
        "/usr/local/share/vulkan/icd.d",
    ]
    .iter()
    .any(|dir| {
        std::fs::read_dir(dir).is_ok_and(|entries| {
            entries
                .flatten()
                .any(|e| e.path().extension().is_some_and(|x| x == "json"))
        })
    })
}

fn ensure_vulkan() -> Result<()> {
    if vulkan_driver_present() {
        return Ok(());
    }
    eprintln!(
        "xtask: no Vulkan driver found; installing Mesa's software Vulkan (mesa-vulkan-drivers) with apt"
    );
    let root = Command::new("id")
        .arg("-u")
        .output()
        .is_ok_and(|o| o.stdout.starts_with(b"0"));
    let apt = |args: &[&str]| {
        let mut c = if root {
            Command::new("apt-get")
        } else {
            Command::new("sudo")
        };
        if !root {
            c.arg("apt-get");
        }
        c.args(args).env("DEBIAN_FRONTEND", "noninteractive");
        c
    };
    run(&mut apt(&["update", "-qq"]))?;
    run(&mut apt(&[
        "install",
        "-y",
        "-qq",
        "--no-install-recommends",
        "mesa-vulkan-drivers",
        "libvulkan1",
    ]))?;
    if !vulkan_driver_present() {
        bail!("mesa-vulkan-drivers installed but no Vulkan ICD manifest found");
    }
    Ok(())
}

fn cargo() -> Command {
    let mut c = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()));
    c.current_dir(workspace_root());
    c
}

fn main() -> Result<()> {
    let mut args = std::env::args().skip(1);
    let task = args.next().unwrap_or_default();
    let rest: Vec<String> = args.collect();
    match task.as_str() {
        "test" => {
            ensure_vulkan()?;
            run(cargo()
                .args(["test", "--workspace", "--release"])
                .args(&rest))
        }
        "bench" => {
            for (package, bin) in [
                ("pipeline", "deferred-bench"),
                ("interleave", "interleave-bench"),
                ("pipeline", "indirect-bench"),
                ("pipeline", "tiled-bench"),
                ("pipeline", "ssaa-bench"),
                ("pipeline", "subdiv-bench"),
                ("pipeline", "manylod-bench"),
            ] {
                run(cargo()
                    .args(["run", "--release", "-p", package, "--bin", bin, "--"])
                    .args(&rest))?;
            }
            run(cargo().args([
                "bench",
                "-p",
                "gbuffer",
                "-p",
                "interleave",
                "-p",
                "tiled-shading",
                "-p",
                "adaptive-ssaa",
                "-p",
                "subdiv-bft",
                // Only the criterion targets: the library test harnesses reject `--quick`.
                "--bench",
                "rasterize",
                "--bench",
                "split",
                "--bench",
                "shade",
                "--bench",
                "adaptive",
                "--bench",
                "subdiv",
                "--",
                "--quick",
            ]))
        }
        "bft" => run(cargo()
            .args(["run", "--release", "-p", "subdiv-bft", "--bin", "bft", "--"])
            .args(&rest)),
        "subdiv-fixtures" => {
            let shared = workspace_root().join("../shared/fixtures");
            run(Command::new("python3").args([
                "-m",
                "pip",
                "install",
                "--quiet",
                "numpy",
                "scipy",
                "trimesh",
                "pymeshlab",
            ]))?;
            run(Command::new("python3")
                .current_dir(workspace_root())
                .arg("xtask/loop_reference.py")
                .arg(shared)
                .arg("fixtures/subdiv"))
        }
        _ => bail!(
            "usage: cargo xtask test [CARGO TEST ARGS] | cargo xtask bench [BENCH ARGS: --frames N, --out DIR, --allow-software] | cargo xtask bft [--level L] [--max-valence N] [-o FILE] | cargo xtask subdiv-fixtures"
        ),
    }
}
