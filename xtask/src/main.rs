//! Project tasks.
//!
//! - `cargo xtask test [ARGS]`: makes sure a Vulkan driver exists (installs Mesa's software
//!   Vulkan, Debian package `mesa-vulkan-drivers`, with apt when none is found), Xvfb (for
//!   the viewer's tests, with the X libraries winit loads) and what OpenSubdiv's C++ build
//!   needs (`deferred-peers`: cmake, g++, libclang-dev), then runs the
//!   whole test suite in release mode (`cargo test --workspace --release [ARGS]`), runs every
//!   benchmark once (`cargo test --bench "*"`: the GPU benches' run-once mode at reduced sizes on
//!   any adapter, criterion's test mode), builds every example, and runs every `*-embed`
//!   example (each crate in a device the example creates itself at `wgpu::Limits::default()`
//!   plus the crate's stated needs).
//! - `cargo xtask bench [ARGS]`: runs every GPU benchmark (the `*-gpu` bench targets beside
//!   their crates, on the `deferred-bench` harness; reports under docs/bench/) with `ARGS`,
//!   then the CPU criterion benches. `peers-gpu` builds OpenSubdiv (CMake, g++ and libclang,
//!   installed with apt when missing, as for `test`) and calls MeshLab and Open3D through Python
//!   (pip-installed from `crates/peers/requirements.txt` when they do not import; without them
//!   it reports them as not run).
//! - `cargo xtask bench-bins [DIR]`: builds every GPU benchmark and copies its executable to
//!   `DIR/<name>` (default `.gpu-bin`), to carry to a machine without Rust (the lent GPU).
//!   Start them there with `--bench` (without it they run once at reduced sizes, as in tests).
//! - `cargo xtask package-check`: packages every library crate (`cargo package --no-verify`),
//!   unpacks `deferred-interleave` and `deferred-tiled-shading` with the toolkit crates they
//!   depend on, and builds and runs a throwaway crate outside the workspace that depends on the
//!   unpacked packages (through `[patch.crates-io]`) and runs their `examples/embed.rs`.
//! - `cargo xtask bft [--level L] [--max-valence N] [-o FILE]`: builds the Loop basis-function
//!   tables and writes their versioned binary file (default `loop-l5-v18.bft` in the user's cache folder, `BftSet::default_path`).
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
    apt_install(&["mesa-vulkan-drivers", "libvulkan1"])?;
    if !vulkan_driver_present() {
        bail!("mesa-vulkan-drivers installed but no Vulkan ICD manifest found");
    }
    Ok(())
}

/// Whether `program` is on the PATH.
fn on_path(program: &str) -> bool {
    std::env::var_os("PATH")
        .is_some_and(|paths| std::env::split_paths(&paths).any(|dir| dir.join(program).is_file()))
}

/// The virtual X display the viewer's tests start (`Xvfb`) and the X client libraries winit
/// loads at run time.
fn ensure_xvfb() -> Result<()> {
    if on_path("Xvfb") {
        return Ok(());
    }
    eprintln!("xtask: no Xvfb found; installing it and the X libraries winit loads with apt");
    apt_install(&[
        "xvfb",
        "libx11-6",
        "libx11-xcb1",
        "libxcursor1",
        "libxrandr2",
        "libxi6",
        "libxkbcommon-x11-0",
    ])?;
    if !on_path("Xvfb") {
        bail!("xvfb installed but no Xvfb on the PATH");
    }
    Ok(())
}

/// What building OpenSubdiv's C++ (the `deferred-peers` crate, through opensubdiv-petite-sys)
/// needs: CMake, a C++ compiler, and libclang for its bindings.
fn ensure_opensubdiv_tools() -> Result<()> {
    let libclang = || {
        Command::new("ldconfig").arg("-p").output().is_ok_and(|o| {
            String::from_utf8_lossy(&o.stdout).lines().any(|l| {
                l.trim_start().starts_with("libclang-") || l.trim_start().starts_with("libclang.so")
            })
        })
    };
    if on_path("cmake") && on_path("c++") && libclang() {
        return Ok(());
    }
    eprintln!(
        "xtask: installing what OpenSubdiv's build needs (cmake, g++, libclang-dev) with apt"
    );
    apt_install(&["cmake", "g++", "libclang-dev"])?;
    if !(on_path("cmake") && on_path("c++") && libclang()) {
        bail!("cmake, g++ and libclang-dev installed, but cmake, c++ or libclang is still missing");
    }
    Ok(())
}

