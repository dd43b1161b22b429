//! wgpu plumbing shared by every kernel of the workspace.
//!
//! - [`Gpu`]: instance, adapter, device and queue chosen from the environment
//!   (`WGPU_BACKEND`, `WGPU_ADAPTER_NAME`, `WGPU_POWER_PREF`), with only the optional
//!   features the adapter has and the adapter's own limits.
//! - [`DeviceNeeds`]: the features and limits a kernel states; [`test_device`], the device
//!   helper every GPU test uses (default limits + stated needs; skips with a reason, fails
//!   under `CI`).
//! - [`shader`]: each crate's WGSL [`shader::Library`], `#import`, one specialisation
//!   mechanism, naga validation.
//! - [`kernel`]: explicit bind-group layouts from binding kinds, pipelines, [`kernel::Passes`].
//! - [`transfer`]: upload and readback helpers.
//! - [`PassTimer`]: GPU time of named passes from timestamp queries.
//!
//! ```no_run
//! let gpu = gpu::Gpu::from_env()?;
//! println!("running on {}", gpu.describe());
//! # Ok::<(), gpu::GpuError>(())
//! ```

mod device;
pub mod kernel;
pub mod shader;
mod timer;
pub mod transfer;

pub use device::{DeviceNeeds, Gpu, OPTIONAL_FEATURES, test_device};
pub use timer::{PassTime, PassTimer, PassTiming};
pub use wgpu;

/// Everything that can go wrong while talking to the GPU.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// No adapter at all (no Vulkan/Metal/DX12 driver).
    #[error(
        "no GPU adapter found ({0}); install a Vulkan driver (e.g. Debian's mesa-vulkan-drivers) or use the CPU path"
    )]
    NoAdapter(String),
    /// `WGPU_ADAPTER_NAME` names no adapter present.
    #[error("WGPU_ADAPTER_NAME={wanted:?} matches no adapter; available: {available}")]
    AdapterNotFound {
        /// The requested name.
        wanted: String,
        /// Adapters that exist, comma-separated.
        available: String,
    },
    /// The adapter refused to create a device.
    #[error("could not create a device on {adapter}: {source}")]
    RequestDevice {
        /// Adapter name.
        adapter: String,
        /// wgpu's error.
        source: wgpu::RequestDeviceError,
    },
    /// A shader file is missing or does not compile.
    #[error("shader {name}: {message}")]
    Shader {
        /// Path relative to `shaders/`.
        name: String,
        /// What is wrong.
        message: String,
    },
    /// A texture or buffer handed to a kernel's `bind` does not fit it.
    #[error("{what} {problem}")]
    Resource {
        /// The resource, as the kernel names it.
        what: String,
        /// What is wrong (size, format, usage).
        problem: String,
    },
    /// The device lacks features or limits a kernel needs.
    #[error("the device lacks what this kernel needs: {0}")]
    Unsupported(String),
    /// A resource is larger than the device allows.
    #[error("{what} needs {needed} but the device allows at most {limit}")]
    TooLarge {
        /// The resource.
        what: String,
        /// Requested size.
        needed: u64,
        /// Device limit.
        limit: u64,
    },
    /// The device could not allocate what a kernel or renderer asked for.
    #[error("{what}: the device is out of memory ({message})")]
    OutOfMemory {
        /// What was being allocated.
        what: String,
        /// wgpu's error.
        message: String,
    },
    /// Data handed to an upload does not have the size the resource needs.
    #[error("{0}")]
    DataSize(String),
    /// Mapping a buffer for readback failed or the device was lost.
    #[error("GPU readback failed: {0}")]
    Readback(String),
}
