//! Everything that can go wrong on the GPU path, each with a message a user can act on.

use crate::shader::ShaderError;

/// What to tell a user who has no usable GPU.
pub const NO_ADAPTER_HINT: &str = "install a Vulkan driver (on Debian/Ubuntu: `apt-get install \
mesa-vulkan-drivers libvulkan1`, or run scripts/setup.sh, which also gives a CPU-only machine \
the lavapipe software driver), or render on the CPU by leaving out --gpu";

/// An error of the GPU renderer.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// wgpu found no adapter (no GPU and no software Vulkan driver).
    #[error("no GPU adapter found (backends tried: {backends}); {hint}", hint = NO_ADAPTER_HINT)]
    NoAdapter {
        /// The backends wgpu was allowed to use.
        backends: String,
    },
    /// The adapter refused to give a device.
    #[error("the GPU adapter `{adapter}` refused to create a device: {message}")]
    RequestDevice {
        /// The adapter's name.
        adapter: String,
        /// What wgpu said.
        message: String,
    },
    /// The WGSL program failed validation (names the registry entry).
    #[error(transparent)]
    Shader(#[from] ShaderError),
    /// The driver rejected a pipeline or another object.
    #[error("the GPU driver rejected {what}: {message}")]
    Driver {
        /// The object the driver rejected.
        what: String,
        /// What the driver said.
        message: String,
    },
    /// A buffer would exceed the device's limits.
    #[error(
        "{what} needs {bytes} bytes, more than this device allows in one storage buffer ({limit} bytes)"
    )]
    BufferTooLarge {
        /// The buffer.
        what: String,
        /// The bytes it needs.
        bytes: u64,
        /// The device's largest storage buffer in bytes.
        limit: u64,
    },
    /// The image is larger than the device's texture limit.
    #[error(
        "a {width}x{height} image exceeds this device's largest texture ({limit} pixels per side); render smaller or on the CPU"
    )]
    ImageTooLarge {
        /// Requested width in pixels.
        width: u32,
        /// Requested height in pixels.
        height: u32,
        /// The device's largest texture side in pixels.
        limit: u32,
    },
    /// The device was lost (driver reset, GPU removed, or a timeout).
    #[error("the GPU device was lost: {0}; re-run, or render on the CPU without --gpu")]
    DeviceLost(String),
    /// Waiting for the GPU took too long.
    #[error("the GPU did not finish within {0} s; the scene may be too expensive for this device")]
    Timeout(u64),
    /// The caller abandoned the frame between two bands ([`crate::Renderer::render_in_bands`]).
    #[error("the frame was cancelled")]
    Cancelled,
    /// Bad input (a scene that does not compile, a zero-sized image).
    #[error("{0}")]
    Invalid(String),
    /// The path tracer refused the scene or its settings (names the setting or node).
    #[error(transparent)]
    Path(#[from] fathom_pathtrace::PathTraceError),
    /// Something the CPU path tracer renders that the GPU one does not yet.
    #[error("the GPU path tracer does not support {0} yet; render it on the CPU (leave out --gpu)")]
    PathUnsupported(String),
    /// The view needs more precision than f32 positions give; use the CPU's f64 path.
    #[error(
        "the view is zoomed too deep for f32 on the GPU (pixel footprint {footprint:e} at distance \
         {distance:e} from the origin); render on the CPU, which switches to f64"
    )]
    TooDeep {
        /// The pixel footprint in world units.
        footprint: f64,
        /// The view's distance from the origin.
        distance: f64,
    },
}
