//! Frame sequences: a fixed-step [`Clock`] (runs are reproducible: frame `k` is at `k / fps`
//! seconds whatever the machine's speed), [`CameraPath`]s, looping clip time, and the frames'
//! pass times ([`Timeline`]) as a CSV table, a Chrome/Perfetto trace and per-pass statistics.
//!
//! ```
//! use pipeline::sequence::{Clock, Timeline};
//! let clock = Clock::new(24.0)?;
//! let mut timeline = Timeline::default();
//! for frame in 0..3 {
//!     let t = clock.time(frame);
//!     // … pose the rig at t, set the camera, encode and submit the frame …
//!     let passes = vec![gpu::PassTime { name: "gbuffer".into(), ms: 1.5, start_ms: 0.0 }];
//!     timeline.push(frame, t, 1e6 * f64::from(t), passes);
//! }
//! assert!(timeline.csv().starts_with("frame,time_s,gbuffer,total\n"));
//! # Ok::<(), pipeline::RenderError>(())
//! ```

use glam::{Quat, Vec3};
use scene::Camera;

use crate::RenderError;

/// The most frames per second a clock runs at.
pub const MAX_FPS: f32 = 1000.0;

/// A clock with a fixed time step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Clock {
    fps: f32,
}

impl Clock {
    /// A clock of `fps` frames per second (finite, above 0, at most [`MAX_FPS`]).
    pub fn new(fps: f32) -> Result<Self, RenderError> {
        if !(fps > 0.0 && fps <= MAX_FPS) {
            return Err(RenderError::Animation(format!(
                "frames per second must be above 0 and at most {MAX_FPS}, not {fps}"
            )));
        }
        Ok(Self { fps })
    }

    /// Frames per second.
    pub fn fps(&self) -> f32 {
        self.fps
    }

    /// Seconds at frame `frame`.
    pub fn time(&self, frame: u32) -> f32 {
        (f64::from(frame) / f64::from(self.fps)) as f32
    }
}

/// `t` seconds into a clip of `duration` seconds played in a loop.
pub fn looped(t: f32, duration: f32) -> f32 {
    if duration > 0.0 {
        t.rem_euclid(duration)
    } else {
        0.0
    }
}

/// How the camera moves over a sequence.
#[derive(Clone, Debug, Default, PartialEq)]
pub enum CameraPath {
    /// It stays.
    #[default]
    Still,
    /// The eye turns about the vertical (+Y) axis through the target, `degrees_per_second`
    /// counter-clockwise seen from above.
    Orbit {
        /// Turn rate.
        degrees_per_second: f32,
    },
    /// Through keyframes `(seconds, camera)` in time order: eye, target, up, field of view
    /// and planes interpolated linearly, held before the first and after the last.
    Keyframes(Vec<(f32, Camera)>),
}

impl CameraPath {
    /// The camera at `t` seconds, starting from `base` (the path's first camera for
    /// [`CameraPath::Still`] and [`CameraPath::Orbit`]).
    pub fn camera(&self, base: &Camera, t: f32) -> Camera {
        match self {
            CameraPath::Still => *base,
            CameraPath::Orbit { degrees_per_second } => {
                let turn = Quat::from_rotation_y((degrees_per_second * t).to_radians());
                Camera {
                    eye: base.target + turn * (base.eye - base.target),
                    up: turn * base.up,
                    ..*base
                }
            }
            CameraPath::Keyframes(keys) => {
                let next = keys.partition_point(|(k, _)| *k <= t);
                match (next.checked_sub(1).map(|i| &keys[i]), keys.get(next)) {
                    (Some((t0, a)), Some((t1, b))) => {
                        let s = (t - t0) / (t1 - t0);
                        Camera {
                            eye: a.eye.lerp(b.eye, s),
                            target: a.target.lerp(b.target, s),
                            up: a.up.lerp(b.up, s).normalize_or(Vec3::Y),
                            fov_y: a.fov_y + (b.fov_y - a.fov_y) * s,
                            near: a.near + (b.near - a.near) * s,
                            far: a.far + (b.far - a.far) * s,
                        }
                    }
                    (Some((_, c)), None) | (None, Some((_, c))) => *c,
                    (None, None) => *base,
                }
            }
        }
    }
}

/// One frame of a [`Timeline`].
#[derive(Clone, Debug, PartialEq)]
pub struct FrameRecord {
    /// Frame number.
    pub frame: u32,
    /// Sequence time in seconds.
    pub time_s: f32,
    /// When the frame was submitted, in microseconds of the wall clock from the sequence's
    /// start (places the frame in the trace).
    pub submitted_us: f64,
    /// Its GPU passes.
    pub passes: Vec<::gpu::PassTime>,
}

/// Per-pass statistics over a sequence ([`Timeline::summary`]).
#[derive(Clone, Debug, PartialEq)]
pub struct PassSummary {
    /// Pass name (`total` for the whole frame).
    pub name: String,
    /// Median milliseconds.
    pub median_ms: f64,
    /// 99th-percentile milliseconds (nearest rank).
    pub p99_ms: f64,
}

