//! Adapter and device selection from the environment, and the test helper.

use std::sync::OnceLock;

use crate::GpuError;

/// An adapter with its device and queue.
///
/// Kernels never own this: they borrow `device` and `queue` and record into the caller's
/// encoders. `Gpu` exists for programs, tests and examples that need one device quickly.
pub struct Gpu {
    /// The wgpu instance the adapter came from.
    pub instance: wgpu::Instance,
    /// The chosen adapter.
    pub adapter: wgpu::Adapter,
    /// The device, created with the adapter's optional features that the toolkit uses.
    pub device: wgpu::Device,
    /// The device's queue.
    pub queue: wgpu::Queue,
    /// Adapter name, backend, driver.
    pub info: wgpu::AdapterInfo,
}

/// Optional features the toolkit uses when the adapter has them.
pub const OPTIONAL_FEATURES: wgpu::Features = wgpu::Features::TIMESTAMP_QUERY
    .union(wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS)
    .union(wgpu::Features::SUBGROUP)
    .union(wgpu::Features::FLOAT32_FILTERABLE)
    .union(wgpu::Features::TEXTURE_FORMAT_16BIT_NORM);

impl Gpu {
    /// Chooses an adapter from the environment and creates its device.
    ///
    /// `WGPU_BACKEND` (e.g. `vulkan`) limits the backends, `WGPU_ADAPTER_NAME` picks the first
    /// adapter whose name contains the given text (case-insensitive), `WGPU_POWER_PREF`
    /// (`low`/`high`) guides the default choice.
    pub fn from_env() -> Result<Self, GpuError> {
        pollster::block_on(Self::from_env_async())
    }

    async fn from_env_async() -> Result<Self, GpuError> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let adapter = match std::env::var("WGPU_ADAPTER_NAME") {
            Ok(wanted) if !wanted.is_empty() => {
                let adapters = instance.enumerate_adapters(wgpu::Backends::all()).await;
                let needle = wanted.to_lowercase();
                let names: Vec<String> = adapters.iter().map(|a| a.get_info().name).collect();
                adapters
                    .into_iter()
                    .find(|a| a.get_info().name.to_lowercase().contains(&needle))
                    .ok_or_else(|| GpuError::AdapterNotFound {
                        wanted,
                        available: if names.is_empty() {
                            "none".into()
                        } else {
                            names.join(", ")
                        },
                    })?
            }
            _ => instance
                .request_adapter(&wgpu::RequestAdapterOptions {
                    power_preference: wgpu::PowerPreference::from_env()
                        .unwrap_or(wgpu::PowerPreference::HighPerformance),
                    ..Default::default()
                })
                .await
                .map_err(|e| GpuError::NoAdapter(e.to_string()))?,
        };
        let info = adapter.get_info();
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("deferred toolkit device"),
                required_features: adapter.features() & OPTIONAL_FEATURES,
                required_limits: adapter.limits(),
                ..Default::default()
            })
            .await
            .map_err(|source| GpuError::RequestDevice {
                adapter: info.name.clone(),
                source,
            })?;
        Ok(Self {
            instance,
            adapter,
            device,
            queue,
            info,
        })
    }

    /// Whether GPU pass timing with timestamp queries is available.
    pub fn has_timestamps(&self) -> bool {
        self.device
            .features()
            .contains(wgpu::Features::TIMESTAMP_QUERY)
    }

    /// One line naming the adapter, its backend and driver.
    pub fn describe(&self) -> String {
        let i = &self.info;
        format!(
            "{} ({:?}, driver {} {})",
            i.name, i.backend, i.driver, i.driver_info
        )
    }

    /// True for software rasterizers (llvmpipe, lavapipe, WARP, SwiftShader).
    pub fn is_software(&self) -> bool {
        self.info.device_type == wgpu::DeviceType::Cpu
    }

    /// Blocks until all submitted work is done.
    pub fn wait(&self) -> Result<(), GpuError> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|e| GpuError::Readback(e.to_string()))
    }
}

/// The shared device for GPU tests.
///
/// Returns `None` (and prints why) when no adapter exists, so the caller can skip the test;
/// when the environment variable `CI` is set, a missing adapter is a failure instead: GPU tests
/// never pass silently without running. All tests of one process share one device.
///
/// ```no_run
/// let Some(gpu) = gpu::test_gpu() else { return };
/// assert!(!gpu.info.name.is_empty());
/// ```
pub fn test_gpu() -> Option<&'static Gpu> {
    static GPU: OnceLock<Result<Gpu, String>> = OnceLock::new();
    match GPU.get_or_init(|| Gpu::from_env().map_err(|e| e.to_string())) {
        Ok(gpu) => Some(gpu),
        Err(reason) if std::env::var_os("CI").is_some() => {
            panic!("CI is set and no GPU adapter is available: {reason}")
        }
        Err(reason) => {
            eprintln!("skipping GPU test: {reason}");
            None
        }
    }
}
