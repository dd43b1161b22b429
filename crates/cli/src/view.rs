//! `deferred view`: the renderer in a window (winit, a wgpu surface) with an egui panel of the
//! recipe's settings, debug views and per-pass GPU timings; a fly/orbit camera, animation
//! playback, screenshots (PNG + EXR + the recipe that renders them again) and scripted input
//! for tests without a display of one's own (Xvfb).
//!
//! The viewer's state *is* a recipe: the long flags of `deferred` and their values. The panel
//! edits that recipe; settings the renderer can change in place are applied at once, the rest
//! rebuild the frame from the recipe exactly as `deferred --recipe` does, so a saved recipe
//! renders the image on screen.

use std::{
    collections::{BTreeMap, HashMap, VecDeque},
    ffi::OsString,
    path::{Path, PathBuf},
    sync::Arc,
};

use anyhow::{Context, Result, anyhow, bail};
use clap::{CommandFactory, Parser};
use glam::{Quat, Vec3};
use winit::{
    application::ApplicationHandler,
    event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent},
    event_loop::{ActiveEventLoop, EventLoop},
    keyboard::{KeyCode, PhysicalKey},
    window::{Window, WindowId},
};

use crate::{Args, Setup};

/// What `deferred view --help` prints.
const HELP: &str = "\
deferred view [--script FILE] [RENDER FLAGS | --recipe FILE]

Opens the renderer in a window. Every flag of `deferred` (see `deferred --help`) sets up the
first frame; the panel changes them live. Without flags: the first-impression Cornell box.

Controls (when the panel does not have the keyboard):
  W A S D / Q E    move forward, left, back, right / down, up (Shift: 4x faster)
  drag (left or right button on the image)   look around (orbit mode: turn about the target)
  wheel            flying speed (orbit mode: distance to the target)
  O                fly / orbit mode        R   reset to the recipe's camera
  1 .. 9           the scene's cameras (recipe, scene file, framing, animated)
  Space            play / pause the animation    .   step one frame (1/24 s)
  F12              screenshot: OUT/screenshot-N.png, .exr and .toml (the recipe with this camera)
  Escape           quit

