//! Frame timing and report writing shared by the benchmark programs.

use std::time::{Duration, Instant};

use glam::Vec3;
use gpu::Gpu;
use scene::Camera;

/// The warm-up every timing of this harness does before measuring (stated in each report).
pub const WARM_UP_RULE: &str = "at least 10 frames and 300 ms of back-to-back work, then more \
    until the SM clock reads at least 90 % of its maximum (nvidia-smi; at most 2 s more)";

/// The fraction of its maximum the SM clock must read before the timed frames begin.
const CLOCK_UP: f64 = 0.9;
/// The longest the warm-up goes on waiting for the clock, after its fixed part.
const CLOCK_WAIT: Duration = Duration::from_secs(2);
/// Work between two readings of the clock while waiting for it.
const CLOCK_POLL: Duration = Duration::from_millis(100);

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

/// Runs `frame` for the warm-up of [`WARM_UP_RULE`], so that the GPU has left the idle clocks
/// it drops to while the CPU prepares a configuration, then `frames` more times, and returns
/// those frames' results ([run-once mode](crate::run_once): one frame, no warm-up). The clock
/// read as the timed frames begin goes into the report's header.
pub fn warm_then_time<T, E>(
    frames: u32,
    mut frame: impl FnMut() -> Result<T, E>,
) -> Result<Vec<T>, E> {
    if crate::run_once() {
        return frame().map(|t| vec![t]);
    }
    let clock = warm_up(
        &mut frame,
        crate::sm_clock_max_mhz(),
        &mut crate::sm_clock_mhz,
    )?;
    if let Some(mhz) = clock {
        crate::record_measured_clock(mhz);
    }
    (0..frames).map(|_| frame()).collect()
}

/// The warm-up of [`WARM_UP_RULE`] with the clock read by `clock` and its maximum `max`
/// (neither: the fixed part only); the last clock read.
fn warm_up<T, E>(
    frame: &mut impl FnMut() -> Result<T, E>,
    max: Option<u32>,
    clock: &mut dyn FnMut() -> Option<u32>,
) -> Result<Option<u32>, E> {
    let work = |frame: &mut dyn FnMut() -> Result<T, E>, least: u32, time: Duration| {
        let start = Instant::now();
        let mut done = 0;
        while done < least || start.elapsed() < time {
            frame()?;
            done += 1;
        }
        Ok(())
    };
    work(frame, 10, Duration::from_millis(300))?;
    let Some(max) = max else {
        return Ok(None);
    };
    let waiting = Instant::now();
    loop {
        let mhz = clock();
        let up = mhz.is_none_or(|c| f64::from(c) >= CLOCK_UP * f64::from(max));
        if up || waiting.elapsed() >= CLOCK_WAIT {
            return Ok(mhz);
        }
        work(frame, 1, CLOCK_POLL)?;
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A warm-up whose clock reads `readings` in turn (then the last one again): the frames it
    /// ran, the clock it ended on and how often it read the clock.
    fn warm_up_with(max: Option<u32>, readings: &[u32]) -> (usize, Option<u32>, usize) {
        let mut frames = 0;
        let mut reads = 0;
        let mut clock = || {
            reads += 1;
            readings.get(reads - 1).or(readings.last()).copied()
        };
        let last = warm_up(
            &mut || {
                frames += 1;
                Ok::<(), ()>(())
            },
            max,
            &mut clock,
        )
        .unwrap();
        (frames, last, reads)
    }

    #[test]
    fn without_a_clock_the_warm_up_is_its_fixed_part() {
        let start = Instant::now();
        let (frames, last, reads) = warm_up_with(None, &[]);
        assert!(frames >= 10 && start.elapsed() >= Duration::from_millis(300));
        assert_eq!((last, reads), (None, 0));
    }

    #[test]
    fn the_warm_up_waits_for_the_clock_to_rise() {
        let (_, last, reads) = warm_up_with(Some(1980), &[345, 900, 1755, 1980]);
        // 1755 MHz is below 90 % of 1980 (1782): the fourth reading ends it.
        assert_eq!((last, reads), (Some(1980), 4));
    }

    #[test]
    fn a_clock_that_never_rises_ends_the_warm_up_after_the_wait() {
        let start = Instant::now();
        let (_, last, _) = warm_up_with(Some(1980), &[345]);
        assert_eq!(last, Some(345));
        assert!(start.elapsed() >= Duration::from_millis(300) + CLOCK_WAIT);
        assert!(start.elapsed() < Duration::from_millis(300) + CLOCK_WAIT + 10 * CLOCK_POLL);
    }
}
