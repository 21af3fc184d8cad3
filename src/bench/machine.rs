//! The machine and driver a benchmark ran on: CPU model and cores (`/proc/cpuinfo`), Vulkan device
//! and driver version (the adapter info).

use serde::Serialize;

use crate::gpu::GpuContext;

#[derive(Clone, Debug, Serialize)]
pub struct Machine {
    pub cpu_model: String,
    /// Logical CPUs available to this process.
    pub cores: usize,
    pub os: String,
}

impl Machine {
    pub fn detect() -> Machine {
        let cpu_model = std::fs::read_to_string("/proc/cpuinfo")
            .ok()
            .and_then(|text| {
                text.lines()
                    .find(|l| l.starts_with("model name"))
                    .and_then(|l| l.split_once(':'))
                    .map(|(_, v)| v.trim().to_string())
            })
            .unwrap_or_else(|| "unknown".into());
        Machine {
            cpu_model,
            cores: std::thread::available_parallelism().map_or(1, |n| n.get()),
            os: std::env::consts::OS.to_string(),
        }
    }
}

#[derive(Clone, Debug, Serialize)]
pub struct Driver {
    pub device: String,
    pub device_type: String,
    pub driver_name: String,
    /// e.g. "Mesa 22.3.6 (LLVM 15.0.6)".
    pub driver_info: String,
    pub vulkan: String,
    /// The driver's active quirks by name (`gpu::Quirks`).
    pub quirks: Vec<String>,
}

impl Driver {
    pub fn of(gpu: &GpuContext) -> Driver {
        let info = gpu.info();
        Driver {
            device: info.name.clone(),
            device_type: info.device_type.clone(),
            driver_name: info.driver_name.clone(),
            driver_info: info.driver_info.clone(),
            vulkan: info.api_version.clone(),
            quirks: info.quirks.active().into_iter().map(String::from).collect(),
        }
    }
}