--script FILE: drive the viewer from a file of commands, one a line (# comments), each run
after the frames before it:
  wait N                  render N frames
  hold KEY N              hold KEY (W, A, S, D, Q, E, Shift) for N frames
  press KEY               press and release KEY (F12, R, O, Space, Period, 1 .. 9)
  drag DX DY              look by DX, DY pixels of mouse drag
  wheel N                 N wheel steps
  click LABEL             click the panel widget labelled LABEL (synthesised pointer events)
  set KEY VALUE|on|off    set a recipe key as the panel does (off removes it)
  view NAME               the debug view NAME (final, depth, normal, albedo, material, ...)
  screenshot NAME         like F12, to OUT/NAME.png, .exr and .toml
  capture-window NAME     the window's pixels, panel included, to OUT/NAME.png
  quit                    close the viewer (exit status 0)
Commands run before the next frame up to a wait, hold, click, screenshot or capture-window;
scripted frames advance the clocks by 1/30 s each, so a script replays identically.
";

/// `deferred view ARGS` (`argv` without the word `view`).
pub(crate) fn run(mut argv: Vec<OsString>) -> Result<()> {
    if argv.iter().skip(1).any(|a| a == "--help" || a == "-h") {
        print!("{HELP}");
        return Ok(());
    }
    let at = argv
        .iter()
        .position(|a| a == "--script" || a.to_string_lossy().starts_with("--script="));
    let script = match at {
        Some(at) => {
            let path = match argv[at].to_string_lossy().strip_prefix("--script=") {
                Some(p) => PathBuf::from(p),
                None => argv
                    .get(at + 1)
                    .map(PathBuf::from)
                    .context("--script needs a FILE")?,
            };
            let end = if argv[at] == "--script" { at + 1 } else { at };
            argv.drain(at..=end);
            Some(Script::read(&path)?)
        }
        None => None,
    };
    let argv = crate::with_recipe(argv)?;
    let mut recipe = Recipe::from_argv(&argv)?;
    let sequence: Vec<&str> = SEQUENCE_KEYS
        .into_iter()
        .filter(|k| recipe.has(k))
        .collect();
    if !sequence.is_empty() {
        eprintln!(
            "note: the viewer plays the animation live; it leaves out the sequence's flags {}",
            sequence.join(", ")
        );
        for k in sequence {
            recipe.set(k, None);
        }
    }
    let args = recipe.args()?;
    if args.command.is_some() {
        bail!("deferred view: `subdivide` is not a view; run it as `deferred subdivide`");
    }
    for (set, flag) in [
        (args.cpu, "--cpu"),
        (args.reference.is_some(), "--reference"),
    ] {
        if set {
            bail!("deferred view: {flag} renders to files; drop it to view (or run `deferred`)");
        }
    }
    if cfg!(all(unix, not(target_os = "macos")))
        && std::env::var_os("DISPLAY").is_none()
        && std::env::var_os("WAYLAND_DISPLAY").is_none()
    {
        bail!(
            "deferred view: no display (neither DISPLAY nor WAYLAND_DISPLAY is set). Render to \
             files with `deferred` instead, or start a virtual one: `xvfb-run -a deferred view …`"
        );
    }
    let event_loop = EventLoop::new().map_err(|e| {
        anyhow!("deferred view: cannot open the display ({e}); render to files with `deferred`")
    })?;
    let mut app = App {
        start: Some((recipe, args, script)),
        viewer: None,
        error: None,
    };
    event_loop.run_app(&mut app)?;
    match app.error {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

/// The viewer's settings as recipe keys: each long flag given and its values (none for a
/// switch), in the order of `deferred --help`.
#[derive(Clone, Debug, Default, PartialEq)]
struct Recipe(BTreeMap<String, Vec<String>>);

/// The flags of a frame sequence (`--frames` and those that need it): the viewer's clock and
/// camera replace them.
const SEQUENCE_KEYS: [&str; 8] = [
    "frames",
    "fps",
    "orbit",
    "light-orbit",
    "camera-key",
    "frame-exr",
    "frame-every",
    "warm-up",
];

/// Keys the renderer changes in place ([`Viewer::apply_live`]); any other key rebuilds.
const LIVE_KEYS: [&str; 13] = [
    "shading",
    "tile",
    "shadows",
    "ssaa",
    "adaptive",
    "ssaa-metric",
    "ssao",
    "ssao-kernel",
    "ssao-radius",
    "exposure",
    "auto-exposure",
    "tone-map",
    "ambient",
];

/// Keys that turn others off when set (`deferred` refuses them together).
const EXCLUSIVE: [(&str, &[&str]); 6] = [
    ("ray-shadows", &["shadows", "manylod-shadows"]),
    ("shadows", &["ray-shadows"]),
    ("manylod-shadows", &["ray-shadows"]),
    ("vpls", &["pbgi", "reflections"]),
    ("pbgi", &["vpls"]),
    ("reflections", &["vpls"]),
];

/// Keys that only mean something with another (`requires` in `deferred`'s flags): turning
/// that one off removes them too.
const DEPENDENTS: [(&str, &[&str]); 7] = [
    (
        "vpls",
        &[
            "pattern",
            "blur",
            "plain-blur",
            "interleaving",
            "no-interleave",
            "vpl-clamp",
            "near-field",
        ],
    ),
    ("ssaa", &["adaptive"]),
    ("adaptive", &["ssaa-metric"]),
    ("pbgi", &["pbgi-tile", "pbgi-epsilon", "pbgi-points"]),
    ("reflections", &["reflection-epsilon", "reflection-points"]),
    ("ssao", &["ssao-kernel", "ssao-radius"]),
    (
        "subdiv",
        &["subdiv-pixels", "subdiv-flat", "subdiv-show-levels"],
    ),
];

impl Recipe {
    /// The flags of `argv` (after [`crate::with_recipe`]) that were given, checked by parsing.
    fn from_argv(argv: &[OsString]) -> Result<Self> {
        let command = Args::command();
        let matches = command
            .clone()
            .try_get_matches_from(argv)
            .map_err(|e| anyhow!("{}", e.render()))?;
        let mut keys = BTreeMap::new();
        for arg in command.get_arguments() {
            let (Some(long), id) = (arg.get_long(), arg.get_id().as_str()) else {
                continue;
            };
            if long == "recipe"
                || matches.value_source(id) != Some(clap::parser::ValueSource::CommandLine)
            {
                continue;
            }
            let values = if matches!(arg.get_action(), clap::ArgAction::SetTrue) {
                Vec::new()
            } else {
                matches
                    .get_raw(id)
                    .map(|v| v.map(|s| s.to_string_lossy().into_owned()).collect())
                    .unwrap_or_default()
            };
            keys.insert(long.to_owned(), values);
        }
        Ok(Self(keys))
    }

    /// `deferred` with these flags.
    fn argv(&self) -> Vec<OsString> {
        let mut argv = vec![OsString::from("deferred")];
        for (key, values) in &self.0 {
            if values.is_empty() {
                argv.push(format!("--{key}").into());
            }
            // `--key=value`: a value starting with `-` (an eye at x < 0) is not a flag.
            for v in values {
                argv.push(format!("--{key}={v}").into());
            }
        }
        argv
    }

    /// The arguments these flags parse to (clap's message when they do not).
    fn args(&self) -> Result<Args> {
        Args::try_parse_from(self.argv()).map_err(|e| anyhow!("{}", e.render()))
    }

    /// The value of `key` (its first), if given.
    fn get(&self, key: &str) -> Option<&str> {
        self.0.get(key).and_then(|v| v.first()).map(String::as_str)
    }

    /// Whether `key` is given (a switch is on).
    fn has(&self, key: &str) -> bool {
        self.0.contains_key(key)
    }

    /// Sets `key` to `value` (`Some(vec![])` for a switch) or removes it.
    fn set(&mut self, key: &str, value: Option<Vec<String>>) {
        match value {
            Some(v) => self.0.insert(key.to_owned(), v),
            None => self.0.remove(key),
        };
    }

    /// The recipe as TOML for `deferred --recipe`: switches `true`, repeated flags arrays,
    /// values strings, file paths absolute (the recipe may be saved elsewhere).
    fn to_toml(&self) -> Result<String> {
        let mut table = toml::Table::new();
        for (key, values) in &self.0 {
            let absolute = |v: &String| -> Result<String> {
                if !matches!(key.as_str(), "scene" | "add-model" | "out")
                    || v.starts_with("fixtures:")
                {
                    return Ok(v.clone());
                }
                let (path, place) = match key.as_str() {
                    "add-model" => v
                        .rsplit_once('@')
                        .map_or((v.as_str(), None), |(p, a)| (p, Some(a))),
                    _ => (v.as_str(), None),
                };
                let path = std::path::absolute(path)
                    .with_context(|| format!("recipe key {key}: {path}"))?;
                let path = path.to_string_lossy();
                Ok(place.map_or_else(|| path.to_string(), |a| format!("{path}@{a}")))
            };
            let value = match &values[..] {
                [] => toml::Value::Boolean(true),
                [one] if !matches!(key.as_str(), "light" | "add-model" | "camera-key") => {
                    toml::Value::String(absolute(one)?)
                }
                many => toml::Value::Array(
                    many.iter()
                        .map(|v| absolute(v).map(toml::Value::String))
                        .collect::<Result<_>>()?,
                ),
            };
            table.insert(key.clone(), value);
        }
        Ok(format!(
            "# Saved by `deferred view`; render it with `deferred --recipe FILE`.\n{}",
            toml::to_string(&table)?
        ))
    }
}

/// A scripted session ([`HELP`]): commands and the line each came from.
struct Script {
    commands: VecDeque<(usize, Step)>,
    /// Frames left to wait, or to hold the held keys for.
    wait: u32,
    held: Vec<KeyCode>,
}

/// One script command.
#[derive(Clone, Debug, PartialEq)]
enum Step {
    Wait(u32),
    Hold(KeyCode, u32),
    Press(KeyCode),
    Drag(f32, f32),
    Wheel(f32),
    Click(String),
    Set(String, Option<String>),
    View(DebugView),
    Screenshot(String),
    CaptureWindow(String),
    Quit,
}

/// The most bytes a script may hold.
const SCRIPT_LIMIT: u64 = 1 << 20;

impl Script {
    fn read(path: &Path) -> Result<Self> {
        let fail = |e: String| anyhow!("script {}: {e}", path.display());
        let file = std::fs::File::open(path).map_err(|e| fail(e.to_string()))?;
        let mut text = String::new();
        std::io::Read::read_to_string(&mut std::io::Read::take(file, SCRIPT_LIMIT + 1), &mut text)
            .map_err(|e| fail(e.to_string()))?;
        if text.len() as u64 > SCRIPT_LIMIT {
            return Err(fail(format!("longer than {SCRIPT_LIMIT} bytes")));
        }
        Self::parse(&text).map_err(|e| fail(e.to_string()))
    }

    fn parse(text: &str) -> Result<Self> {
        let mut commands = VecDeque::new();
        for (i, line) in text.lines().enumerate() {
            let line = line.split('#').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            let (word, rest) = line.split_once(' ').unwrap_or((line, ""));
            let rest = rest.trim();
            let parts: Vec<&str> = rest.split_whitespace().collect();
            let at = |e: String| anyhow!("line {}: {e}", i + 1);
            let number = |s: Option<&&str>| -> Result<f32> {
                s.and_then(|s| s.parse::<f32>().ok())
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| at(format!("{word} needs a number: {line:?}")))
            };
            let frames = |s: Option<&&str>| -> Result<u32> {
                s.and_then(|s| s.parse::<u32>().ok())
                    .filter(|&n| n <= 100_000)
                    .ok_or_else(|| at(format!("{word} needs a frame count up to 100000: {line:?}")))
            };
            let name = |s: &str| -> Result<String> {
                let ok = !s.is_empty()
                    && s.chars()
                        .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_');
                if ok {
                    Ok(s.to_owned())
                } else {
                    Err(at(format!(
                        "{word} needs a file name of letters, digits, - and _: {s:?}"
                    )))
                }
            };
            let step = match word {
                "wait" => Step::Wait(frames(parts.first())?),
                "hold" => Step::Hold(
                    key_code(parts.first().copied().unwrap_or("")).map_err(at)?,
                    frames(parts.get(1))?,
                ),
                "press" => Step::Press(key_code(rest).map_err(at)?),
                "drag" => Step::Drag(number(parts.first())?, number(parts.get(1))?),
                "wheel" => Step::Wheel(number(parts.first())?),
                "click" => Step::Click(rest.trim_matches('"').to_owned()),
                "set" => {
                    let (key, value) = rest
                        .split_once(' ')
                        .ok_or_else(|| at(format!("set needs KEY VALUE: {line:?}")))?;
                    let value = value.trim().trim_matches('"');
                    Step::Set(key.to_owned(), (value != "off").then(|| value.to_owned()))
                }
                "view" => Step::View(DebugView::named(rest).map_err(at)?),
                "screenshot" => Step::Screenshot(name(rest)?),
                "capture-window" => Step::CaptureWindow(name(rest)?),
                "quit" => Step::Quit,
                other => {
                    return Err(at(format!(
                        "unknown command {other:?} (see deferred view --help)"
                    )));
                }
            };
            commands.push_back((i + 1, step));
        }
        Ok(Self {
            commands,
            wait: 0,
            held: Vec::new(),
        })
    }
}

/// A key by its script name.
fn key_code(name: &str) -> Result<KeyCode, String> {
    Ok(match name {
        "W" | "w" => KeyCode::KeyW,
        "A" | "a" => KeyCode::KeyA,
        "S" | "s" => KeyCode::KeyS,
        "D" | "d" => KeyCode::KeyD,
        "Q" | "q" => KeyCode::KeyQ,
        "E" | "e" => KeyCode::KeyE,
        "R" | "r" => KeyCode::KeyR,
        "O" | "o" => KeyCode::KeyO,
        "Shift" => KeyCode::ShiftLeft,
        "Space" => KeyCode::Space,
        "Period" | "." => KeyCode::Period,
        "F12" => KeyCode::F12,
        "Escape" => KeyCode::Escape,
        "1" => KeyCode::Digit1,
        "2" => KeyCode::Digit2,
        "3" => KeyCode::Digit3,
        "4" => KeyCode::Digit4,
        "5" => KeyCode::Digit5,
        "6" => KeyCode::Digit6,
        "7" => KeyCode::Digit7,
        "8" => KeyCode::Digit8,
        "9" => KeyCode::Digit9,
        other => return Err(format!("unknown key {other:?}")),
    })
}

/// What the image area shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum DebugView {
    /// The frame after the output transform.
    Final,
    /// A G-buffer channel.
    Depth,
    Normal,
    Albedo,
    Material,
    /// The interleaved split normals (Segovia 2006 §3.1's split buffer).
    SplitBuffer,
    /// The discontinuity buffer (§3.3).
    Discontinuities,
    /// Lights per tile of the light accumulation.
    LightCounts,
    /// Samples per pixel of adaptive supersampling.
    SsaaSamples,
    /// The VPL shadow-map atlas (ManyLoD, ISM or SSM).
    VplAtlas,
}

impl DebugView {
    const ALL: [DebugView; 10] = [
        Self::Final,
        Self::Depth,
        Self::Normal,
        Self::Albedo,
        Self::Material,
        Self::SplitBuffer,
        Self::Discontinuities,
        Self::LightCounts,
        Self::SsaaSamples,
        Self::VplAtlas,
    ];

    fn name(self) -> &'static str {
        match self {
            Self::Final => "final",
            Self::Depth => "depth",
            Self::Normal => "normal",
            Self::Albedo => "albedo",
            Self::Material => "material",
            Self::SplitBuffer => "split-buffer",
            Self::Discontinuities => "discontinuities",
            Self::LightCounts => "light-counts",
            Self::SsaaSamples => "ssaa-samples",
            Self::VplAtlas => "vpl-atlas",
        }
    }

    fn named(name: &str) -> Result<Self, String> {
        Self::ALL
            .into_iter()
            .find(|v| v.name() == name)
            .ok_or_else(|| {
                let names: Vec<&str> = Self::ALL.iter().map(|v| v.name()).collect();
                format!("unknown view {name:?} ({})", names.join(", "))
            })
    }

    /// The view's image, read back from the last frame (`None` where the frame has no such
    /// stage, with the reason).
    fn image(
        self,
        gpu: &gpu::Gpu,
        live: &Live,
    ) -> Result<Result<gbuffer::Image<[f32; 4]>, &'static str>> {
        let (d, q) = (&gpu.device, &gpu.queue);
        let r = &live.renderer;
        Ok(match self {
            Self::Final => Err("the final frame is shown on the GPU"),
            Self::Depth | Self::Normal | Self::Albedo | Self::Material => {
                let gb = r.targets().read(d, q)?;
                let channel = match self {
                    Self::Depth => crate::GBufferChannel::Depth,
                    Self::Normal => crate::GBufferChannel::Normal,
                    Self::Albedo => crate::GBufferChannel::Albedo,
                    _ => crate::GBufferChannel::Material,
                };
                Ok(crate::gbuffer_channel(&gb, channel))
            }
            Self::SplitBuffer | Self::Discontinuities => {
                let Some(stages) = r.indirect().map(|s| s.read(d, q)).transpose()? else {
                    return Ok(Err("no indirect light (add VPLs)"));
                };
                let image = if self == Self::SplitBuffer {
                    stages.split_normal.as_ref().map(crate::normal_image)
                } else {
                    stages
                        .discontinuities
                        .as_ref()
                        .map(crate::discontinuity_image)
                };
                image.ok_or("the fused interleaving keeps no such buffer (pick tiled, one-pass or two-pass)")
            }
            Self::LightCounts => {
                let m = r.ssaa().map_or(1, |c| c.m);
                let (w, h) = r.size();
                match r.light_counts(d, q)? {
                    Some(counts) => {
                        let max = counts.iter().copied().max().unwrap_or(0).max(1);
                        Ok(tiled_shading::heatmap(
                            &counts,
                            &live.setup.shading,
                            w * m,
                            h * m,
                            max,
                        ))
                    }
                    None => Err("brute force keeps no per-tile lists"),
                }
            }
            Self::SsaaSamples => match (r.ssaa(), r.ssaa_counts(d, q)?) {
                (Some(config), Some(counts)) => Ok(adaptive_ssaa::cpu::sample_heatmap(
                    &counts,
                    config.samples(),
                )),
                _ => Err("no supersampling"),
            },
            Self::VplAtlas => match r.vpl_shadows() {
                Some(s) if s.mode() != instant_radiosity::shadows::VplShadows::Rays => {
                    Ok(crate::atlas_image(gpu, s)?)
                }
                _ => Err("no VPL shadow maps"),
            },
        })
    }
}

