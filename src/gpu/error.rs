//! GPU errors, and the one mapping from `vk::Result` to them.
//!
//! | `vk::Result`                                   | `GpuError`                      |
//! |------------------------------------------------|---------------------------------|
//! | `ERROR_OUT_OF_HOST_MEMORY`, `…_DEVICE_MEMORY`    | `OutOfMemory` (names the call)  |
//! | `ERROR_DEVICE_LOST`                            | `DeviceLost`                    |
//! | `ERROR_INCOMPATIBLE_DRIVER`                    | `NoDevice` (install hint)       |
//! | anything else                                  | `Vulkan { call, result }`       |

use ash::vk;

/// What can go wrong below the renderer.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    #[error(
        "cannot load the Vulkan loader (libvulkan.so.1): {detail}. \
         Install it, with a driver: apt-get install libvulkan1 mesa-vulkan-drivers"
    )]
    NoLoader { detail: String },
    #[error(
        "no usable Vulkan 1.3 device{detail}. Install a driver; with no GPU, the CPU driver \
         lavapipe: apt-get install mesa-vulkan-drivers"
    )]
    NoDevice { detail: String },
    #[error(
        "the device name {wanted:?} (SHIKKI_DEVICE; in the C API options.device_name) matches \
         no Vulkan device; the devices are: {available}"
    )]
    DeviceNotFound { wanted: String, available: String },
    #[error(
        "validation was requested but the layer VK_LAYER_KHRONOS_validation is not installed: \
         apt-get install vulkan-validationlayers, or turn validation off (unset \
         SHIKKI_VALIDATION; in the C API options.validation = false)"
    )]
    ValidationLayerMissing,
    #[error("the Vulkan device {device:?} lacks {what}, which shikki needs")]
    MissingFeature { device: String, what: String },
    #[error("out of memory in {call}: reduce the image size or the number of samples")]
    OutOfMemory { call: &'static str },
    #[error("the Vulkan device was lost during {call} (driver crash or reset)")]
    DeviceLost { call: &'static str },
    #[error("GPU work did not finish within {seconds} s; the driver may be hung")]
    Timeout { seconds: u64 },
    #[error("Vulkan call {call} failed: {result:?}")]
    Vulkan {
        call: &'static str,
        result: vk::Result,
    },
    #[error("GPU memory allocation for {name} failed: {detail}")]
    Allocation { name: String, detail: String },
    #[error("{what} = {value} exceeds the device limit {limit}")]
    Limit {
        what: &'static str,
        value: u64,
        limit: u64,
    },
    #[error("{count} Vulkan validation message(s):\n{messages}")]
    Validation { count: usize, messages: String },
    #[error("cannot save the pipeline cache {path}: {detail} (set SHIKKI_PIPELINE_CACHE=0 to run without one)")]
    PipelineCache {
        path: std::path::PathBuf,
        detail: String,
    },
    #[error("invalid SPIR-V for {name}: {detail}")]
    Shader { name: &'static str, detail: String },
}

/// Adds the name of the failing call to a `vk::Result`.
pub(crate) trait VkResultExt<T> {
    fn during(self, call: &'static str) -> Result<T, GpuError>;
}

impl<T> VkResultExt<T> for Result<T, vk::Result> {
    fn during(self, call: &'static str) -> Result<T, GpuError> {
        self.map_err(|result| from_vk(call, result))
    }
}

pub(crate) fn from_vk(call: &'static str, result: vk::Result) -> GpuError {
    match result {
        vk::Result::ERROR_OUT_OF_HOST_MEMORY | vk::Result::ERROR_OUT_OF_DEVICE_MEMORY => {
            GpuError::OutOfMemory { call }
        }
        vk::Result::ERROR_DEVICE_LOST => GpuError::DeviceLost { call },
        vk::Result::ERROR_INCOMPATIBLE_DRIVER => GpuError::NoDevice {
            detail: format!(" ({call}: incompatible driver)"),
        },
        result => GpuError::Vulkan { call, result },
    }
}
