//! Adapter and device selection from the environment, and the test helper.

use std::sync::Mutex;

use crate::GpuError;

/// What a kernel needs of a device beyond wgpu's defaults: required features and limits.
///
/// Each crate states its needs (`interleave::device_needs()`, …); a caller creating its own
/// device requests `needs.limits` and `needs.features`. Needs combine with [`DeviceNeeds::and`].
#[derive(Clone, Debug, PartialEq)]
pub struct DeviceNeeds {
    /// Features that must be present.
    pub features: wgpu::Features,
    /// Limits that must be met (at least `wgpu::Limits::default()`).
    pub limits: wgpu::Limits,
}

impl Default for DeviceNeeds {
    /// No features, `wgpu::Limits::default()`.
    fn default() -> Self {
        Self {
            features: wgpu::Features::empty(),
            limits: wgpu::Limits::default(),
        }
    }
}

impl DeviceNeeds {
    /// What both `self` and `other` need.
    pub fn and(self, other: &DeviceNeeds) -> Self {
        Self {
            features: self.features | other.features,
            limits: self.limits.or_better_values_from(&other.limits),
        }
    }

    /// Fails with [`GpuError::Unsupported`] naming every missing feature and limit when
    /// `features`/`limits` (a device's or an adapter's) do not meet these needs.
    pub fn check(&self, features: wgpu::Features, limits: &wgpu::Limits) -> Result<(), GpuError> {
        let mut missing = Vec::new();
        let absent = self.features - features;
        if !absent.is_empty() {
            missing.push(format!("features {absent:?}"));
        }
        self.limits
            .check_limits_with_fail_fn(limits, false, |name, needed, allowed| {
                missing.push(format!("{name} {needed} (has {allowed})"))
            });
        if missing.is_empty() {
            Ok(())
        } else {
            Err(GpuError::Unsupported(missing.join(", ")))
        }
    }

    /// A device descriptor requesting exactly these features and limits: what an application
    /// embedding a crate passes to `Adapter::request_device`.
    pub fn descriptor(&self) -> wgpu::DeviceDescriptor<'static> {
        wgpu::DeviceDescriptor {
            label: None,
            required_features: self.features,
            required_limits: self.limits.clone(),
            ..Default::default()
        }
    }

    /// [`DeviceNeeds::check`] against `device`.
    pub fn check_device(&self, device: &wgpu::Device) -> Result<(), GpuError> {
        self.check(device.features(), &device.limits())
    }
}

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
    .union(wgpu::Features::TEXTURE_FORMAT_16BIT_NORM)
    .union(wgpu::Features::FLOAT32_BLENDABLE)
    .union(wgpu::Features::DEPTH_CLIP_CONTROL)
    // The visibility buffer's compute rasteriser (`gbuffer::gpu::visibility`).
    .union(wgpu::Features::SHADER_INT64)
    .union(wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX)
    // Its resolve in one dispatch (binding arrays of the scene's textures).
    .union(wgpu::Features::TEXTURE_BINDING_ARRAY)
    .union(wgpu::Features::SAMPLED_TEXTURE_AND_STORAGE_BUFFER_ARRAY_NON_UNIFORM_INDEXING);

impl Gpu {
    /// Chooses an adapter from the environment and creates its device.
    ///
    /// `WGPU_BACKEND` (e.g. `vulkan`) limits the backends, `WGPU_ADAPTER_NAME` picks the first
    /// adapter whose name contains the given text (case-insensitive), `WGPU_POWER_PREF`
    /// (`low`/`high`) guides the default choice.
    /// The device gets the adapter's own limits (programs want the largest buffers); see
    /// [`Gpu::from_env_with`] for a device with exactly stated needs.
    pub fn from_env() -> Result<Self, GpuError> {
        pollster::block_on(Self::from_env_async(None))
    }