/// Everything built from one recipe: its arguments, the set-up and the renderer.
struct Live {
    args: Args,
    setup: Setup,
    renderer: pipeline::gpu::GpuRenderer,
    posed: crate::Posed,
    /// Whether frames pose the scene (it has an animation).
    animated: bool,
}

impl Live {
    fn build(args: Args, gpu: &gpu::Gpu) -> Result<Self> {
        let setup = crate::prepare(&args)?;
        let (mut renderer, _) = crate::gpu_renderer(&args, gpu, &setup)?;
        let animated = setup.scene.rig.is_some();
        if animated {
            renderer.set_animation(&gpu.device, &gpu.queue, setup.scene.rig.as_ref())?;
        }
        let posed = crate::Posed::new(&setup, false);
        Ok(Self {
            args,
            setup,
            renderer,
            posed,
            animated,
        })
    }

    /// Applies the [`LIVE_KEYS`] of `args` to the renderer in place.
    fn apply_live(&mut self, args: Args, gpu: &gpu::Gpu) -> Result<()> {
        let (d, q) = (&gpu.device, &gpu.queue);
        let shading = pipeline::ShadingConfig {
            method: args.shading,
            tile_size: args.tile,
            search: args.light_search,
        };
        shading.validate()?;
        let shadows = args
            .shadows
            .map(|resolution| tiled_shading::shadows::ShadowMapConfig {
                resolution,
                ..Default::default()
            });
        let ssaa = crate::ssaa_config(&args)?;
        let ssao = crate::ssao_setting(&args, &self.setup.scene)?;
        let output = crate::output_transform(&args)?;
        let r = &mut self.renderer;
        // Dithering first where asked (the light pre-pass refuses blended surfaces drawn
        // forward), forward after the method that draws them.
        if args.blend == gbuffer::gpu::BlendedSurfaces::Dithered {
            r.set_blended(d, q, args.blend)?;
            r.set_shading(d, q, &shading)?;
        } else {
            r.set_shading(d, q, &shading)?;
            r.set_blended(d, q, args.blend)?;
        }
        r.set_shadows(d, q, shadows.as_ref())?;
        r.set_ssaa(d, q, ssaa.as_ref())?;
        r.set_ssao(d, q, ssao.as_ref().map(|(c, e)| (c, *e)))?;
        r.set_output(d, Some(output))?;
        if let Some(ambient) = args.ambient {
            r.set_ambient(q, ambient);
        }
        self.setup.shading = shading;
        self.setup.shadow_config = shadows;
        self.setup.output = output;
        self.args = args;
        Ok(())
    }
}

/// The fly / orbit camera: position and view direction about the scene camera's up axis.
#[derive(Clone, Copy, Debug)]
struct FlyCamera {
    eye: Vec3,
    forward: Vec3,
    /// Distance to the target (the orbit centre).
    distance: f32,
    up: Vec3,
    fov_degrees: f32,
    /// World units a second.
    speed: f32,
    orbit: bool,
}

/// Radians of turn per pixel of drag.
const TURN_PER_PIXEL: f32 = 0.004;

impl FlyCamera {
    fn new(camera: &scene::Camera, speed: f32, orbit: bool) -> Self {
        let view = camera.target - camera.eye;
        Self {
            eye: camera.eye,
            forward: view.normalize_or(Vec3::NEG_Z),
            distance: view.length().max(1e-3),
            up: camera.up.normalize_or(Vec3::Y),
            fov_degrees: camera.fov_y.to_degrees(),
            speed,
            orbit,
        }
    }

    fn target(&self) -> Vec3 {
        self.eye + self.forward * self.distance
    }

    /// Turns the view by a drag of (`dx`, `dy`) pixels: about the up axis, then about the
    /// right axis (stopping short of the poles); in orbit mode the eye circles the target.
    fn turn(&mut self, dx: f32, dy: f32) {
        let target = self.target();
        let yawed = Quat::from_axis_angle(self.up, -dx * TURN_PER_PIXEL) * self.forward;
        let right = yawed.cross(self.up).normalize_or_zero();
        let pitched = Quat::from_axis_angle(right, -dy * TURN_PER_PIXEL) * yawed;
        self.forward = if pitched.dot(self.up).abs() < 0.995 {
            pitched.normalize()
        } else {
            yawed.normalize()
        };
        if self.orbit {
            self.eye = target - self.forward * self.distance;
        }
    }

    /// Wheel steps: flying speed (×1.2 a step), or in orbit mode the distance (÷1.2 a step).
    fn wheel(&mut self, steps: f32) {
        if self.orbit {
            let target = self.target();
            self.distance = (self.distance / 1.2f32.powf(steps)).max(1e-3);
            self.eye = target - self.forward * self.distance;
        } else {
            self.speed *= 1.2f32.powf(steps);
        }
    }

    /// Moves by the held keys over `dt` seconds.
    fn fly(&mut self, held: &[KeyCode], dt: f32) {
        let right = self.forward.cross(self.up).normalize_or_zero();
        let mut step = Vec3::ZERO;
        for key in held {
            step += match key {
                KeyCode::KeyW => self.forward,
                KeyCode::KeyS => -self.forward,
                KeyCode::KeyD => right,
                KeyCode::KeyA => -right,
                KeyCode::KeyE => self.up,
                KeyCode::KeyQ => -self.up,
                _ => Vec3::ZERO,
            };
        }
        let fast = held.contains(&KeyCode::ShiftLeft) || held.contains(&KeyCode::ShiftRight);
        let speed = self.speed * if fast { 4.0 } else { 1.0 };
        self.eye += step.normalize_or_zero() * speed * dt;
    }

