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

/// The bench stability rule's bound: a configuration whose median is more than this factor
/// off the trend through its neighbours in a sweep is measured again ([`remeasure_outliers`]).
pub const OUTLIER_FACTOR: f64 = 1.5;

/// A configuration measured again by [`remeasure_outliers`]; every report's header lists them.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Remeasurement {
    /// The configuration, as the benchmark names it.
    pub configuration: String,
    /// The median of the first measurement, ms.
    pub first_ms: f64,
    /// The median measured again, ms: what the report shows.
    pub again_ms: f64,
    /// What its neighbours' trend expects after the re-measurement, ms.
    pub expected_ms: f64,
    /// What the re-measurement says about the configuration.
    pub verdict: Verdict,
}

/// A re-measured configuration's standing.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// Measured again, it fits its neighbours' trend: the first measurement was the outlier.
    Fits,
    /// Still off the trend, but both measurements agree within [`REPEAT_TOLERANCE`]: the
    /// configuration itself departs from its neighbours (a different regime, not noise).
    Repeatable,
    /// Still off the trend and the two measurements disagree: not to be trusted.
    Unstable,
}

/// How far two medians of one configuration may differ and still count as the same
/// measurement ([`Verdict::Repeatable`]).
pub const REPEAT_TOLERANCE: f64 = 0.1;

impl Verdict {
    fn of(first_ms: f64, again_ms: f64, expected_ms: f64) -> Self {
        if !off_trend(again_ms, expected_ms) {
            Self::Fits
        } else if (again_ms / first_ms - 1.0).abs() <= REPEAT_TOLERANCE {
            Self::Repeatable
        } else {
            Self::Unstable
        }
    }

    /// How the report words it after the medians (empty where it fits).
    pub fn words(self) -> &'static str {
        match self {
            Self::Fits => "",
            Self::Repeatable => ", repeatable: off the trend, not noise",
            Self::Unstable => ", **unstable: do not trust**",
        }
    }
}

/// Per point `(x, ms)` of one sweep, sorted by `x > 0`, what its neighbours expect: the
/// power law through the points either side (straight in log–log), extrapolated from the two
/// nearest at the ends; none with fewer than three points or where the neighbours share an `x`.
fn trend(points: &[(f64, f64)]) -> Vec<Option<f64>> {
    let n = points.len();
    (0..n)
        .map(|i| {
            let (a, b) = match i {
                _ if n < 3 => return None,
                0 => (1, 2),
                _ if i == n - 1 => (n - 3, n - 2),
                _ => (i - 1, i + 1),
            };
            let ln = |(x, ms): (f64, f64)| (x.ln(), ms.ln());
            let ((xa, va), (xb, vb), (xi, _)) = (ln(points[a]), ln(points[b]), ln(points[i]));
            (xb != xa).then(|| (va + (xi - xa) / (xb - xa) * (vb - va)).exp())
        })
        .collect()
}

/// Whether `ms` is more than [`OUTLIER_FACTOR`] off `expected`, either way.
fn off_trend(ms: f64, expected: f64) -> bool {
    let ratio = ms / expected;
    !(ratio <= OUTLIER_FACTOR && ratio >= 1.0 / OUTLIER_FACTOR)
}

/// The bench stability rule's re-measurement: `rows` form sweeps (rows of equal `sweep(r).0`,
/// ordered by the position `sweep(r).1 > 0` along the swept parameter); every row whose
/// `median` is more than [`OUTLIER_FACTOR`] off the trend through its neighbours is measured
/// again by `measure_again`, once, and recorded with its [`Verdict`] for the report's header
/// ([`crate::Header::remeasured`]). In [run-once mode](crate::run_once) the first row
/// is measured again regardless, so that every benchmark's re-measurement path runs in CI.
pub fn remeasure_outliers<R, K: PartialEq, E>(
    rows: &mut [R],
    sweep: impl Fn(&R) -> (K, f64),
    median: impl Fn(&R) -> f64,
    label: impl Fn(&R) -> String,
    measure_again: impl FnMut(&mut R) -> Result<(), E>,
) -> Result<Vec<Remeasurement>, E> {
    let remeasured = remeasure(
        rows,
        (sweep, median, label),
        measure_again,
        crate::run_once(),
    )?;
    crate::record_remeasured(&remeasured);
    Ok(remeasured)
}