/// The pass times of a sequence's frames.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Timeline {
    /// The frames in order.
    pub frames: Vec<FrameRecord>,
}

impl Timeline {
    /// Adds frame `frame` at `time_s` seconds, submitted `submitted_us` after the start.
    pub fn push(
        &mut self,
        frame: u32,
        time_s: f32,
        submitted_us: f64,
        passes: Vec<::gpu::PassTime>,
    ) {
        self.frames.push(FrameRecord {
            frame,
            time_s,
            submitted_us,
            passes,
        });
    }

    /// Pass names in first-seen order over all frames.
    pub fn columns(&self) -> Vec<String> {
        let mut names: Vec<String> = Vec::new();
        for p in self.frames.iter().flat_map(|f| &f.passes) {
            if !names.contains(&p.name) {
                names.push(p.name.clone());
            }
        }
        names
    }

    /// Each column's milliseconds in `frame` (passes of one name summed; 0 where absent),
    /// then the frame's total.
    fn row(frame: &FrameRecord, columns: &[String]) -> Vec<f64> {
        let mut row: Vec<f64> = columns
            .iter()
            .map(|c| {
                // A fold from +0: an empty f64 `sum` is −0, which prints as "-0".
                let named = frame.passes.iter().filter(|p| &p.name == c);
                named.fold(0.0, |a, p| a + p.ms)
            })
            .collect();
        row.push(frame.passes.iter().fold(0.0, |a, p| a + p.ms));
        row
    }

    /// One row per frame: `frame,time_s,<pass ms>…,total`.
    pub fn csv(&self) -> String {
        let columns = self.columns();
        let mut out = String::from("frame,time_s");
        for c in &columns {
            out.push(',');
            out.push_str(&c.replace([',', '"', '\n'], " "));
        }
        out.push_str(",total\n");
        for f in &self.frames {
            out.push_str(&format!("{},{:.6}", f.frame, f.time_s));
            for ms in Self::row(f, &columns) {
                out.push_str(&format!(",{ms:.6}"));
            }
            out.push('\n');
        }
        out
    }

    /// The GPU passes as a Chrome trace (JSON, `chrome://tracing` or ui.perfetto.dev): one
    /// complete event per pass at its frame's submission time plus its start in the frame.
    pub fn chrome_trace(&self) -> String {
        let events: Vec<serde_json::Value> = self
            .frames
            .iter()
            .flat_map(|f| {
                f.passes.iter().map(move |p| {
                    serde_json::json!({
                        "name": p.name,
                        "cat": "gpu",
                        "ph": "X",
                        "ts": f.submitted_us + 1e3 * p.start_ms,
                        "dur": 1e3 * p.ms,
                        "pid": 1,
                        "tid": 1,
                        "args": { "frame": f.frame, "time_s": f.time_s },
                    })
                })
            })
            .collect();
        serde_json::json!({ "traceEvents": events, "displayTimeUnit": "ms" }).to_string()
    }

    /// Median and 99th percentile of every pass and of the total, over the frames.
    pub fn summary(&self) -> Vec<PassSummary> {
        let mut columns = self.columns();
        let rows: Vec<Vec<f64>> = self.frames.iter().map(|f| Self::row(f, &columns)).collect();
        columns.push("total".into());
        columns
            .into_iter()
            .enumerate()
            .map(|(i, name)| {
                let mut v: Vec<f64> = rows.iter().map(|r| r[i]).collect();
                v.sort_by(f64::total_cmp);
                PassSummary {
                    name,
                    median_ms: percentile(&v, 50.0),
                    p99_ms: percentile(&v, 99.0),
                }
            })
            .collect()
    }
}

impl Timeline {
    /// Milliseconds of every pass (and the total) per frame as an SVG line chart, like
    /// Holländer 2013 Fig. 3.21: frame on x, GPU time on y, one line per pass.
    pub fn plot_svg(&self, title: &str) -> Result<String, RenderError> {
        use plotters::prelude::*;
        const PALETTE: [RGBColor; 10] = [
            RGBColor(31, 119, 180),
            RGBColor(255, 127, 14),
            RGBColor(44, 160, 44),
            RGBColor(214, 39, 40),
            RGBColor(148, 103, 189),
            RGBColor(140, 86, 75),
            RGBColor(227, 119, 194),
            RGBColor(127, 127, 127),
            RGBColor(188, 189, 34),
            RGBColor(23, 190, 207),
        ];
        let mut columns = self.columns();
        let rows: Vec<Vec<f64>> = self.frames.iter().map(|f| Self::row(f, &columns)).collect();
        columns.push("total".into());
        let top = rows
            .iter()
            .flatten()
            .copied()
            .fold(0.0f64, f64::max)
            .max(1e-3)
            * 1.05;
        let frames = self.frames.len().max(2) as f64 - 1.0;
        let mut svg = String::new();
        let plot_error = |e: String| RenderError::InvalidOutput(format!("plot: {e}"));
        {
            let root = SVGBackend::with_string(&mut svg, (960, 540)).into_drawing_area();
            root.fill(&WHITE).map_err(|e| plot_error(e.to_string()))?;
            let mut chart = ChartBuilder::on(&root)
                .caption(title, ("sans-serif", 20))
                .margin(12)
                .x_label_area_size(36)
                .y_label_area_size(56)
                .build_cartesian_2d(0.0..frames, 0.0..top)
                .map_err(|e| plot_error(e.to_string()))?;
            chart
                .configure_mesh()
                .x_desc("frame")
                .y_desc("GPU ms")
                .draw()
                .map_err(|e| plot_error(e.to_string()))?;
            for (i, name) in columns.iter().enumerate() {
                let colour = if name == "total" {
                    BLACK
                } else {
                    PALETTE[i % PALETTE.len()]
                };
                let points = self
                    .frames
                    .iter()
                    .zip(&rows)
                    .enumerate()
                    .map(|(k, (_, r))| (k as f64, r[i]));
                chart
                    .draw_series(LineSeries::new(points, colour.stroke_width(2)))
                    .map_err(|e| plot_error(e.to_string()))?
                    .label(name.as_str())
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 16, y)], colour.stroke_width(2))
                    });
            }
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .position(SeriesLabelPosition::UpperRight)
                .draw()
                .map_err(|e| plot_error(e.to_string()))?;
            root.present().map_err(|e| plot_error(e.to_string()))?;
        }
        Ok(svg)
    }
}