    /// The recipe's camera keys for this view (`eye`, `target`, `fov`), as `deferred` reads
    /// them back to the same floats.
    fn keys(&self) -> [(&'static str, String); 3] {
        let v = |p: Vec3| format!("{},{},{}", p.x, p.y, p.z);
        [
            ("eye", v(self.eye)),
            ("target", v(self.target())),
            ("fov", self.fov_degrees.to_string()),
        ]
    }
}

/// A selectable camera of the scene.
struct NamedCamera {
    name: &'static str,
    camera: scene::Camera,
}

/// The event loop's handler: builds the viewer when the window can be made.
struct App {
    start: Option<(Recipe, Args, Option<Script>)>,
    viewer: Option<Viewer>,
    error: Option<anyhow::Error>,
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        let Some((recipe, args, script)) = self.start.take() else {
            return;
        };
        match Viewer::new(event_loop, recipe, args, script) {
            Ok(v) => {
                v.window.request_redraw();
                self.viewer = Some(v);
            }
            Err(e) => {
                self.error = Some(e);
                event_loop.exit();
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let Some(viewer) = &mut self.viewer else {
            return;
        };
        match viewer.event(event) {
            Ok(true) => {}
            Ok(false) => event_loop.exit(),
            Err(e) => {
                self.error = Some(e);
                event_loop.exit();
            }
        }
    }
}

/// What the panel or a script asks for after a frame.
#[derive(Clone, Debug, PartialEq)]
enum Action {
    /// Recipe edits: key and value (`Some(vec![])` a switch, `None` removes it).
    Edit(Vec<(String, Option<Vec<String>>)>),
    Camera(usize),
    Screenshot(Option<String>),
    SaveRecipe,
    CaptureWindow(String),
    Quit,
}

/// The most frames of pass timings the graph keeps.
const TIMING_HISTORY: usize = 240;

/// The panel's width in points.
const PANEL_WIDTH: f32 = 330.0;

/// The window, its device and surface, the egui state and the live frame.
struct Viewer {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    surface_config: wgpu::SurfaceConfiguration,
    gpu: gpu::Gpu,
    egui_state: egui_winit::State,
    egui_renderer: egui_wgpu::Renderer,
    present: Present,
    recipe: Recipe,
    live: Live,
    camera: FlyCamera,
    cameras: Vec<NamedCamera>,
    /// Whether the camera follows the scene's animated camera.
    follow_rig_camera: bool,
    time: f32,
    playing: bool,
    last_frame: std::time::Instant,
    held: Vec<KeyCode>,
    dragging: bool,
    cursor: Option<(f32, f32)>,
    pending: Vec<Action>,
    script: Option<Script>,
    view: DebugView,
    /// The debug view's image as an egui texture.
    view_texture: Option<egui::TextureHandle>,
    view_note: Option<String>,
    timings: VecDeque<Vec<gpu::PassTime>>,
    message: Option<String>,
    /// Panel widgets by label, where the last frame drew them (for scripted clicks).
    widgets: HashMap<String, egui::Rect>,
    /// A scripted click's release, sent the frame after its press.
    release: Option<egui::Pos2>,
    /// The image area in points (where drags look around).
    image_rect: egui::Rect,
}

/// The present kernel ([`present.wgsl`]) and its 8-bit sRGB target, shown by egui.
struct Present {
    pipeline: wgpu::ComputePipeline,
    layout: gpu::kernel::Layout,
    group: wgpu::BindGroup,
    shown: wgpu::Texture,
    texture_id: egui::TextureId,
}

impl Present {
    fn new(
        gpu: &gpu::Gpu,
        egui_renderer: &mut egui_wgpu::Renderer,
        renderer: &pipeline::gpu::GpuRenderer,
    ) -> Result<Self> {
        let d = &gpu.device;
        let module = d.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("viewer present"),
            source: wgpu::ShaderSource::Wgsl(include_str!("present.wgsl").into()),
        });
        let layout = gpu::kernel::Layout::compute(
            d,
            "viewer present",
            &[
                gpu::kernel::Binding::TextureUnfilterable,
                gpu::kernel::Binding::StorageTexture(wgpu::TextureFormat::Rgba8Unorm),
            ],
        );
        let pipeline = gpu::kernel::pipeline(d, &module, "present_main", &[&layout], &[]);
        let (group, shown) = Self::bind(gpu, &layout, renderer)?;
        let texture_id = egui_renderer.register_native_texture(
            d,
            &shown.create_view(&Default::default()),
            wgpu::FilterMode::Nearest,
        );
        Ok(Self {
            pipeline,
            layout,
            group,
            shown,
            texture_id,
        })
    }

    fn bind(
        gpu: &gpu::Gpu,
        layout: &gpu::kernel::Layout,
        renderer: &pipeline::gpu::GpuRenderer,
    ) -> Result<(wgpu::BindGroup, wgpu::Texture)> {
        let display = renderer
            .display()
            .context("the renderer has an output stage")?;
        let shown = gpu::transfer::texture_2d(
            &gpu.device,
            "viewer shown",
            display.width(),
            display.height(),
            wgpu::TextureFormat::Rgba8Unorm,
            gpu::transfer::STORAGE_OUTPUT,
        );
        let group = layout.bind(
            &gpu.device,
            &[
                wgpu::BindingResource::TextureView(&display.create_view(&Default::default())),
                wgpu::BindingResource::TextureView(&shown.create_view(&Default::default())),
            ],
        );
        Ok((group, shown))
    }

    /// Rebinds to a new renderer's display (after a rebuild or a resize).
    fn rebind(
        &mut self,
        gpu: &gpu::Gpu,
        egui_renderer: &mut egui_wgpu::Renderer,
        renderer: &pipeline::gpu::GpuRenderer,
    ) -> Result<()> {
        let (group, shown) = Self::bind(gpu, &self.layout, renderer)?;
        egui_renderer.update_egui_texture_from_wgpu_texture(
            &gpu.device,
            &shown.create_view(&Default::default()),
            wgpu::FilterMode::Nearest,
            self.texture_id,
        );
        (self.group, self.shown) = (group, shown);
        Ok(())
    }

    fn encode(&self, encoder: &mut wgpu::CommandEncoder) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("viewer present"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.group, &[]);
        pass.dispatch_workgroups(
            self.shown.width().div_ceil(8),
            self.shown.height().div_ceil(8),
            1,
        );
    }
}

impl Viewer {
    fn new(
        event_loop: &ActiveEventLoop,
        recipe: Recipe,
        args: Args,
        script: Option<Script>,
    ) -> Result<Self> {
        let (w, h) = args.size;
        let title = match &args.scene {
            Some(p) => format!("deferred view: {}", p.display()),
            None => format!("deferred view: {}", args.builtin),
        };
        let window = Arc::new(
            event_loop
                .create_window(
                    Window::default_attributes()
                        .with_title(title)
                        .with_inner_size(winit::dpi::PhysicalSize::new(
                            w + PANEL_WIDTH as u32 + 16,
                            h.max(640) + 16,
                        )),
                )
                .context("deferred view: cannot open a window")?,
        );
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_with_display_handle_from_env(
                Box::new(event_loop.owned_display_handle()),
            ));
        let surface = instance
            .create_surface(window.clone())
            .context("deferred view: cannot make a surface for the window")?;
        let gpu = gpu::Gpu::for_surface(instance, &surface)
            .context("deferred view: no adapter can present to the window")?;
        let size = window.inner_size();
        let caps = surface.get_capabilities(&gpu.adapter);
        // egui blends in sRGB-encoded values, and the shown image holds them already: a
        // non-sRGB format passes both through unchanged.
        let format = caps
            .formats
            .iter()
            .copied()
            .find(|f| !f.is_srgb())
            .or_else(|| caps.formats.first().copied())
            .context("deferred view: the surface has no format")?;
        let mut usage = wgpu::TextureUsages::RENDER_ATTACHMENT;
        if caps.usages.contains(wgpu::TextureUsages::COPY_SRC) {
            usage |= wgpu::TextureUsages::COPY_SRC;
        }
        let surface_config = wgpu::SurfaceConfiguration {
            usage,
            format,
            width: size.width.max(1),
            height: size.height.max(1),
            present_mode: wgpu::PresentMode::AutoVsync,
            desired_maximum_frame_latency: 2,
            alpha_mode: caps
                .alpha_modes
                .first()
                .copied()
                .unwrap_or(wgpu::CompositeAlphaMode::Auto),
            view_formats: Vec::new(),
            color_space: wgpu::SurfaceColorSpace::Auto,
        };
        surface.configure(&gpu.device, &surface_config);
        eprintln!("deferred view: {}", gpu.describe());

