//! `deferred view` driven by scripts on a virtual display (Xvfb, started here when no DISPLAY
//! is set; `cargo xtask test` installs it): scripted flight and a panel click, each screenshot
//! against the offline renderer's image of the recipe the viewer saved with it, the window's
//! pixels against the screenshot and a debug view against `--dump-stages`, and the errors
//! without a display or with a bad script.

mod common;

use std::io::BufRead;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};

/// A virtual X display for one test (its server stops with it), or the caller's display.
struct Display {
    name: String,
    server: Option<Child>,
}

impl Drop for Display {
    fn drop(&mut self) {
        if let Some(server) = &mut self.server {
            let _ = server.kill();
            let _ = server.wait();
        }
    }
}

/// The display to test on: `DISPLAY` when set, else a new Xvfb server. `None` (the test is
/// skipped, and says so) when there is neither, except under CI, where that fails.
fn display() -> Option<Display> {
    if let Some(name) = std::env::var("DISPLAY").ok().filter(|d| !d.is_empty()) {
        return Some(Display { name, server: None });
    }
    let started = Command::new("Xvfb")
        .args([
            "-displayfd",
            "1",
            "-screen",
            "0",
            "1280x1024x24",
            "-nolisten",
            "tcp",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn();
    let mut server = match started {
        Ok(s) => s,
        Err(e) => {
            assert!(
                std::env::var_os("CI").is_none(),
                "no DISPLAY and no Xvfb ({e}): `cargo xtask test` installs it"
            );
            eprintln!("skipped: no DISPLAY and no Xvfb ({e})");
            return None;
        }
    };
    // Xvfb writes its display number to fd 1 once it accepts clients.
    let mut line = String::new();
    let stdout = server.stdout.take().expect("Xvfb's stdout is piped");
    std::io::BufReader::new(stdout)
        .read_line(&mut line)
        .expect("Xvfb reports its display");
    let number: u32 = line.trim().parse().expect("Xvfb's display number");
    Some(Display {
        name: format!(":{number}"),
        server: Some(server),
    })
}

/// `deferred view ARGS --script SCRIPT --out OUT` on `display`.
fn view(display: &Display, script: &str, args: &[&str], out: &Path) -> Output {
    std::fs::create_dir_all(out).expect("test folder");
    let script_path = out.join("script.txt");
    std::fs::write(&script_path, script).expect("script written");
    Command::new(env!("CARGO_BIN_EXE_deferred"))
        .arg("view")
        .args(args)
        .arg("--script")
        .arg(&script_path)
        .arg("--out")
        .arg(out)
        .env("DISPLAY", &display.name)
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("RUST_BACKTRACE")
        .output()
        .expect("the deferred program runs")
}

fn rgb(path: &Path) -> image::RgbImage {
    image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgb8()
}

/// The largest difference of any channel, and the mean over all channels.
fn difference(a: &image::RgbImage, b: &image::RgbImage) -> (u8, f64) {
    assert_eq!(a.dimensions(), b.dimensions());
    let d: Vec<u8> = a
        .as_raw()
        .iter()
        .zip(b.as_raw())
        .map(|(x, y)| x.abs_diff(*y))
        .collect();
    let max = d.iter().copied().max().unwrap_or(0);
    let mean = d.iter().map(|&v| f64::from(v)).sum::<f64>() / d.len() as f64;
    (max, mean)
}

/// A recipe key's value as three numbers (`eye = "x,y,z"`).
fn vec3_key(recipe: &Path, key: &str) -> [f32; 3] {
    let table: toml::Table = toml::from_str(&std::fs::read_to_string(recipe).expect("recipe"))
        .expect("the saved recipe is TOML");
    let text = table[key].as_str().expect("a string value");
    let v: Vec<f32> = text
        .split(',')
        .map(|c| c.parse().expect("a number"))
        .collect();
    [v[0], v[1], v[2]]
}

fn output_text(out: &Output) -> String {
    format!(
        "status {}\nstdout:\n{}\nstderr:\n{}",
        out.status,
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

/// The screenshot's and the offline render's difference the test accepts: one step of 8 bits
/// in any channel (the same GPU kernels on the same adapter; measured: identical).
const TOLERANCE: u8 = 1;

#[test]
fn scripted_flight_and_panel_click_match_the_offline_renderer() {
    let Some(display) = display() else { return };
    let out = common::out_folder("viewer", "flight");
    let script = "\
# the first frames, then fly forward, look right and up, strafe right
wait 3
screenshot start
hold W 6
drag 20 -10
hold D 2
screenshot flown
capture-window window
# the panel's checkbox, clicked by synthesised pointer events
click exact ray shadows
wait 2
screenshot toggled
# a debug view: the G-buffer's normals
view normal
wait 1
capture-window window-normal
quit
";
    let run = view(&display, script, &["--size", "256x192"], &out);
    assert!(run.status.success(), "{}", output_text(&run));

    // Each screenshot is what `deferred --recipe` renders from the recipe saved beside it.
    for name in ["start", "flown", "toggled"] {
        let recipe = out.join(format!("{name}.toml"));
        let offline = out.join(format!("offline-{name}"));
        let rendered = common::deferred(
            &["--recipe", recipe.to_str().expect("utf-8"), "--dump-stages"],
            &offline,
        );
        assert!(rendered.status.success(), "{}", output_text(&rendered));
        let (max, mean) = difference(
            &rgb(&out.join(format!("{name}.png"))),
            &rgb(&offline.join("render.png")),
        );
        assert!(
            max <= TOLERANCE,
            "{name}: viewer and offline renderer differ by up to {max} (mean {mean:.4})"
        );
    }

    // W flew along the view: the eye moved forward along the first view direction.
    let (eye0, target0) = (
        vec3_key(&out.join("start.toml"), "eye"),
        vec3_key(&out.join("start.toml"), "target"),
    );
    let eye1 = vec3_key(&out.join("flown.toml"), "eye");
    let forward: f32 = (0..3)
        .map(|i| (eye1[i] - eye0[i]) * (target0[i] - eye0[i]))
        .sum();
    assert!(
        forward > 0.0,
        "the eye did not move forward: {eye0:?} → {eye1:?}"
    );
    let (_, moved) = difference(&rgb(&out.join("start.png")), &rgb(&out.join("flown.png")));
    assert!(
        moved > 2.0,
        "the image hardly changed after flying ({moved:.3})"
    );

    // The click turned on exact ray shadows: the recipe says so, and shadows only take light
    // away (every pixel as dark or darker, many clearly darker).
    let toggled = std::fs::read_to_string(out.join("toggled.toml")).expect("recipe");
    assert!(toggled.contains("ray-shadows = true"), "{toggled}");
    let (before, after) = (rgb(&out.join("flown.png")), rgb(&out.join("toggled.png")));
    let brighter = before
        .pixels()
        .zip(after.pixels())
        .filter(|(b, a)| (0..3).any(|c| a[c] > b[c].saturating_add(TOLERANCE)))
        .count();
    let darker = before
        .pixels()
        .zip(after.pixels())
        .filter(|(b, a)| (0..3).any(|c| a[c] + 10 < b[c]))
        .count();
    assert_eq!(brighter, 0, "pixels got brighter with shadows");
    let pixels = (before.width() * before.height()) as usize;
    assert!(
        darker * 100 > pixels,
        "too few shadowed pixels: {darker} of {pixels}"
    );

    // The window shows the screenshot's exact pixels (beside the panel).
    let window = rgb(&out.join("window.png"));
    assert!(
        contains(&window, &before),
        "the window capture does not contain the frame"
    );
    // The normal view shows what --dump-stages writes of the same G-buffer.
    let normals = rgb(&out.join("offline-toggled/stages/gbuffer-normal.png"));
    assert!(
        contains(&rgb(&out.join("window-normal.png")), &normals),
        "the window's normal view is not the G-buffer's normals"
    );
}

/// Whether `small` appears in `big` at some offset, pixel for pixel.
fn contains(big: &image::RgbImage, small: &image::RgbImage) -> bool {
    let (bw, bh) = big.dimensions();
    let (sw, sh) = small.dimensions();
    if sw > bw || sh > bh {
        return false;
    }
    (0..=bh - sh).any(|y0| {
        (0..=bw - sw).any(|x0| {
            (0..sh).all(|y| (0..sw).all(|x| big.get_pixel(x0 + x, y0 + y) == small.get_pixel(x, y)))
        })
    })
}

#[test]
fn without_a_display_the_viewer_says_so() {
    let out = common::out_folder("viewer", "no-display");
    let run = Command::new(env!("CARGO_BIN_EXE_deferred"))
        .args(["view", "--size", "64x48", "--out"])
        .arg(&out)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("RUST_BACKTRACE")
        .output()
        .expect("the deferred program runs");
    assert!(!run.status.success());
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(stderr.contains("no display"), "{stderr}");
    assert!(!out.exists(), "nothing is written");
}

#[test]
fn a_bad_script_is_refused_with_its_line() {
    let out = common::out_folder("viewer", "bad-script");
    std::fs::create_dir_all(&out).expect("test folder");
    let script: PathBuf = out.join("script.txt");
    for (text, expected) in [
        ("wait 2\nfly away\n", "line 2: unknown command \"fly\""),
        ("hold W many\n", "line 1: hold needs a frame count"),
        (
            "screenshot ../../escape\n",
            "line 1: screenshot needs a file name",
        ),
        ("press F13\n", "line 1: unknown key \"F13\""),
    ] {
        std::fs::write(&script, text).expect("script");
        let run = Command::new(env!("CARGO_BIN_EXE_deferred"))
            .arg("view")
            .arg("--script")
            .arg(&script)
            .env_remove("RUST_BACKTRACE")
            .output()
            .expect("the deferred program runs");
        assert!(!run.status.success());
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert!(stderr.contains(expected), "{text:?}: {stderr}");
    }
}
