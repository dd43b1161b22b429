//! GPU time of named passes from timestamp queries.

use std::sync::Mutex;

use crate::{GpuError, transfer};

/// The GPU time one named pass took.
#[derive(Clone, Debug, PartialEq)]
pub struct PassTime {
    /// Pass name, as given to [`PassTimer::render_pass`] or [`PassTimer::compute_pass`].
    pub name: String,
    /// Milliseconds between the pass's begin and end timestamps.
    pub ms: f64,
    /// Milliseconds from the first timed pass's begin to this pass's begin.
    pub start_ms: f64,
}

impl PassTime {
    /// Milliseconds from the first timed pass's begin to this pass's end.
    pub fn end_ms(&self) -> f64 {
        self.start_ms + self.ms
    }
}

/// Time one pass of a frame took, as renderers report it: GPU timestamps on a GPU path, wall
/// clock on a CPU path.
#[derive(Clone, Debug, PartialEq)]
pub struct PassTiming {
    /// Pass name.
    pub name: String,
    /// Milliseconds.
    pub ms: f64,
}

/// Records a begin and an end timestamp around each named pass and reports milliseconds.
///
/// When the device lacks `TIMESTAMP_QUERY` the timer is disabled: the pass hooks return
/// `None` and [`PassTimer::read`] returns an empty list, so callers need no special case.
/// A frame starts with [`PassTimer::reset`], so frames encoded without reading their timings
/// never fill the timer up; reading after a submission gives that frame's passes.
///
/// ```no_run
/// # let gpu = gpu::Gpu::from_env()?;
/// let timer = gpu::PassTimer::new(&gpu.device, 8);
/// let mut encoder = gpu.device.create_command_encoder(&Default::default());
/// let pass = encoder.begin_compute_pass(&gpu::wgpu::ComputePassDescriptor {
///     label: Some("shade"),
///     timestamp_writes: timer.compute_pass("shade"),
/// });
/// drop(pass);
/// timer.resolve(&mut encoder);
/// gpu.queue.submit([encoder.finish()]);
/// for t in timer.read(&gpu.device, &gpu.queue)? { println!("{}: {:.3} ms", t.name, t.ms); }
/// # Ok::<(), gpu::GpuError>(())
/// ```
pub struct PassTimer {
    queries: Option<(wgpu::QuerySet, wgpu::Buffer)>,
    capacity: u32,
    names: Mutex<Vec<String>>,
}

impl PassTimer {
    /// A timer for up to `capacity` passes per frame.
    pub fn new(device: &wgpu::Device, capacity: u32) -> Self {
        let queries = device
            .features()
            .contains(wgpu::Features::TIMESTAMP_QUERY)
            .then(|| {
                let set = device.create_query_set(&wgpu::QuerySetDescriptor {
                    label: Some("pass timer"),
                    ty: wgpu::QueryType::Timestamp,
                    count: capacity * 2,
                });
                let resolve = device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("pass timer resolve"),
                    size: u64::from(capacity) * 2 * 8,
                    usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                });
                (set, resolve)
            });
        Self {
            queries,
            capacity,
            names: Default::default(),
        }
    }

    /// Whether timestamps are recorded at all.
    pub fn enabled(&self) -> bool {
        self.queries.is_some()
    }

    fn names(&self) -> std::sync::MutexGuard<'_, Vec<String>> {
        self.names.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Forgets the passes recorded so far: call at the start of each frame's encoding.
    pub fn reset(&self) {
        self.names().clear();
    }

    fn next(&self, name: &str) -> Option<(&wgpu::QuerySet, u32)> {
        let (set, _) = self.queries.as_ref()?;
        let mut names = self.names();
        let index = names.len() as u32;
        if index >= self.capacity {
            log::warn!(
                "pass timer full ({} passes): {name} is not timed",
                self.capacity
            );
            return None;
        }
        names.push(name.to_owned());
        Some((set, index * 2))
    }

    /// Timestamp writes for a render pass named `name`.
    pub fn render_pass(&self, name: &str) -> Option<wgpu::RenderPassTimestampWrites<'_>> {
        self.next(name)
            .map(|(query_set, i)| wgpu::RenderPassTimestampWrites {
                query_set,
                beginning_of_pass_write_index: Some(i),
                end_of_pass_write_index: Some(i + 1),
            })
    }

    /// Timestamp writes for a compute pass named `name`.
    pub fn compute_pass(&self, name: &str) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        self.next(name)
            .map(|(query_set, i)| wgpu::ComputePassTimestampWrites {
                query_set,
                beginning_of_pass_write_index: Some(i),
                end_of_pass_write_index: Some(i + 1),
            })
    }

    /// Resolves the recorded timestamps; call once after the last timed pass of the encoder.
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        let count = self.names().len() as u32;
        if let Some((set, buffer)) = &self.queries
            && count > 0
        {
            encoder.resolve_query_set(set, 0..count * 2, buffer, 0);
        }
    }

    /// Waits for the submitted work, returns each pass's time and clears the list of passes.
    pub fn read(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<Vec<PassTime>, GpuError> {
        let names = std::mem::take(&mut *self.names());
        let Some((_, buffer)) = &self.queries else {
            return Ok(Vec::new());
        };
        if names.is_empty() {
            return Ok(Vec::new());
        }
        let ticks: Vec<u64> = transfer::read_pod(device, queue, buffer)?;
        let period = f64::from(queue.get_timestamp_period());
        let ms = |a: u64, b: u64| b.wrapping_sub(a) as f64 * period * 1e-6;
        Ok(names
            .into_iter()
            .enumerate()
            .map(|(i, name)| PassTime {
                name,
                ms: ms(ticks[2 * i], ticks[2 * i + 1]),
                start_ms: ms(ticks[0], ticks[2 * i]),
            })
            .collect())
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn timer_is_send_and_sync() {
        fn check<T: Send + Sync>() {}
        check::<super::PassTimer>();
    }
}