        let live = Live::build(args, &gpu)?;
        let egui_ctx = egui::Context::default();
        let egui_state = egui_winit::State::new(
            egui_ctx,
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            Some(gpu.device.limits().max_texture_dimension_2d as usize),
        );
        // No dithering: the image shows render.png's exact bytes.
        let mut egui_renderer = egui_wgpu::Renderer::new(
            &gpu.device,
            format,
            egui_wgpu::RendererOptions {
                dithering: false,
                ..Default::default()
            },
        );
        let present = Present::new(&gpu, &mut egui_renderer, &live.renderer)?;
        let cameras = cameras(&live);
        let speed = 0.25 * live.setup.scene.bounds().diagonal().max(1e-3);
        let camera = FlyCamera::new(&live.setup.camera, speed, false);
        let time = live.args.time;
        let playing = live.setup.scene.rig.is_some() && script.is_none();
        Ok(Self {
            window,
            surface,
            surface_config,
            gpu,
            egui_state,
            egui_renderer,
            present,
            recipe,
            live,
            camera,
            cameras,
            follow_rig_camera: false,
            time,
            playing,
            last_frame: std::time::Instant::now(),
            held: Vec::new(),
            dragging: false,
            cursor: None,
            pending: Vec::new(),
            script,
            view: DebugView::Final,
            view_texture: None,
            view_note: None,
            timings: VecDeque::new(),
            message: None,
            widgets: HashMap::new(),
            release: None,
            image_rect: egui::Rect::NOTHING,
        })
    }

    /// Handles a window event; `false` closes the viewer.
    fn event(&mut self, event: WindowEvent) -> Result<bool> {
        let response = self.egui_state.on_window_event(&self.window, &event);
        match event {
            WindowEvent::CloseRequested => return Ok(false),
            WindowEvent::Resized(size) => {
                self.surface_config.width = size.width.max(1);
                self.surface_config.height = size.height.max(1);
                self.surface
                    .configure(&self.gpu.device, &self.surface_config);
            }
            WindowEvent::RedrawRequested => {
                let go_on = self.frame()?;
                self.window.request_redraw();
                return Ok(go_on);
            }
            WindowEvent::KeyboardInput { event, .. } if !response.consumed => {
                if let PhysicalKey::Code(code) = event.physical_key {
                    let pressed = event.state == ElementState::Pressed;
                    if !event.repeat && !self.key(code, pressed) {
                        return Ok(false);
                    }
                }
            }
            WindowEvent::MouseInput { state, button, .. } => {
                let over_image = self
                    .cursor
                    .is_some_and(|(x, y)| self.image_rect.contains(egui::pos2(x, y)));
                if matches!(button, MouseButton::Left | MouseButton::Right) {
                    self.dragging = state == ElementState::Pressed
                        && (over_image || button == MouseButton::Right)
                        && !response.consumed;
                }
            }
            WindowEvent::CursorMoved { position, .. } => {
                let scale = self.window.scale_factor() as f32;
                let now = (position.x as f32 / scale, position.y as f32 / scale);
                if let (true, Some(before)) = (self.dragging, self.cursor) {
                    self.look((now.0 - before.0) * scale, (now.1 - before.1) * scale);
                }
                self.cursor = Some(now);
            }
            WindowEvent::MouseWheel { delta, .. } if !response.consumed => {
                let steps = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                self.camera.wheel(steps);
            }
            _ => {}
        }
        Ok(true)
    }

    fn look(&mut self, dx: f32, dy: f32) {
        self.follow_rig_camera = false;
        self.camera.turn(dx, dy);
    }

    /// A key going down or up (from the window or a script); `false` quits.
    fn key(&mut self, code: KeyCode, pressed: bool) -> bool {
        if !pressed {
            self.held.retain(|&k| k != code);
            return true;
        }
        match code {
            KeyCode::Escape => return false,
            KeyCode::KeyO => self.camera.orbit = !self.camera.orbit,
            KeyCode::KeyR => self.pending.push(Action::Camera(0)),
            KeyCode::Space => self.playing = !self.playing,
            KeyCode::Period => {
                self.playing = false;
                self.time += 1.0 / 24.0;
            }
            KeyCode::F12 => self.pending.push(Action::Screenshot(None)),
            KeyCode::Digit1
            | KeyCode::Digit2
            | KeyCode::Digit3
            | KeyCode::Digit4
            | KeyCode::Digit5
            | KeyCode::Digit6
            | KeyCode::Digit7
            | KeyCode::Digit8
            | KeyCode::Digit9 => {
                let n = code as usize - KeyCode::Digit1 as usize;
                self.pending.push(Action::Camera(n));
            }
            _ => {
                if !self.held.contains(&code) {
                    self.held.push(code);
                }
                if matches!(
                    code,
                    KeyCode::KeyW
                        | KeyCode::KeyA
                        | KeyCode::KeyS
                        | KeyCode::KeyD
                        | KeyCode::KeyQ
                        | KeyCode::KeyE
                ) {
                    self.follow_rig_camera = false;
                }
            }
        }
        true
    }

    /// Runs the script's commands due before this frame; `false` quits.
    fn run_script(&mut self) -> Result<bool> {
        let Some(mut script) = self.script.take() else {
            return Ok(true);
        };
        let mut go_on = true;
        if script.wait > 0 {
            script.wait -= 1;
        } else {
            for key in std::mem::take(&mut script.held) {
                self.key(key, false);
            }
            while let Some((line, step)) = script.commands.pop_front() {
                let at = |e: anyhow::Error| e.context(format!("script line {line}"));
                match step {
                    Step::Wait(n) => {
                        script.wait = n.saturating_sub(1);
                        break;
                    }
                    Step::Hold(key, n) => {
                        self.key(key, true);
                        script.held.push(key);
                        script.wait = n.saturating_sub(1);
                        break;
                    }
                    Step::Press(key) => {
                        go_on &= self.key(key, true);
                        self.key(key, false);
                    }
                    Step::Drag(dx, dy) => self.look(dx, dy),
                    Step::Wheel(n) => self.camera.wheel(n),
                    Step::Click(label) => {
                        let rect = self.widgets.get(&label).copied().ok_or_else(|| {
                            let mut known: Vec<&String> = self.widgets.keys().collect();
                            known.sort();
                            at(anyhow!(
                                "no panel widget labelled {label:?} (there are {known:?})"
                            ))
                        })?;
                        let pos = rect.center();
                        let input = self.egui_state.egui_input_mut();
                        input.events.push(egui::Event::PointerMoved(pos));
                        input.events.push(egui::Event::PointerButton {
                            pos,
                            button: egui::PointerButton::Primary,
                            pressed: true,
                            modifiers: Default::default(),
                        });
                        self.release = Some(pos);
                        // The press is seen next frame, the release the frame after.
                        script.wait = 2;
                        break;
                    }
                    Step::Set(key, value) => {
                        let value = value.map(|v| if v == "on" { Vec::new() } else { vec![v] });
                        self.pending.push(Action::Edit(vec![(key, value)]));
                    }
                    Step::View(view) => self.view = view,
                    // Pictures end the frame's commands: they show this frame as set so far.
                    Step::Screenshot(name) => {
                        self.pending.push(Action::Screenshot(Some(name)));
                        break;
                    }
                    Step::CaptureWindow(name) => {
                        self.pending.push(Action::CaptureWindow(name));
                        break;
                    }
                    Step::Quit => self.pending.push(Action::Quit),
                }
            }
        }
        self.script = Some(script);
        Ok(go_on)
    }

    /// One frame: script, camera, animation, the renderer's frame, the panel, present; then
    /// the actions the panel or the script asked for. `false` closes the viewer.
    fn frame(&mut self) -> Result<bool> {
        if let Some(pos) = self.release.take() {
            self.egui_state
                .egui_input_mut()
                .events
                .push(egui::Event::PointerButton {
                    pos,
                    button: egui::PointerButton::Primary,
                    pressed: false,
                    modifiers: Default::default(),
                });
        }
        if !self.run_script()? {
            return Ok(false);
        }
        let now = std::time::Instant::now();
        let dt = if self.script.is_some() {
            1.0 / 30.0
        } else {
            now.duration_since(self.last_frame).as_secs_f32().min(0.1)
        };
        self.last_frame = now;
        self.camera.fly(&self.held, dt);
        if self.playing {
            self.time += dt;
        }
        self.render_frame()?;
        self.read_view()?;
        self.draw_panel_and_present()?;
        let mut go_on = true;
        for action in std::mem::take(&mut self.pending) {
            go_on &= self.act(action)?;
        }
        Ok(go_on)
    }

    /// The camera the frame renders: the fly camera aimed as `deferred --eye --target --fov`
    /// aims it (so a saved recipe renders the same view).
    fn render_camera(&self) -> Result<scene::Camera> {
        let base = &self.live.setup.camera;
        let camera = crate::aimed(
            *base,
            Some(self.camera.eye),
            Some(self.camera.target()),
            Some(self.camera.fov_degrees),
            self.live.setup.scene.bounds(),
        );
        gbuffer::validate_camera(&camera).context("the viewer's camera")?;
        Ok(camera)
    }

    fn render_frame(&mut self) -> Result<()> {
        let (d, q) = (&self.gpu.device, &self.gpu.queue);
        let mut camera = self.render_camera()?;
        let live = &mut self.live;
        if live.animated {
            let follow = self.follow_rig_camera;
            let rig = live.setup.scene.rig.clone();
            camera = crate::pose_frame(
                &live.args,
                &self.gpu,
                &mut live.renderer,
                &live.setup,
                &mut live.posed,
                self.time,
                |pose| match (follow, rig.as_ref(), pose) {
                    (true, Some(rig), Some(pose)) => rig.camera(pose).unwrap_or(camera),
                    _ => camera,
                },
            )?;
        }
        live.renderer.set_camera(q, &camera)?;
        live.renderer.follow_visibility_split(d)?;
        let mut encoder = d.create_command_encoder(&Default::default());
        live.renderer.encode(&mut encoder);
        self.present.encode(&mut encoder);
        q.submit([encoder.finish()]);
        let passes = live.renderer.pass_times(d, q)?;
        if live.renderer.check_pbgi(d, q)? {
            self.message = Some("point-based GI's cut lists grew to hold the cut".into());
        }
        if live.renderer.check_reflections(d, q)? {
            self.message = Some("the reflection maps' cut lists grew to hold the cut".into());
        }
        if live.renderer.check_visibility(d, q)? {
            self.message = Some("the visibility buffer's lists grew to hold every triangle".into());
        }
        if self.timings.len() == TIMING_HISTORY {
            self.timings.pop_front();
        }
        self.timings.push_back(passes);
        Ok(())
    }

    /// Reads the debug view's image back into an egui texture.
    fn read_view(&mut self) -> Result<()> {
        self.view_note = None;
        if self.view == DebugView::Final {
            self.view_texture = None;
            return Ok(());
        }
        match self.view.image(&self.gpu, &self.live)? {
            Ok(image) => {
                let rgb = image.to_srgb8();
                let color = egui::ColorImage::from_rgb(
                    [image.width() as usize, image.height() as usize],
                    &rgb,
                );
                let ctx = self.egui_state.egui_ctx().clone();
                match &mut self.view_texture {
                    Some(t) => t.set(color, egui::TextureOptions::NEAREST),
                    None => {
                        self.view_texture = Some(ctx.load_texture(
                            "debug view",
                            color,
                            egui::TextureOptions::NEAREST,
                        ));
                    }
                }
            }
            Err(why) => {
                self.view_texture = None;
                self.view_note = Some(why.to_owned());
            }
        }
        Ok(())
    }

    fn draw_panel_and_present(&mut self) -> Result<()> {
        let input = self.egui_state.take_egui_input(&self.window);
        let ctx = self.egui_state.egui_ctx().clone();
        let view = self.view;
        let mut panel = Panel {
            recipe: &self.recipe,
            args: &self.live.args,
            gpu: &self.gpu,
            camera: &mut self.camera,
            cameras: &self.cameras,
            time: &mut self.time,
            playing: &mut self.playing,
            animated: self.live.setup.scene.rig.is_some(),
            view: &mut self.view,
            ssao_radius: crate::ssao_setting(&self.live.args, &self.live.setup.scene)
                .ok()
                .flatten()
                .map(|(c, _)| c.ao.radius),
            timings: &self.timings,
            message: self.message.as_deref(),
            actions: Vec::new(),
            widgets: HashMap::new(),
        };
        let image = match (&self.view_texture, view) {
            (Some(t), _) => Some(egui::load::SizedTexture::from_handle(t)),
            (None, DebugView::Final) => {
                let s = &self.present.shown;
                Some(egui::load::SizedTexture::new(
                    self.present.texture_id,
                    egui::vec2(s.width() as f32, s.height() as f32),
                ))
            }
            (None, _) => None,
        };
        let note = self.view_note.clone();
        let mut image_rect = egui::Rect::NOTHING;
        let output = ctx.run_ui(input, |ui| {
            egui::Panel::left("settings")
                .exact_size(PANEL_WIDTH)
                .show(ui, |ui| {
                    egui::ScrollArea::vertical().show(ui, |ui| panel.show(ui));
                });
            egui::CentralPanel::default().show(ui, |ui| {
                image_rect = ui.max_rect();
                match image {
                    Some(texture) => {
                        // Pixels 1:1 where they fit, else scaled down keeping the aspect.
                        let ppp = ui.ctx().pixels_per_point();
                        let natural = texture.size / ppp;
                        let fit = (ui.available_size() / natural).min_elem().min(1.0);
                        ui.add(egui::Image::from_texture(texture).fit_to_exact_size(natural * fit));
                    }
                    None => {
                        ui.label(note.as_deref().unwrap_or("no image"));
                    }
                }
            });
        });
        let Panel {
            actions, widgets, ..
        } = panel;
        self.pending.extend(actions);
        self.widgets = widgets;
        self.image_rect = image_rect;
        self.egui_state
            .handle_platform_output(&self.window, output.platform_output);
        let jobs = ctx.tessellate(output.shapes, output.pixels_per_point);
        let (d, q) = (&self.gpu.device, &self.gpu.queue);
        for (id, deltas) in &output.textures_delta.set {
            for delta in deltas {
                self.egui_renderer.update_texture(d, q, *id, delta);
            }
        }
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [self.surface_config.width, self.surface_config.height],
            pixels_per_point: output.pixels_per_point,
        };
        let frame = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            wgpu::CurrentSurfaceTexture::Timeout | wgpu::CurrentSurfaceTexture::Occluded => {
                return Ok(());
            }
            _ => {
                self.surface.configure(d, &self.surface_config);
                return Ok(());
            }
        };
        let target = frame.texture.create_view(&Default::default());
        let mut encoder = d.create_command_encoder(&Default::default());
        let mut buffers = self
            .egui_renderer
            .update_buffers(d, q, &mut encoder, &jobs, &screen);
        {
            let pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("viewer panel"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &target,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                ..Default::default()
            });
            self.egui_renderer
                .render(&mut pass.forget_lifetime(), &jobs, &screen);
        }
        let capture = self.pending.iter().find_map(|a| match a {
            Action::CaptureWindow(name) => Some((name.clone(), frame.texture.clone())),
            _ => None,
        });
        buffers.push(encoder.finish());
        q.submit(buffers);
        if let Some((name, texture)) = capture {
            self.capture_window(&name, &texture)?;
        }
        self.window.pre_present_notify();
        q.present(frame);
        for id in &output.textures_delta.free {
            self.egui_renderer.free_texture(id);
        }
        Ok(())
    }

    /// Writes the window's pixels (the surface texture before presenting) as OUT/NAME.png.
    fn capture_window(&self, name: &str, texture: &wgpu::Texture) -> Result<()> {
        if !texture.usage().contains(wgpu::TextureUsages::COPY_SRC) {
            bail!("capture-window: this surface cannot be copied from (no COPY_SRC)");
        }
        let (d, q) = (&self.gpu.device, &self.gpu.queue);
        let bytes = gpu::transfer::read_texture(d, q, texture, wgpu::TextureAspect::All)?;
        let bgra = matches!(
            texture.format(),
            wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb
        );
        let rgb: Vec<u8> = bytes
            .chunks_exact(4)
            .flat_map(|p| {
                if bgra {
                    [p[2], p[1], p[0]]
                } else {
                    [p[0], p[1], p[2]]
                }
            })
            .collect();
        let path = self.out_dir()?.join(format!("{name}.png"));
        gbuffer::write_atomically(&path, |tmp| {
            image::save_buffer_with_format(
                tmp,
                &rgb,
                texture.width(),
                texture.height(),
                image::ExtendedColorType::Rgb8,
                image::ImageFormat::Png,
            )
            .map_err(|e| e.to_string())
        })?;
        eprintln!("wrote {}", path.display());
        Ok(())
    }

    fn out_dir(&self) -> Result<PathBuf> {
        let dir = self.live.args.out.clone();
        std::fs::create_dir_all(&dir)
            .with_context(|| format!("cannot create {}", dir.display()))?;
        Ok(dir)
    }

    /// The recipe of what is on screen: the settings and the camera (and clock).
    fn current_recipe(&self) -> Recipe {
        let mut recipe = self.recipe.clone();
        for (key, value) in self.camera.keys() {
            recipe.set(key, Some(vec![value]));
        }
        recipe.set(
            "time",
            (self.time != 0.0).then(|| vec![self.time.to_string()]),
        );
        recipe
    }

    /// `OUT/STEM-N` with the first N that names no file yet, or `OUT/NAME`.
    fn numbered(&self, stem: &str, name: Option<String>) -> Result<PathBuf> {
        let dir = self.out_dir()?;
        if let Some(name) = name {
            return Ok(dir.join(name));
        }
        (1..100_000)
            .map(|n| dir.join(format!("{stem}-{n:03}")))
            .find(|p| !p.with_extension("png").exists() && !p.with_extension("toml").exists())
            .context("no free file name")
    }

    fn act(&mut self, action: Action) -> Result<bool> {
        match action {
            Action::Edit(edits) => self.edit(edits)?,
            Action::Camera(n) => match self.cameras.get(n) {
                Some(c) => {
                    let (speed, orbit) = (self.camera.speed, self.camera.orbit);
                    self.camera = FlyCamera::new(&c.camera, speed, orbit);
                    self.follow_rig_camera = c.name == "animated";
                }
                None => self.message = Some(format!("no camera {}", n + 1)),
            },
            Action::Screenshot(name) => {
                let stem = self.numbered("screenshot", name)?;
                let (d, q) = (&self.gpu.device, &self.gpu.queue);
                let r = &self.live.renderer;
                let display = pipeline::gpu::read_display(
                    d,
                    q,
                    r.display().context("the renderer has an output stage")?,
                )?;
                let radiance = pipeline::gpu::read_radiance(d, q, r.output())?;
                display.write_png(&stem.with_extension("png"))?;
                radiance.write_exr(&stem.with_extension("exr"))?;
                self.save_recipe(&stem.with_extension("toml"))?;
                self.message = Some(format!("wrote {}.png, .exr and .toml", stem.display()));
                eprintln!("wrote {}.png, .exr and .toml", stem.display());
            }
            Action::SaveRecipe => {
                let path = self.numbered("recipe", None)?.with_extension("toml");
                self.save_recipe(&path)?;
                self.message = Some(format!("wrote {}", path.display()));
            }
            Action::CaptureWindow(_) => {} // done while presenting
            Action::Quit => return Ok(false),
        }
        Ok(true)
    }

    fn save_recipe(&self, path: &Path) -> Result<()> {
        let text = self.current_recipe().to_toml()?;
        gbuffer::write_atomically(path, |tmp| {
            std::fs::write(tmp, &text).map_err(|e| e.to_string())
        })?;
        Ok(())
    }

    /// Applies recipe edits: in place where every edited key is live, else by rebuilding the
    /// frame from the recipe. A recipe that does not parse or build is not taken, and says why.
    fn edit(&mut self, mut edits: Vec<(String, Option<Vec<String>>)>) -> Result<()> {
        // A setting turned on turns off those it cannot be combined with.
        let excluded: Vec<(String, Option<Vec<String>>)> = edits
            .iter()
            .filter(|(_, v)| v.is_some())
            .flat_map(|(k, _)| EXCLUSIVE.iter().filter(move |(key, _)| key == k))
            .flat_map(|(_, others)| others.iter())
            .filter(|k| self.recipe.has(k))
            .map(|k| ((*k).to_owned(), None))
            .collect();
        edits.extend(excluded);
        // … and one turned off takes its dependents with it (transitively).
        let mut i = 0;
        while i < edits.len() {
            if edits[i].1.is_none() {
                let key = edits[i].0.clone();
                for (_, dependents) in DEPENDENTS.iter().filter(|(k, _)| *k == key) {
                    for d in dependents.iter() {
                        if self.recipe.has(d) && !edits.iter().any(|(k, _)| k == d) {
                            edits.push(((*d).to_owned(), None));
                        }
                    }
                }
            }
            i += 1;
        }
        let mut recipe = self.recipe.clone();
        for (key, value) in &edits {
            recipe.set(key, value.clone());
        }
        if recipe == self.recipe {
            return Ok(());
        }
        let args = match recipe.args() {
            Ok(a) => a,
            Err(e) => {
                self.message = Some(format!("not applied: {e}"));
                return Ok(());
            }
        };
        let live = edits.iter().all(|(k, _)| LIVE_KEYS.contains(&k.as_str()));
        let result = if live {
            self.live.apply_live(args, &self.gpu)
        } else {
            self.message = Some("rebuilding the frame…".into());
            // The camera stays where the user took it.
            let mut with_camera = recipe.clone();
            for (key, value) in self.camera.keys() {
                with_camera.set(key, Some(vec![value]));
            }
            let new_scene = edits
                .iter()
                .any(|(k, _)| matches!(k.as_str(), "scene" | "builtin" | "add-model"));
            with_camera
                .args()
                .and_then(|args| Live::build(args, &self.gpu))
                .map(|live| {
                    self.live = live;
                    if new_scene {
                        self.cameras = cameras(&self.live);
                    }
                })
        };
        match result {
            Ok(()) => {
                self.present
                    .rebind(&self.gpu, &mut self.egui_renderer, &self.live.renderer)?;
                let keys: Vec<&str> = edits.iter().map(|(k, _)| k.as_str()).collect();
                self.message = Some(format!("applied {}", keys.join(", ")));
                self.recipe = recipe;
            }
            Err(e) => {
                // A failed in-place change may have left the renderer half set: rebuild it
                // from the recipe it had.
                if live {
                    self.live = Live::build(self.recipe.args()?, &self.gpu)?;
                    self.present
                        .rebind(&self.gpu, &mut self.egui_renderer, &self.live.renderer)?;
                }
                self.message = Some(format!("not applied: {e:#}"));
            }
        }
        Ok(())
    }
}