/// The nearest-rank `p`-th percentile of `sorted` (0 when empty).
fn percentile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return 0.0;
    }
    let rank = ((p / 100.0) * sorted.len() as f64).ceil() as usize;
    sorted[rank.clamp(1, sorted.len()) - 1]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pass(name: &str, ms: f64, start_ms: f64) -> ::gpu::PassTime {
        ::gpu::PassTime {
            name: name.into(),
            ms,
            start_ms,
        }
    }

    #[test]
    fn clock_steps_are_fixed_and_bad_rates_are_refused() {
        let c = Clock::new(24.0).unwrap();
        assert_eq!(c.time(48), 2.0);
        for bad in [0.0, -1.0, f32::NAN, f32::INFINITY, 1e6] {
            assert!(Clock::new(bad).is_err(), "{bad}");
        }
        assert_eq!(looped(2.5, 1.0), 0.5);
        assert_eq!(looped(2.5, 0.0), 0.0);
    }

    #[test]
    fn orbit_turns_about_the_target_and_keyframes_interpolate() {
        let base = Camera {
            eye: Vec3::new(0.0, 1.0, 5.0),
            target: Vec3::new(0.0, 1.0, 0.0),
            up: Vec3::Y,
            fov_y: 0.8,
            near: 0.1,
            far: 100.0,
        };
        let quarter = CameraPath::Orbit {
            degrees_per_second: 90.0,
        }
        .camera(&base, 1.0);
        // +Z turned 90° counter-clockwise seen from above is +X.
        assert!(
            quarter.eye.distance(Vec3::new(5.0, 1.0, 0.0)) < 1e-5,
            "{}",
            quarter.eye
        );
        let other = Camera {
            eye: Vec3::new(2.0, 1.0, 5.0),
            fov_y: base.fov_y * 2.0,
            ..base
        };
        let path = CameraPath::Keyframes(vec![(1.0, base), (3.0, other)]);
        assert_eq!(path.camera(&base, 0.0), base);
        let mid = path.camera(&base, 2.0);
        assert!(mid.eye.distance(Vec3::new(1.0, 1.0, 5.0)) < 1e-6);
        assert!((mid.fov_y - 1.5 * base.fov_y).abs() < 1e-6);
        assert_eq!(path.camera(&base, 9.0), other);
    }

    #[test]
    fn timeline_tables_sum_passes_of_one_name_and_trace_every_pass() {
        let mut t = Timeline::default();
        t.push(
            0,
            0.0,
            0.0,
            vec![
                pass("gbuffer", 2.0, 0.0),
                pass("shadows", 1.0, 2.0),
                pass("shadows", 0.5, 3.0),
            ],
        );
        t.push(1, 0.5, 1000.0, vec![pass("gbuffer", 4.0, 0.0)]);
        assert_eq!(
            t.csv(),
            "frame,time_s,gbuffer,shadows,total\n\
             0,0.000000,2.000000,1.500000,3.500000\n\
             1,0.500000,4.000000,0.000000,4.000000\n"
        );
        let trace: serde_json::Value = serde_json::from_str(&t.chrome_trace()).unwrap();
        let events = trace["traceEvents"].as_array().unwrap();
        assert_eq!(events.len(), 4);
        assert_eq!(events[2]["ts"], 3000.0);
        assert_eq!(events[3]["ts"], 1000.0);
        assert_eq!(events[3]["dur"], 4000.0);
        let svg = t.plot_svg("test").unwrap();
        assert!(svg.starts_with("<svg") && svg.contains("shadows") && svg.contains("total"));
        let s = t.summary();
        assert_eq!(s.last().unwrap().name, "total");
        assert_eq!((s[0].median_ms, s[0].p99_ms), (2.0, 4.0));
    }
}
