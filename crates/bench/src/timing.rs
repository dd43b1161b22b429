//! Frame timing and report writing shared by the benchmark programs.

use glam::Vec3;
use gpu::Gpu;
use scene::Camera;

/// The warm-up every timing of this harness does before measuring (stated in each report).
pub const WARM_UP_RULE: &str = "at least 10 frames and 300 ms of back-to-back work";

/// The ManyLoDs benchmark's light (`manylod-bench`, `manylod-cuts`) at `angle` radians along
/// its orbit: a spot light high in the scene pointing down, circling the vertical axis through
/// the scene's centre at a tenth of the smaller horizontal extent; it reaches past the scene, so
/// every photon lands.
pub fn orbiting_spot(bounds: &scene::Aabb, angle: f32) -> scene::Light {
    let extent = bounds.max - bounds.min;
    let orbit = 0.1 * extent.x.min(extent.z);
    scene::Light::Spot {
        position: bounds.center()
            + Vec3::new(orbit * angle.cos(), 0.3 * extent.y, orbit * angle.sin()),
        direction: Vec3::NEG_Y,
        color: Vec3::ONE,
        intensity: 30.0,
        radius: 2.0 * bounds.diagonal(),
        inner_angle: 50f32.to_radians(),
        outer_angle: 60f32.to_radians(),
    }
}

/// Runs `frame` for a warm-up of at least 10 frames and 300 ms of back-to-back work, so that
/// the GPU has left the idle clocks it drops to while the CPU prepares a configuration, then
/// `frames` more times, and returns those frames' results ([run-once mode](crate::run_once):
/// one frame, no warm-up).
pub fn warm_then_time<T, E>(
    frames: u32,
    mut frame: impl FnMut() -> Result<T, E>,
) -> Result<Vec<T>, E> {
    if crate::run_once() {
        return frame().map(|t| vec![t]);
    }
    let start = std::time::Instant::now();
    let mut warm = 0;
    while warm < 10 || start.elapsed() < std::time::Duration::from_millis(300) {
        frame()?;
        warm += 1;
    }
    (0..frames).map(|_| frame()).collect()
}

/// Per pass name, the per-frame milliseconds of `frames` frames of `frame`'s `(name, ms)`
/// passes (passes of one name summed within a frame), after [`warm_then_time`]'s warm-up.
pub fn time_named<E>(
    frames: u32,
    frame: impl FnMut() -> Result<Vec<(String, f64)>, E>,
) -> Result<Vec<(String, Vec<f64>)>, E> {
    let mut by_name: Vec<(String, Vec<f64>)> = Vec::new();
    for (f, passes) in warm_then_time(frames, frame)?.into_iter().enumerate() {
        for (name, ms) in passes {
            match by_name.iter_mut().find(|(n, _)| *n == name) {
                Some((_, v)) if v.len() > f => v[f] += ms,
                Some((_, v)) => v.push(ms),
                None => by_name.push((name, vec![ms])),
            }
        }
    }
    Ok(by_name)
}

/// [`time_named`] of the passes `record` encodes with `timer`, one command buffer per frame:
/// per pass name, the per-frame GPU milliseconds.
pub fn time_recorded(
    gpu: &Gpu,
    timer: &gpu::PassTimer,
    frames: u32,
    mut record: impl FnMut(&mut wgpu::CommandEncoder, &gpu::PassTimer),
) -> Result<Vec<(String, Vec<f64>)>, gpu::GpuError> {
    time_named(frames, || {
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        record(&mut encoder, timer);
        timer.resolve(&mut encoder);
        gpu.queue.submit([encoder.finish()]);
        Ok(timer
            .read(&gpu.device, &gpu.queue)?
            .into_iter()
            .map(|t| (t.name, t.ms))
            .collect())
    })
}

/// The statistics of the pass `name` of [`time_named`]'s result, if it ran.
pub fn pass_stat(by_name: &[(String, Vec<f64>)], name: &str) -> Option<crate::Stat> {
    by_name
        .iter()
        .find(|(n, _)| n == name)
        .map(|(_, v)| crate::Stat::of(v.clone()))
}

/// Per-frame GPU ms of the passes `record` encodes (summed over the frame's passes; with
/// `span`, from the first pass's begin to the last one's end, which also counts commands
/// recorded between passes such as buffer clears), after [`warm_then_time`]'s warm-up.
pub fn time_encoded(
    gpu: &Gpu,
    timer: &gpu::PassTimer,
    frames: u32,
    span: bool,
    record: &dyn Fn(&mut wgpu::CommandEncoder, &gpu::PassTimer),
) -> Result<crate::Stat, gpu::GpuError> {
    let frame = || -> Result<f64, gpu::GpuError> {
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        record(&mut encoder, timer);
        timer.resolve(&mut encoder);
        gpu.queue.submit([encoder.finish()]);
        let times = timer.read(&gpu.device, &gpu.queue)?;
        Ok(match (span, times.first(), times.last()) {
            (true, Some(first), Some(last)) => last.end_ms() - first.start_ms,
            _ => times.iter().map(|t| t.ms).sum(),
        })
    };
    Ok(crate::Stat::of(warm_then_time(frames, frame)?))
}

/// Per frame, the sum of the passes named in `names`.
pub fn per_frame_sum(by_name: &[(String, Vec<f64>)], names: &[&str]) -> Vec<f64> {
    let frames = by_name.iter().map(|(_, v)| v.len()).max().unwrap_or(0);
    (0..frames)
        .map(|f| {
            by_name
                .iter()
                .filter(|(n, _)| names.contains(&n.as_str()))
                .map(|(_, v)| v.get(f).copied().unwrap_or(0.0))
                .sum()
        })
        .collect()
}

/// How a report names its scene file and camera: `(file name, "eye … target … fov …°")`.
pub fn scene_labels(path: &std::path::Path, camera: &Camera) -> (String, String) {
    (
        path.file_name()
            .map_or("?".into(), |f| f.to_string_lossy().into_owned()),
        format!(
            "eye {} target {} fov {:.0}°",
            camera.eye,
            camera.target,
            camera.fov_y.to_degrees()
        ),
    )
}

/// Writes `<stem>.json` (the serialized report) and `<stem>.md` under `out`, each atomically
/// (a report rewritten as rows come in is never seen half-written), and says so.
pub fn write_report(
    out: &std::path::Path,
    stem: &str,
    report: &impl serde::Serialize,
    markdown: &str,
) -> anyhow::Result<()> {
    std::fs::create_dir_all(out)?;
    let write = |path: &std::path::Path, text: &str| {
        gbuffer::write_atomically(path, |tmp| {
            std::fs::write(tmp, text).map_err(|e| e.to_string())
        })
    };
    let json = out.join(format!("{stem}.json"));
    write(&json, &serde_json::to_string_pretty(report)?)?;
    let md = out.join(format!("{stem}.md"));
    write(&md, markdown)?;
    println!("wrote {} and {}", md.display(), json.display());
    Ok(())
}