/// The cameras 1..: the recipe's, the scene file's, one framing the scene, the animated one.
fn cameras(live: &Live) -> Vec<NamedCamera> {
    let scene = &live.setup.scene;
    let mut list = vec![NamedCamera {
        name: "recipe",
        camera: live.setup.camera,
    }];
    if let Some(c) = scene.camera {
        list.push(NamedCamera {
            name: "scene file",
            camera: c,
        });
    }
    list.push(NamedCamera {
        name: "framing the scene",
        camera: scene::Camera::framing(scene.bounds()),
    });
    if scene.rig.as_ref().is_some_and(|r| r.camera.is_some()) {
        list.push(NamedCamera {
            name: "animated",
            camera: live.setup.camera,
        });
    }
    list
}

/// The panel for one frame: reads the state, collects [`Action`]s.
struct Panel<'a> {
    recipe: &'a Recipe,
    args: &'a Args,
    gpu: &'a gpu::Gpu,
    camera: &'a mut FlyCamera,
    cameras: &'a [NamedCamera],
    time: &'a mut f32,
    playing: &'a mut bool,
    animated: bool,
    view: &'a mut DebugView,
    /// The SSAO radius in use (the default follows the scene's size).
    ssao_radius: Option<f32>,
    timings: &'a VecDeque<Vec<gpu::PassTime>>,
    message: Option<&'a str>,
    actions: Vec<Action>,
    widgets: HashMap<String, egui::Rect>,
}