/// [`remeasure_outliers`]; with `first_regardless`, the first row is the one measured again.
fn remeasure<R, K: PartialEq, E>(
    rows: &mut [R],
    (sweep, median, label): (
        impl Fn(&R) -> (K, f64),
        impl Fn(&R) -> f64,
        impl Fn(&R) -> String,
    ),
    mut measure_again: impl FnMut(&mut R) -> Result<(), E>,
    first_regardless: bool,
) -> Result<Vec<Remeasurement>, E> {
    let expected = |rows: &[R]| {
        let mut keys: Vec<K> = Vec::new();
        let mut sweeps: Vec<Vec<usize>> = Vec::new();
        for (i, r) in rows.iter().enumerate() {
            let key = sweep(r).0;
            match keys.iter().position(|k| *k == key) {
                Some(s) => sweeps[s].push(i),
                None => {
                    keys.push(key);
                    sweeps.push(vec![i]);
                }
            }
        }
        let mut expected = vec![None; rows.len()];
        for mut s in sweeps {
            s.sort_by(|&a, &b| sweep(&rows[a]).1.total_cmp(&sweep(&rows[b]).1));
            let points: Vec<(f64, f64)> = s
                .iter()
                .map(|&i| (sweep(&rows[i]).1, median(&rows[i])))
                .collect();
            for (i, e) in s.into_iter().zip(trend(&points)) {
                expected[i] = e;
            }
        }
        expected
    };
    let first = expected(rows);
    let outliers: Vec<usize> = if first_regardless {
        (0..rows.len().min(1)).collect()
    } else {
        (0..rows.len())
            .filter(|&i| first[i].is_some_and(|e| off_trend(median(&rows[i]), e)))
            .collect()
    };
    let mut firsts = Vec::new();
    for &i in &outliers {
        firsts.push(median(&rows[i]));
        measure_again(&mut rows[i])?;
    }
    let again = expected(rows);
    let remeasured: Vec<Remeasurement> = outliers
        .into_iter()
        .zip(firsts)
        .map(|(i, first_ms)| {
            let again_ms = median(&rows[i]);
            let expected_ms = again[i].unwrap_or(again_ms);
            Remeasurement {
                configuration: label(&rows[i]),
                first_ms,
                again_ms,
                expected_ms,
                verdict: Verdict::of(first_ms, again_ms, expected_ms),
            }
        })
        .collect();
    for r in &remeasured {
        println!(
            "re-measured {}: {:.3} ms, then {:.3} ms (its neighbours expect {:.3} ms){}",
            r.configuration,
            r.first_ms,
            r.again_ms,
            r.expected_ms,
            r.verdict.words()
        );
    }
    Ok(remeasured)
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
    fn the_trend_is_the_power_law_through_the_neighbours() {
        // t = x²: every point lies on its neighbours' power law, in the middle and at the ends.
        let points: Vec<(f64, f64)> = [1.0, 2.0, 3.0, 8.0].map(|x| (x, x * x)).to_vec();
        for ((_, ms), e) in points.iter().zip(trend(&points)) {
            assert!((e.unwrap() / ms - 1.0).abs() < 1e-9);
        }
        assert_eq!(trend(&points[..2]), vec![None, None]);
    }

    /// A sweep with `ms` at x = 1, 2, 4, 8, 16 whose re-measurement returns x, linear, except
    /// `at_4` at x = 4: the re-measured x values and their verdicts.
    fn remeasured(ms: [f64; 5], at_4: f64) -> Vec<(f64, Verdict)> {
        let mut rows: Vec<(f64, f64)> = [1.0, 2.0, 4.0, 8.0, 16.0].into_iter().zip(ms).collect();
        let r = remeasure(
            &mut rows,
            (
                |r: &(f64, f64)| ((), r.0),
                |r| r.1,
                |r| format!("x = {}", r.0),
            ),
            |r| {
                r.1 = if r.0 == 4.0 { at_4 } else { r.0 };
                Ok::<(), ()>(())
            },
            false,
        )
        .unwrap();
        r.iter()
            .map(|m| (m.configuration[4..].parse().unwrap(), m.verdict))
            .collect()
    }

    #[test]
    fn a_configuration_far_off_its_neighbours_is_measured_again() {
        // Linear in x, but x = 4 measured 3× slow: it and the neighbours whose trend it bends
        // are measured again; measured right, every one fits.
        let again = remeasured([1.0, 2.0, 12.0, 8.0, 16.0], 4.0);
        assert!(again.contains(&(4.0, Verdict::Fits)));
        assert!(again.iter().all(|(_, v)| *v == Verdict::Fits));
        // 3× off again, and the same as the first time: repeatable, a property of x = 4.
        assert!(
            remeasured([1.0, 2.0, 12.0, 8.0, 16.0], 12.5).contains(&(4.0, Verdict::Repeatable))
        );
        // 3× off first, 2× the other way again: unstable.
        assert!(remeasured([1.0, 2.0, 12.0, 8.0, 16.0], 2.0).contains(&(4.0, Verdict::Unstable)));
        // 1.4× off (within the factor): nothing is measured again.
        assert!(remeasured([1.0, 2.0, 5.6, 8.0, 16.0], 4.0).is_empty());
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
