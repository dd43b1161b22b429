//! The `deferred` program against hostile command-line values and scene files, as a
//! subprocess under a memory cap (`ulimit -v`, 6 GiB) and a time limit: every invalid input is
//! a non-zero exit with a message naming the problem — never a panic, a crash (signal), a hang
//! or an exit status of 0.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn folder(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("cli-hostile")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("folder");
    dir
}

/// Runs `deferred ARGS` in `sh` with the address space capped at 6 GiB; (exit code, stderr,
/// seconds). A signal (crash, abort) has no exit code.
fn deferred(args: &[&str]) -> (Option<i32>, String, f64) {
    let start = Instant::now();
    let mut child = Command::new("sh")
        .arg("-c")
        .arg("ulimit -v 6291456; exec \"$0\" \"$@\"")
        .arg(env!("CARGO_BIN_EXE_deferred"))
        .args(args)
        .env_remove("RUST_BACKTRACE")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the deferred program starts");
    let deadline = start + Duration::from_secs(120);
    let status = loop {
        if let Some(status) = child.try_wait().expect("wait") {
            break status;
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            panic!("deferred {args:?} still runs after 120 s (a hang)");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let mut stderr = String::new();
    if let Some(mut e) = child.stderr.take() {
        let _ = std::io::Read::read_to_string(&mut e, &mut stderr);
    }
    (status.code(), stderr, start.elapsed().as_secs_f64())
}

/// Fails unless `args` is refused cleanly with a message containing `why`.
fn refused(args: &[&str], why: &str) {
    let (code, stderr, _) = deferred(args);
    assert!(!stderr.contains("panicked"), "{args:?} panicked: {stderr}");
    assert!(
        matches!(code, Some(c) if c != 0 && c != 101),
        "{args:?}: exit {code:?} (0 = accepted, None = killed by a signal): {stderr}"
    );
    assert!(
        stderr.contains(why),
        "{args:?}: expected {why:?} in {stderr}"
    );
}

#[test]
fn hostile_command_line_values_are_refused() {
    let out = folder("values");
    let out = out.to_str().expect("UTF-8 path");
    let cases: &[(&[&str], &str)] = &[
        (&["--size", "0x10"], "size must be between 1 and"),
        (&["--size", "99999999999x2"], "is not a positive integer"),
        (
            &["--size", "16384x16384", "--cpu"],
            "the CPU reference renders at most",
        ),
        (
            &["--lights", "100000000"],
            "expected a light count from 0 to 2097152",
        ),
        (&["--lights", "-1"], "unexpected argument '-1'"),
        (&["--fov", "1e-30"], "field of view from 0.1 to 179"),
        (&["--fov", "nan"], "field of view from 0.1 to 179"),
        (&["--eye", "1,2"], "three finite numbers"),
        (&["--eye", "0,inf,0"], "three finite numbers"),
        (&["--ambient", "nan,0,0"], "three finite numbers"),
        (&["--blur", "4"], "--vpls"),
        (&["--reference", "0"], "samples per pixel from 1 to 65536"),
        (&["--max-bounces", "2"], "--reference"),
        (&["--reference", "4", "--vpls", "64"], "cannot be used with"),
        (&["--seed", "3", "--cpu"], "--reference"),
        (
            &["--vpls", "0", "--cpu"],
            "expected a VPL count from 1 to 16384",
        ),
        (&["--pattern", "2x2"], "--vpls"),
        (&["--vpls", "64", "--blur", "4", "--cpu"], "blur"),
        (&["--vpls", "64", "--pattern", "0x3", "--cpu"], "pattern"),
        (&["--tile", "7", "--cpu"], "tile"),
        (&["--ssaa", "4", "--cpu"], "--ssaa"),
        (&["--ssaa", "1"], "--ssaa 1"),
        (&["--ssaa", "9"], "--ssaa 9"),
        (&["--adaptive"], "--ssaa"),
        (&["--ssao", "filter-separable", "--cpu"], "--ssao"),
        (&["--ssao", "gtao", "--ssao-kernel", "4"], "odd size"),
        (
            &["--ssao", "hbao-separable", "--ssao-radius", "nan"],
            "radius",
        ),
        (
            &["--ssao", "separable"],
            "unknown ambient-occlusion estimator",
        ),
        (&["--ssao-kernel", "5"], "--ssao"),
        (&["--builtin", "nowhere"], "unknown built-in scene"),
        (&["--scene", "/nonexistent/scene.gltf"], "scene.gltf"),
        (&["--light", "point:0,1,0,-1"], "--light"),
        (&["--indirect-only"], "--indirect-only needs --vpls"),
        (
            &["--eye", "0,1,0", "--target", "0,1,0", "--cpu"],
            "the camera of --eye/--target/--fov",
        ),
        (
            &[
                "subdivide",
                "/nonexistent.obj",
                "--level",
                "2",
                "-o",
                "x.obj",
            ],
            "nonexistent.obj",
        ),
    ];
    for &(args, why) in cases {
        let mut all: Vec<&str> = vec!["--out", out, "--size", "32x24"];
        if args.first() == Some(&"subdivide") {
            all.clear();
        } else if args.contains(&"--size") {
            all.truncate(2);
        }
        all.extend(args);
        refused(&all, why);
    }
}

#[test]
fn hostile_subdivide_inputs_are_refused() {
    let dir = folder("subdivide");
    let write = |name: &str, text: &str| {
        let p = dir.join(name);
        std::fs::write(&p, text).expect("obj");
        p.to_str().expect("UTF-8").to_owned()
    };
    let tri = write("tri.obj", "v 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\n");
    let out = dir.join("out.obj");
    let out = out.to_str().expect("UTF-8");
    for (input, level, why) in [
        (
            write("huge.obj", "v 1e308 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\n"),
            "2",
            "magnitude at most 1e30",
        ),
        (write("empty.obj", ""), "2", "no faces"),
        (
            write("edge.obj", "v 1 0 0\nv 0 1 0\nf 1 2\n"),
            "1",
            "at least three vertices",
        ),
        (tri.clone(), "100", "too large: level 100"),
        (tri.clone(), "4294967296", "--level"),
    ] {
        refused(&["subdivide", &input, "--level", level, "-o", out], why);
        assert!(!Path::new(out).exists(), "{input}: an output was written");
    }
}

#[test]
fn hostile_scene_files_end_in_an_error_not_a_crash() {
    // Every scene below is invalid; each run must be a clean non-zero exit.
    let dir = folder("scenes");
    let out = dir.join("out");
    let cases: &[(&str, &str, &str)] = &[
        (
            "cycle.gltf",
            r#"{"asset":{"version":"2.0"},"nodes":[{"children":[0]}],"scenes":[{"nodes":[0]}]}"#,
            "cycle",
        ),
        (
            "zero.gltf",
            r#"{"asset":{"version":"2.0"},"buffers":[{"uri":"/dev/zero","byteLength":1000000000}]}"#,
            "absolute paths are not read",
        ),
        (
            "up.gltf",
            r#"{"asset":{"version":"2.0"},"buffers":[{"uri":"../../../../etc/passwd","byteLength":10}]}"#,
            "outside the scene's folder",
        ),
        ("bad.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n", "line 3"),
        (
            "nan.obj",
            "v 0 0 nan\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
            "line 1",
        ),
        (
            "mtl.obj",
            "mtllib /etc/passwd\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
            "absolute paths are not read",
        ),
        (
            "huge.ply",
            "ply\nformat ascii 1.0\nelement vertex 99999999999999999999999\nend_header\n",
            "a number too large",
        ),
        ("garbage.glb", "glTF\x02\0\0\0\x7f\x7f\x7f\x7f", "glTF"),
    ];
    for &(name, text, why) in cases {
        let path = dir.join(name);
        std::fs::write(&path, text).expect("scene");
        refused(
            &[
                "--cpu",
                "--size",
                "32x24",
                "--out",
                out.to_str().expect("UTF-8"),
                "--scene",
                path.to_str().expect("UTF-8"),
            ],
            why,
        );
    }
    assert!(
        !out.join("render.png").exists(),
        "a failed run left an image"
    );
}