impl Panel<'_> {
    fn edit(&mut self, key: &str, value: Option<Vec<String>>) {
        self.actions
            .push(Action::Edit(vec![(key.to_owned(), value)]));
    }

    /// Remembers where `label`'s widget is, for scripted clicks.
    fn remember(&mut self, label: &str, response: &egui::Response) {
        self.widgets.insert(label.to_owned(), response.rect);
    }

    /// A switch (a flag without a value).
    fn switch(&mut self, ui: &mut egui::Ui, key: &str, label: &str) {
        let mut on = self.recipe.has(key);
        let response = ui.checkbox(&mut on, label);
        self.remember(label, &response);
        if response.changed() {
            self.edit(key, on.then(Vec::new));
        }
    }

    /// A choice among `options` for `key` (`off` removes the key when `optional`).
    fn choice(
        &mut self,
        ui: &mut egui::Ui,
        key: &str,
        label: &str,
        options: &[&str],
        current: &str,
        optional: bool,
    ) {
        let mut picked = current.to_owned();
        egui::ComboBox::from_label(label)
            .selected_text(current)
            .show_ui(ui, |ui| {
                if optional {
                    ui.selectable_value(&mut picked, "off".to_owned(), "off");
                }
                for o in options {
                    ui.selectable_value(&mut picked, (*o).to_owned(), *o);
                }
            });
        if picked != current {
            self.edit(key, (picked != "off").then(|| vec![picked]));
        }
    }

    /// A number for `key`, taken when the drag ends.
    fn number(
        &mut self,
        ui: &mut egui::Ui,
        key: &str,
        label: &str,
        value: f64,
        range: std::ops::RangeInclusive<f64>,
        integer: bool,
    ) {
        let mut v = value;
        let response = ui.add(
            egui::DragValue::new(&mut v)
                .range(range)
                .speed(if integer {
                    1.0
                } else {
                    value.abs().max(1e-3) * 0.01
                })
                .max_decimals(if integer { 0 } else { 3 })
                .prefix(format!("{label}: ")),
        );
        if (response.drag_stopped() || (response.changed() && !response.dragged())) && v != value {
            let text = if integer {
                format!("{}", v.round() as i64)
            } else {
                format!("{v}")
            };
            self.edit(key, Some(vec![text]));
        }
    }

    fn show(&mut self, ui: &mut egui::Ui) {
        let args = self.args;
        ui.heading("deferred view");
        ui.label(&self.gpu.info.name);
        if let Some(last) = self.timings.back() {
            let total: f64 = last.iter().map(|p| p.ms).sum();
            ui.label(format!(
                "{}x{} · GPU {total:.2} ms a frame",
                args.size.0, args.size.1
            ));
        }
        if let Some(m) = self.message {
            ui.colored_label(egui::Color32::LIGHT_YELLOW, m);
        }
        ui.horizontal(|ui| {
            let shot = ui.button("Screenshot (F12)");
            self.remember("Screenshot (F12)", &shot);
            if shot.clicked() {
                self.actions.push(Action::Screenshot(None));
            }
            let save = ui.button("Save recipe");
            self.remember("Save recipe", &save);
            if save.clicked() {
                self.actions.push(Action::SaveRecipe);
            }
        });

        egui::CollapsingHeader::new("GPU passes")
            .default_open(true)
            .show(ui, |ui| {
                timing_graph(ui, self.timings);
            });
        egui::CollapsingHeader::new("Camera")
            .default_open(true)
            .show(ui, |ui| {
                ui.horizontal(|ui| {
                    ui.radio_value(&mut self.camera.orbit, false, "fly");
                    ui.radio_value(&mut self.camera.orbit, true, "orbit (O)");
                });
                ui.add(egui::Slider::new(&mut self.camera.fov_degrees, 5.0..=120.0).text("fov °"));
                ui.add(
                    egui::Slider::new(&mut self.camera.speed, 1e-3..=1e4)
                        .logarithmic(true)
                        .text("speed"),
                );
                ui.horizontal_wrapped(|ui| {
                    for (i, c) in self.cameras.iter().enumerate() {
                        if ui.button(format!("{} {}", i + 1, c.name)).clicked() {
                            self.actions.push(Action::Camera(i));
                        }
                    }
                });
                let [eye, target, _] = self.camera.keys();
                ui.small(format!("eye {}\ntarget {}", eye.1, target.1));
            });
        if self.animated {
            egui::CollapsingHeader::new("Animation")
                .default_open(true)
                .show(ui, |ui| {
                    ui.horizontal(|ui| {
                        let label = if *self.playing {
                            "Pause (Space)"
                        } else {
                            "Play (Space)"
                        };
                        if ui.button(label).clicked() {
                            *self.playing = !*self.playing;
                        }
                        if ui.button("Step (.)").clicked() {
                            *self.playing = false;
                            *self.time += 1.0 / 24.0;
                        }
                    });
                    ui.add(
                        egui::DragValue::new(self.time)
                            .speed(0.01)
                            .range(0.0..=1e6)
                            .suffix(" s"),
                    );
                });
        }
        egui::CollapsingHeader::new("Direct light")
            .default_open(true)
            .show(ui, |ui| {
                self.choice(
                    ui,
                    "shading",
                    "shading",
                    &[
                        "brute",
                        "tiled",
                        "tiled-cones",
                        "tiled-slices",
                        "clustered",
                        "volumes",
                        "forward",
                        "light-prepass",
                    ],
                    &args.shading.to_string(),
                    false,
                );
                self.choice(
                    ui,
                    "tile",
                    "tile",
                    &["8", "16", "32"],
                    &args.tile.to_string(),
                    false,
                );
                self.choice(
                    ui,
                    "blend",
                    "blended surfaces",
                    &["dithered", "forward"],
                    &args.blend.to_string(),
                    false,
                );
                self.choice(
                    ui,
                    "light-search",
                    "light search",
                    &["tree", "flat"],
                    &args.light_search.to_string(),
                    false,
                );
                let lights = self.recipe.get("lights").unwrap_or("off");
                self.choice(
                    ui,
                    "lights",
                    "scattered point lights",
                    &["16", "256", "4096", "65536"],
                    lights,
                    true,
                );
                let shadows = args.shadows.map_or("off".to_owned(), |r| r.to_string());
                self.choice(
                    ui,
                    "shadows",
                    "shadow maps",
                    &["256", "512", "1024", "2048", "4096"],
                    &shadows,
                    true,
                );
                self.switch(ui, "ray-shadows", "exact ray shadows");
                let manylod = args
                    .manylod_shadows
                    .map_or("off".to_owned(), |t| t.to_string());
                self.choice(
                    ui,
                    "manylod-shadows",
                    "ManyLoD shadows",
                    &["16", "32", "64", "128"],
                    &manylod,
                    true,
                );
            });
        egui::CollapsingHeader::new("Indirect light")
            .default_open(true)
            .show(ui, |ui| {
                let pbgi = args.pbgi.map_or("off".to_owned(), |n| n.to_string());
                self.choice(
                    ui,
                    "pbgi",
                    "point-based GI, receiver every … px",
                    &["2", "4", "8", "16"],
                    &pbgi,
                    true,
                );
                if args.pbgi.is_some() {
                    self.choice(
                        ui,
                        "pbgi-tile",
                        "PBGI texels",
                        &["8", "16", "32", "64"],
                        &args.pbgi_tile.to_string(),
                        false,
                    );
                    self.number(
                        ui,
                        "pbgi-epsilon",
                        "PBGI ε texels",
                        f64::from(args.pbgi_epsilon),
                        0.25..=16.0,
                        false,
                    );
                }
                let reflections = args.reflections.map_or("off".to_owned(), |n| n.to_string());
                self.choice(
                    ui,
                    "reflections",
                    "reflection maps of mirrors, texels",
                    &["16", "32", "64", "128"],
                    &reflections,
                    true,
                );
                let vpls = args.vpls.map_or("off".to_owned(), |n| n.to_string());
                self.choice(
                    ui,
                    "vpls",
                    "VPLs",
                    &["64", "256", "1024", "4096", "16384"],
                    &vpls,
                    true,
                );
                if args.vpls.is_some() {
                    self.choice(
                        ui,
                        "pattern",
                        "pattern",
                        &["2x2", "4x4", "8x8"],
                        &format!("{}x{}", args.pattern.n, args.pattern.m),
                        false,
                    );
                    self.choice(
                        ui,
                        "interleaving",
                        "interleaving",
                        &["fused", "tiled", "one-pass", "two-pass"],
                        &args.interleaving,
                        false,
                    );
                    self.choice(
                        ui,
                        "blur",
                        "blur",
                        &["0", "5", "7", "9", "13", "17"],
                        &args.blur.to_string(),
                        false,
                    );
                    let recipe = self.recipe;
                    let mode = recipe.get("vpl-shadows").unwrap_or("auto");
                    self.choice(
                        ui,
                        "vpl-shadows",
                        "visibility",
                        &["auto", "none", "manylod", "ism", "ssm", "rays"],
                        mode,
                        false,
                    );
                    self.number(
                        ui,
                        "vpl-shadow-epsilon",
                        "ε px",
                        f64::from(args.vpl_shadow_epsilon),
                        0.1..=64.0,
                        false,
                    );
                }
            });
        egui::CollapsingHeader::new("Supersampling")
            .default_open(true)
            .show(ui, |ui| {
                let m = args.ssaa.map_or("off".to_owned(), |m| m.to_string());
                self.choice(ui, "ssaa", "SSAA m×m", &["2", "3", "4", "6", "8"], &m, true);
                if args.ssaa.is_some() {
                    self.switch(ui, "adaptive", "adaptive");
                    if args.adaptive {
                        self.choice(
                            ui,
                            "ssaa-metric",
                            "metric",
                            &["MM", "NC", "DV", "NV", "ND"],
                            &args.ssaa_metric.to_string(),
                            false,
                        );
                    }
                }
            });
        egui::CollapsingHeader::new("Ambient occlusion")
            .default_open(true)
            .show(ui, |ui| {
                let ssao = args.ssao.map_or("off".to_owned(), |e| e.to_string());
                self.choice(
                    ui,
                    "ssao",
                    "SSAO",
                    &[
                        "filter",
                        "filter-separable",
                        "crytek",
                        "crytek-separable",
                        "vo",
                        "vo-separable",
                        "hbao",
                        "hbao-separable",
                        "gtao",
                        "gtao-separable",
                    ],
                    &ssao,
                    true,
                );
                if args.ssao.is_some() {
                    self.number(
                        ui,
                        "ssao-kernel",
                        "kernel",
                        f64::from(args.ssao_kernel),
                        3.0..=63.0,
                        true,
                    );
                    if let Some(radius) = self.ssao_radius {
                        self.number(
                            ui,
                            "ssao-radius",
                            "radius",
                            f64::from(radius),
                            1e-4..=1e4,
                            false,
                        );
                    }
                }
            });
        egui::CollapsingHeader::new("Subdivision")
            .default_open(false)
            .show(ui, |ui| {
                let level = args.subdiv.map_or("off".to_owned(), |l| l.to_string());
                self.choice(
                    ui,
                    "subdiv",
                    "Loop level",
                    &["1", "2", "3", "4", "5", "6"],
                    &level,
                    true,
                );
                if args.subdiv.is_some() {
                    let px = args
                        .subdiv_pixels
                        .map_or("off".to_owned(), |p| p.to_string());
                    self.choice(
                        ui,
                        "subdiv-pixels",
                        "adaptive px",
                        &["1", "2", "4", "8", "16"],
                        &px,
                        true,
                    );
                    if args.subdiv_pixels.is_some() {
                        self.switch(ui, "subdiv-show-levels", "show levels");
                    }
                }
            });
        egui::CollapsingHeader::new("Output")
            .default_open(true)
            .show(ui, |ui| {
                self.number(
                    ui,
                    "exposure",
                    "exposure EV",
                    f64::from(args.exposure),
                    -16.0..=16.0,
                    false,
                );
                self.switch(ui, "auto-exposure", "auto exposure");
                self.choice(
                    ui,
                    "tone-map",
                    "tone curve",
                    &["aces", "clamp"],
                    self.recipe.get("tone-map").unwrap_or("aces"),
                    false,
                );
            });
        egui::CollapsingHeader::new("Debug view")
            .default_open(true)
            .show(ui, |ui| {
                egui::ComboBox::from_label("view")
                    .selected_text(self.view.name())
                    .show_ui(ui, |ui| {
                        for v in DebugView::ALL {
                            ui.selectable_value(self.view, v, v.name());
                        }
                    });
            });
    }
}

