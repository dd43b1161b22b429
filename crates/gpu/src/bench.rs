//! Shared pieces of the benchmark programs: timing statistics, the date, and the adapter
//! header every report under `docs/bench/` starts with.

use serde::Serialize;

use crate::Gpu;

/// Median and minimum of a set of timings.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Stat {
    /// Median, ms.
    pub median_ms: f64,
    /// Minimum, ms.
    pub min_ms: f64,
}

impl Stat {
    /// Statistics of `v` (at least one value; an empty list gives NaN).
    pub fn of(mut v: Vec<f64>) -> Self {
        v.sort_by(f64::total_cmp);
        Self {
            median_ms: v.get(v.len() / 2).copied().unwrap_or(f64::NAN),
            min_ms: v.first().copied().unwrap_or(f64::NAN),
        }
    }
}

/// Today's date (UTC) as YYYY-MM-DD, from the Unix clock (Hinnant's civil-from-days).
pub fn today() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let z = (secs / 86_400) as i64 + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    format!("{:04}-{m:02}-{d:02}", yoe + era * 400 + i64::from(m <= 2))
}

/// A benchmark refused to run on a software rasterizer.
#[derive(Debug, thiserror::Error)]
#[error(
    "{0} is a software rasterizer: its times are not GPU performance (pass --allow-software to measure anyway)"
)]
pub struct SoftwareAdapter(pub String);

/// Fails on a software rasterizer unless `allow_software`.
pub fn require_hardware(gpu: &Gpu, allow_software: bool) -> Result<(), SoftwareAdapter> {
    if gpu.is_software() && !allow_software {
        return Err(SoftwareAdapter(gpu.info.name.clone()));
    }
    Ok(())
}

/// Who measured and when: the first fields of every report.
#[derive(Clone, Debug, Serialize)]
pub struct Header {
    /// YYYY-MM-DD.
    pub date: String,
    /// Adapter name.
    pub adapter: String,
    /// wgpu backend.
    pub backend: String,
    /// Driver name.
    pub driver: String,
    /// Driver version.
    pub driver_info: String,
    /// Discrete, integrated, CPU, ...
    pub device_type: String,
}

impl Header {
    /// The header for `gpu`, dated today.
    pub fn new(gpu: &Gpu) -> Self {
        let i = &gpu.info;
        Self {
            date: today(),
            adapter: i.name.clone(),
            backend: format!("{:?}", i.backend),
            driver: i.driver.clone(),
            driver_info: i.driver_info.clone(),
            device_type: format!("{:?}", i.device_type),
        }
    }

    /// `<prefix><adapter-slug>-<date>`: the report's file name without extension.
    pub fn file_stem(&self, prefix: &str) -> String {
        let slug: String = self
            .adapter
            .to_lowercase()
            .chars()
            .map(|c| if c.is_ascii_alphanumeric() { c } else { '-' })
            .collect();
        let slug = slug
            .split('-')
            .filter(|s| !s.is_empty())
            .collect::<Vec<_>>()
            .join("-");
        format!("{prefix}{slug}-{}", self.date)
    }

    /// The Markdown title and the adapter/driver/date/timing lines.
    pub fn markdown(&self, title: &str, frames: u32) -> String {
        format!(
            "# {title} on {} ({})\n\n- Date: {}\n- Adapter: {} ({}, {})\n- Driver: {} {}\n- Timing: GPU timestamp queries, median (and minimum) of {frames} frames after 10 warm-up frames\n\n",
            self.adapter,
            self.backend,
            self.date,
            self.adapter,
            self.device_type,
            self.backend,
            self.driver,
            self.driver_info,
        )
    }
}