/// The Python libraries `peers-gpu` compares with (MeshLab, Open3D;
/// `crates/peers/requirements.txt`), installed with pip for the user where they do not import.
/// Best effort: without them (no pip, no network) the benchmark says they did not run.
fn ensure_python_peers() {
    let imports = || {
        Command::new("python3")
            .args(["-c", "import pymeshlab, open3d"])
            .output()
            .is_ok_and(|o| o.status.success())
    };
    if imports() {
        return;
    }
    let requirements = workspace_root().join("crates/peers/requirements.txt");
    // Open3D's wheel loads libusb.
    if let Err(e) = apt_install(&["libusb-1.0-0"]) {
        eprintln!("xtask: libusb-1.0-0 (for Open3D) not installed: {e:#}");
    }
    eprintln!(
        "xtask: installing the Python peers of peers-gpu ({}) with pip",
        requirements.display()
    );
    let installed = Command::new("python3")
        .args(["-m", "pip", "install", "--user", "-q", "-r"])
        .arg(&requirements)
        .status()
        .is_ok_and(|s| s.success());
    if !installed || !imports() {
        eprintln!(
            "xtask: pymeshlab/open3d are not importable; peers-gpu will report them as not run"
        );
    }
}

/// `apt-get install` of `packages` (through sudo when not root).
fn apt_install(packages: &[&str]) -> Result<()> {
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
    run(apt(&["install", "-y", "-qq", "--no-install-recommends"]).args(packages))
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
            ensure_xvfb()?;
            ensure_opensubdiv_tools()?;
            run(cargo()
                .args(["test", "--workspace", "--release"])
                .args(&rest))?;
            // Every benchmark runs once (GPU benches in their run-once mode, criterion benches
            // in its test mode) and every example builds, so none can rot unseen.
            run(cargo().args(["test", "--release", "--workspace", "--bench", "*"]))?;
            run(cargo().args(["build", "--release", "--workspace", "--examples"]))?;
            // The workspace build's executables: `cargo run -p` would rebuild with other features.
            for (_, example) in targets("example", "-embed")? {
                run(&mut Command::new(
                    workspace_root()
                        .join("target/release/examples")
                        .join(&example),
                ))?;
            }
            Ok(())
        }
        "bench" => {
            ensure_opensubdiv_tools()?;
            ensure_python_peers();
            // `cargo bench` runs each program in its package's folder: the reports go to the
            // workspace's docs/bench unless --out says otherwise.
            let out = workspace_root().join("docs/bench");
            let out_args: Vec<String> = if rest.iter().any(|a| a == "--out") {
                Vec::new()
            } else {
                vec!["--out".into(), out.display().to_string()]
            };
            for (package, bench) in targets("bench", "-gpu")? {
                run(cargo()
                    .args(["bench", "-p", &package, "--bench", &bench, "--"])
                    .args(&out_args)
                    .args(&rest))?;
            }
            // The CPU criterion benches: every other bench target.
            let mut criterion = cargo();
            criterion.arg("bench");
            for (package, bench) in targets("bench", "")? {
                if !bench.ends_with("-gpu") {
                    criterion.args(["-p", &package, "--bench", &bench]);
                }
            }
            run(criterion.args(["--", "--quick"]))
        }
        "bench-bins" => {
            ensure_opensubdiv_tools()?;
            let dir = PathBuf::from(rest.first().map_or(".gpu-bin", String::as_str));
            bench_bins(&dir)
        }
        "package-check" => package_check(),
        "bft" => run(cargo()
            .args([
                "run",
                "--release",
                "-p",
                "deferred-subdiv-bft",
                "--bin",
                "bft",
                "--",
            ])
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
            "usage: cargo xtask test [CARGO TEST ARGS] | cargo xtask package-check | cargo xtask bench-bins [DIR] | cargo xtask bench [BENCH ARGS: --frames N, --out DIR, --allow-software] | cargo xtask bft [--level L] [--max-valence N] [-o FILE] | cargo xtask subdiv-fixtures"
        ),
    }
}