/// The last frame's passes as bars, and the frame's total over the kept history as a line.
fn timing_graph(ui: &mut egui::Ui, timings: &VecDeque<Vec<gpu::PassTime>>) {
    let Some(last) = timings.back() else {
        ui.label("no timestamps on this device");
        return;
    };
    if last.is_empty() {
        ui.label("no timestamps on this device");
        return;
    }
    let mut rows: Vec<(String, f64)> = Vec::new();
    for p in last {
        match rows.iter_mut().find(|(n, _)| *n == p.name) {
            Some(r) => r.1 += p.ms,
            None => rows.push((p.name.clone(), p.ms)),
        }
    }
    let widest = rows.iter().map(|r| r.1).fold(1e-6, f64::max);
    for (name, ms) in &rows {
        ui.horizontal(|ui| {
            let (rect, _) = ui.allocate_exact_size(egui::vec2(90.0, 10.0), egui::Sense::hover());
            let w = rect.width() * (*ms / widest) as f32;
            ui.painter().rect_filled(
                egui::Rect::from_min_size(rect.min, egui::vec2(w, rect.height())),
                0.0,
                egui::Color32::from_rgb(90, 160, 230),
            );
            ui.small(format!("{ms:7.3} ms {name}"));
        });
    }
    let totals: Vec<f64> = timings
        .iter()
        .map(|f| f.iter().map(|p| p.ms).sum())
        .collect();
    let top = totals.iter().copied().fold(1e-6, f64::max);
    let (rect, _) =
        ui.allocate_exact_size(egui::vec2(ui.available_width(), 60.0), egui::Sense::hover());
    ui.painter().rect_stroke(
        rect,
        0.0,
        egui::Stroke::new(1.0, egui::Color32::DARK_GRAY),
        egui::StrokeKind::Inside,
    );
    let points: Vec<egui::Pos2> = totals
        .iter()
        .enumerate()
        .map(|(i, &t)| {
            egui::pos2(
                rect.left() + rect.width() * i as f32 / (TIMING_HISTORY - 1) as f32,
                rect.bottom() - rect.height() * (t / top) as f32,
            )
        })
        .collect();
    ui.painter().add(egui::Shape::line(
        points,
        egui::Stroke::new(1.5, egui::Color32::LIGHT_GREEN),
    ));
    ui.small(format!(
        "frame total, last {} frames (top {top:.2} ms)",
        totals.len()
    ));
}