    /// Like [`Gpu::from_env`], but the device has `wgpu`'s default limits raised only as far as
    /// `needs` states (plus the optional features the adapter has): what an embedding
    /// application would create, and what tests use, so a kernel needing more than it states
    /// fails.
    pub fn from_env_with(needs: &DeviceNeeds) -> Result<Self, GpuError> {
        pollster::block_on(Self::from_env_async(Some(needs)))
    }

    async fn from_env_async(needs: Option<&DeviceNeeds>) -> Result<Self, GpuError> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        Self::from_instance(instance, needs, None).await
    }

    /// Like [`Gpu::from_env`] on `instance` (made by a windowing program with its display
    /// handle), with an adapter that can present to `surface`: what an interactive viewer
    /// needs. `WGPU_ADAPTER_NAME` picks among the adapters that can.
    pub fn for_surface(
        instance: wgpu::Instance,
        surface: &wgpu::Surface<'_>,
    ) -> Result<Self, GpuError> {
        pollster::block_on(Self::from_instance(instance, None, Some(surface)))
    }

    async fn from_instance(
        instance: wgpu::Instance,
        needs: Option<&DeviceNeeds>,
        surface: Option<&wgpu::Surface<'_>>,
    ) -> Result<Self, GpuError> {
        let adapter = match std::env::var("WGPU_ADAPTER_NAME") {
            Ok(wanted) if !wanted.is_empty() => {
                let adapters = instance.enumerate_adapters(wgpu::Backends::all()).await;
                let presents =
                    |a: &wgpu::Adapter| surface.is_none_or(|s| a.is_surface_supported(s));
                let needle = wanted.to_lowercase();
                let names: Vec<String> = adapters
                    .iter()
                    .filter(|a| presents(a))
                    .map(|a| a.get_info().name)
                    .collect();
                adapters
                    .into_iter()
                    .filter(presents)
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
                    compatible_surface: surface,
                    ..Default::default()
                })
                .await
                .map_err(|e| GpuError::NoAdapter(e.to_string()))?,
        };
        let info = adapter.get_info();
        let (features, limits) = match needs {
            Some(needs) => {
                needs.check(adapter.features(), &adapter.limits())?;
                (needs.features, needs.limits.clone())
            }
            None => (wgpu::Features::empty(), adapter.limits()),
        };
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("deferred toolkit device"),
                required_features: features | (adapter.features() & OPTIONAL_FEATURES),
                required_limits: limits,
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

/// The device for GPU tests: `wgpu::Limits::default()` raised only to what `needs` states.
///
/// Returns `None` (and prints why) when no adapter exists or it cannot meet `needs`, so the
/// caller can skip the test; when the environment variable `CI` is set, that is a failure
/// instead: GPU tests never pass silently without running. Tests of one process asking for
/// the same needs share one device.
///
/// ```no_run
/// let Some(gpu) = gpu::test_device(&gpu::DeviceNeeds::default()) else { return };
/// assert!(!gpu.info.name.is_empty());
/// ```
pub fn test_device(needs: &DeviceNeeds) -> Option<&'static Gpu> {
    type Devices = Vec<(DeviceNeeds, Result<&'static Gpu, String>)>;
    static DEVICES: Mutex<Devices> = Mutex::new(Vec::new());
    let mut devices = DEVICES.lock().unwrap_or_else(|e| e.into_inner());
    let result = match devices.iter().find(|(n, _)| n == needs) {
        Some((_, r)) => r.clone(),
        None => {
            let r = Gpu::from_env_with(needs)
                .map(|g| &*Box::leak(Box::new(g)))
                .map_err(|e| e.to_string());
            devices.push((needs.clone(), r.clone()));
            r
        }
    };
    match result {
        Ok(gpu) => Some(gpu),
        Err(reason) if std::env::var_os("CI").is_some() => {
            panic!("CI is set and no GPU device meets the test's needs: {reason}")
        }
        Err(reason) => {
            eprintln!("skipping GPU test: {reason}");
            None
        }
    }
}