/// `(package, target)` of every workspace target of `kind` (`bench`, `example`) whose name
/// ends with `suffix`: the GPU benchmarks (`*-gpu`) and the embedding examples (`*-embed`).
fn targets(kind: &str, suffix: &str) -> Result<Vec<(String, String)>> {
    let mut found = Vec::new();
    for p in metadata()?["packages"].as_array().into_iter().flatten() {
        for t in p["targets"].as_array().into_iter().flatten() {
            let of_kind = t["kind"]
                .as_array()
                .is_some_and(|k| k.iter().any(|k| k == kind));
            if let (true, Some(name), Some(package)) =
                (of_kind, t["name"].as_str(), p["name"].as_str())
                && name.ends_with(suffix)
            {
                found.push((package.to_owned(), name.to_owned()));
            }
        }
    }
    found.sort();
    Ok(found)
}

fn metadata() -> Result<serde_json::Value> {
    let out = cargo()
        .args(["metadata", "--no-deps", "--format-version", "1"])
        .output()
        .context("cargo metadata")?;
    if !out.status.success() {
        bail!(
            "cargo metadata failed: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    Ok(serde_json::from_slice(&out.stdout)?)
}

/// Library crates of the workspace that publish: (package name, manifest folder).
fn library_packages() -> Result<Vec<(String, PathBuf)>> {
    let meta = metadata()?;
    let mut packages = Vec::new();
    for p in meta["packages"].as_array().into_iter().flatten() {
        let publishes = !p["publish"].as_array().is_some_and(Vec::is_empty);
        let is_lib = p["targets"].as_array().into_iter().flatten().any(|t| {
            t["kind"]
                .as_array()
                .is_some_and(|k| k.iter().any(|k| k == "lib"))
        });
        let (Some(name), Some(manifest)) = (p["name"].as_str(), p["manifest_path"].as_str()) else {
            continue;
        };
        if publishes && is_lib {
            let dir = Path::new(manifest)
                .parent()
                .map(Path::to_path_buf)
                .unwrap_or_default();
            packages.push((name.to_owned(), dir));
        }
    }
    Ok(packages)
}

/// The crates the throwaway user crate depends on, the toolkit crates they need, and the
/// example each user binary runs.
const USER_DEPENDS_ON: [&str; 4] = [
    "deferred-interleave",
    "deferred-tiled-shading",
    "deferred-gbuffer",
    "deferred-scene",
];
const PACKAGE_CLOSURE: [&str; 6] = [
    "deferred-gpu",
    "deferred-scene",
    "deferred-gbuffer",
    "deferred-manylod",
    "deferred-interleave",
    "deferred-tiled-shading",
];
const USER_BINARIES: [(&str, &str); 2] = [
    ("interleave-embed", "crates/interleave/examples/embed.rs"),
    (
        "tiled-shading-embed",
        "crates/tiled-shading/examples/embed.rs",
    ),
];

fn package_check() -> Result<()> {
    let root = workspace_root();
    let packages = library_packages()?;
    let version = env!("CARGO_PKG_VERSION");
    let mut cmd = cargo();
    cmd.args(["package", "--no-verify", "--allow-dirty"]);
    for (name, _) in &packages {
        cmd.args(["-p", name]);
    }
    run(&mut cmd)?;
    let check = root.join("target/package-check");
    if check.exists() {
        std::fs::remove_dir_all(&check).with_context(|| format!("removing {}", check.display()))?;
    }
    let unpacked = check.join("crates");
    std::fs::create_dir_all(&unpacked)?;
    for name in PACKAGE_CLOSURE {
        let file = root.join(format!("target/package/{name}-{version}.crate"));
        run(Command::new("tar")
            .arg("xzf")
            .arg(&file)
            .arg("-C")
            .arg(&unpacked))?;
    }
    for (name, dir) in &packages {
        // Every WGSL file of the crate's shader folder travels with its package.
        let shaders = dir.join("shaders");
        let Ok(entries) = std::fs::read_dir(&shaders) else {
            continue;
        };
        let file = root.join(format!("target/package/{name}-{version}.crate"));
        let listing = Command::new("tar").arg("tzf").arg(&file).output()?;
        let listing = String::from_utf8_lossy(&listing.stdout);
        for e in entries.flatten() {
            let wgsl = e.file_name().to_string_lossy().into_owned();
            if wgsl.ends_with(".wgsl") && !listing.contains(&format!("/shaders/{wgsl}")) {
                bail!("{name}'s package lacks shaders/{wgsl}");
            }
        }
    }
    let user = check.join("user");
    std::fs::create_dir_all(user.join("src/bin"))?;
    let wgpu = "wgpu = { version = \"30\", default-features = false, features = [\"std\", \"parking_lot\", \"wgsl\", \"vulkan\", \"metal\", \"dx12\"] }";
    let mut manifest = format!(
        "[package]\nname = \"package-check-user\"\nversion = \"0.0.0\"\nedition = \"2024\"\npublish = false\n\n[workspace]\n\n[dependencies]\n{wgpu}\npollster = \"0.4\"\n"
    );
    for name in USER_DEPENDS_ON {
        manifest.push_str(&format!("{name} = \"{version}\"\n"));
    }
    // The workspace's release profile, so the third-party builds in its target folder are reused.
    manifest.push_str(
        "\n[profile.release]\ndebug = \"line-tables-only\"\n\n[profile.release.package.\"*\"]\ndebug = false\n",
    );
    manifest.push_str("\n[patch.crates-io]\n");
    for name in PACKAGE_CLOSURE {
        manifest.push_str(&format!(
            "{name} = {{ path = \"../crates/{name}-{version}\" }}\n"
        ));
    }
    std::fs::write(user.join("Cargo.toml"), manifest)?;
    // The workspace's lock file pins the same third-party versions, so their builds are reused.
    std::fs::copy(root.join("Cargo.lock"), user.join("Cargo.lock"))?;
    for (bin, example) in USER_BINARIES {
        std::fs::copy(root.join(example), user.join(format!("src/bin/{bin}.rs")))?;
    }
    for (bin, _) in USER_BINARIES {
        run(
            Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
                .current_dir(&user)
                .args(["run", "--release", "--bin", bin, "--target-dir"])
                .arg(root.join("target")),
        )?;
    }
    eprintln!(
        "xtask: package-check passed: a crate outside the workspace built and ran the packaged kernels"
    );
    Ok(())
}

/// Builds the `*-gpu` benchmarks and copies each executable to `dir/<bench name>`.
fn bench_bins(dir: &Path) -> Result<()> {
    let mut cmd = cargo();
    cmd.args(["bench", "--no-run", "--message-format=json"]);
    for (package, bench) in targets("bench", "-gpu")? {
        cmd.args(["-p", &package, "--bench", &bench]);
    }
    eprintln!("xtask: running {cmd:?}");
    let out = cmd.output().context("cargo bench --no-run")?;
    if !out.status.success() {
        bail!(
            "building the benchmarks failed:\n{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    std::fs::create_dir_all(dir)?;
    for line in String::from_utf8_lossy(&out.stdout).lines() {
        let Ok(msg) = serde_json::from_str::<serde_json::Value>(line) else {
            continue;
        };
        let is_bench = msg["target"]["kind"]
            .as_array()
            .is_some_and(|k| k.iter().any(|k| k == "bench"));
        if let (true, Some(name), Some(exe)) = (
            is_bench,
            msg["target"]["name"].as_str(),
            msg["executable"].as_str(),
        ) && name.ends_with("-gpu")
        {
            std::fs::copy(exe, dir.join(name)).with_context(|| format!("copying {exe}"))?;
            eprintln!("xtask: {} -> {}", exe, dir.join(name).display());
        }
    }
    Ok(())
}
