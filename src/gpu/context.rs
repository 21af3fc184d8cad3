//! [`GpuContext`]: the device, one queue, one command pool. The renderer creates every GPU object
//! through it and submits work with [`GpuContext::submit_and_wait`].

use super::adapter::{AdapterInfo, RayTracingChoice};
use super::buffer::{Buffer, BufferDesc};
use super::command::Recorder;
use super::debug::ValidationLog;
use super::device::DeviceShared;
use super::error::{GpuError, VkResultExt};
use super::image::{Image, ImageDesc, Sampler};
use super::pipeline::{
    Binding, ComputePipeline, DescriptorSet, GraphicsPipeline, GraphicsPipelineDesc,
    PipelineLayout, Resource,
};
use super::query::TimestampPool;
use super::ray_pipeline::{RayTracingPipeline, RayTracingPipelineDesc};
use ash::vk;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// How long a submit may take before shikki reports a hung driver instead of waiting forever.
/// A CPU driver renders a 4096² MSAA image in seconds; ten minutes is far beyond any real job.
const SUBMIT_TIMEOUT_SECONDS: u64 = 600;

/// Options for creating the context.
#[derive(Clone, Debug, Default)]
pub struct ContextOptions {
    /// Enable VK_LAYER_KHRONOS_validation and collect its messages.
    pub validation: bool,
    /// Pick the first device whose name contains this (case-insensitive).
    pub device_name: Option<String>,
    /// With `validation`, also the layer's synchronisation checks (hazards between commands,
    /// missing barriers); `SHIKKI_SYNC_VALIDATION=1`.
    pub synchronization_validation: bool,
    /// A file holding the driver's pipeline cache, read at start and written by
    /// [`GpuContext::save_pipeline_cache`]: the second run starts without compiling shaders.
    pub pipeline_cache: Option<PathBuf>,
    /// How rays are traced: ray queries where the device has them, else a ray-tracing pipeline
    /// (`Auto`); the ray-tracing pipeline even where ray queries exist (`SHIKKI_RAY_QUERY=pipeline`);
    /// or not at all (`SHIKKI_RAY_QUERY=0`): the paths of devices without ray queries, which
    /// tests keep covered.
    pub ray_tracing: RayTracingChoice,
}

impl ContextOptions {
    /// `SHIKKI_VALIDATION=1` turns validation on (`SHIKKI_SYNC_VALIDATION=1` adds its
    /// synchronisation checks); `SHIKKI_DEVICE=<substring>` picks the device;
    /// `SHIKKI_RAY_QUERY=0` leaves ray tracing off, `SHIKKI_RAY_QUERY=pipeline` traces by a
    /// ray-tracing pipeline even where ray queries exist.
    /// Every way of opening a device (CLI, C API, tests) reads `SHIKKI_RAY_QUERY` here.
    pub fn ray_tracing_by_env() -> RayTracingChoice {
        match std::env::var("SHIKKI_RAY_QUERY").as_deref() {
            Ok("0") => RayTracingChoice::Off,
            Ok("pipeline") => RayTracingChoice::Pipeline,
            _ => RayTracingChoice::Auto,
        }
    }

    /// Why `SHIKKI_RAY_QUERY` is not a value [`Self::ray_tracing_by_env`] knows, if it is not:
    /// an unknown value was taken for "auto" without a word (`SHIKKI_RAY_QUERY=off`).
    pub fn ray_tracing_env_problem() -> Option<crate::Error> {
        let value = std::env::var("SHIKKI_RAY_QUERY").ok()?;
        match value.as_str() {
            "" | "0" | "1" | "auto" | "pipeline" => None,
            _ => Some(crate::Error::invalid(
                "SHIKKI_RAY_QUERY",
                format!("{value:?}"),
                "valid values are 0 (no ray tracing), pipeline (the ray-tracing pipeline even \
                 where ray queries exist), or auto / 1 / unset (ray queries where the device has \
                 them)",
            )),
        }
    }

    pub fn from_env() -> Self {
        Self {
            validation: std::env::var("SHIKKI_VALIDATION").is_ok_and(|v| v == "1"),
            device_name: std::env::var("SHIKKI_DEVICE")
                .ok()
                .filter(|s| !s.is_empty()),
            synchronization_validation: std::env::var("SHIKKI_SYNC_VALIDATION")
                .is_ok_and(|v| v == "1"),
            pipeline_cache: default_pipeline_cache(),
            ray_tracing: Self::ray_tracing_by_env(),
        }
    }
}

/// `SHIKKI_PIPELINE_CACHE` (a file, or `0` for none), else `$XDG_CACHE_HOME/shikki/pipelines.bin`
/// or `~/.cache/shikki/pipelines.bin`. The file's header names the device it belongs to.
fn default_pipeline_cache() -> Option<PathBuf> {
    match std::env::var_os("SHIKKI_PIPELINE_CACHE") {
        Some(v) if v == "0" || v.is_empty() => None,
        Some(v) => Some(PathBuf::from(v)),
        None => std::env::var_os("XDG_CACHE_HOME")
            .map(PathBuf::from)
            .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))
            .map(|dir| dir.join("shikki").join("pipelines.bin")),
    }
}

/// The cache file's data if its header (VkPipelineCacheHeaderVersionOne: length 32, version 1,
/// vendorID, deviceID, pipelineCacheUUID) matches this device; otherwise nothing — a stale or
/// foreign cache is simply not used.
fn read_pipeline_cache(path: Option<&Path>, info: &AdapterInfo) -> Vec<u8> {
    let Some(data) = path.and_then(|p| std::fs::read(p).ok()) else {
        return Vec::new();
    };
    let word = |i: usize| {
        data.get(4 * i..4 * i + 4)
            .and_then(|b| b.try_into().ok())
            .map(u32::from_le_bytes)
    };
    let (vendor, device, uuid) = info.pipeline_cache_id;
    let matches = word(0) == Some(32)
        && word(1) == Some(1)
        && word(2) == Some(vendor)
        && word(3) == Some(device)
        && data.get(16..32) == Some(&uuid[..]);
    if matches {
        data
    } else {
        Vec::new()
    }
}

struct Submission {
    queue: vk::Queue,
    pool: vk::CommandPool,
}

/// The Vulkan device shikki renders with.
pub struct GpuContext {
    submission: Mutex<Submission>,
    pub(super) shared: Arc<DeviceShared>,
    pipeline_cache_path: Option<PathBuf>,
}

impl GpuContext {
    pub fn new(options: &ContextOptions) -> Result<Self, GpuError> {
        let shared = Arc::new(DeviceShared::create(
            options.validation,
            options.synchronization_validation,
            options.device_name.as_deref(),
            options.ray_tracing,
            |info| read_pipeline_cache(options.pipeline_cache.as_deref(), info),
        )?);
        // SAFETY: the queue family was chosen with one queue; index 0 exists.
        let queue = unsafe { shared.device.get_device_queue(shared.queue_family, 0) };
        let info = vk::CommandPoolCreateInfo::default()
            .flags(vk::CommandPoolCreateFlags::TRANSIENT)
            .queue_family_index(shared.queue_family);
        // SAFETY: valid device; info lives until return.
        let pool = unsafe { shared.device.create_command_pool(&info, None) }
            .during("vkCreateCommandPool")?;
        Ok(GpuContext {
            submission: Mutex::new(Submission { queue, pool }),
            shared,
            pipeline_cache_path: options.pipeline_cache.clone(),
        })
    }

    /// Writes the driver's pipeline cache to the file named in the options (temp file + rename,
    /// so a crash never leaves a torn cache). Nothing to do without one.
    pub fn save_pipeline_cache(&self) -> Result<(), GpuError> {
        let Some(path) = &self.pipeline_cache_path else {
            return Ok(());
        };
        if self.shared.pipeline_cache == vk::PipelineCache::null() {
            return Ok(());
        }
        // SAFETY: the cache belongs to this device; the driver synchronises cache access.
        let data = unsafe {
            self.shared
                .device
                .get_pipeline_cache_data(self.shared.pipeline_cache)
        }
        .during("vkGetPipelineCacheData")?;
        let io = |e: std::io::Error| GpuError::PipelineCache {
            path: path.clone(),
            detail: e.to_string(),
        };
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir).map_err(io)?;
        }
        let temp = path.with_extension(format!("tmp.{}", std::process::id()));
        std::fs::write(&temp, &data)
            .and_then(|()| std::fs::rename(&temp, path))
            .map_err(|e| {
                let _ = std::fs::remove_file(&temp);
                io(e)
            })
    }

    pub fn info(&self) -> &AdapterInfo {
        &self.shared.info
    }

    /// The chosen driver's quirks (as in [`AdapterInfo::quirks`]).
    pub fn quirks(&self) -> super::adapter::Quirks {
        self.shared.info.quirks
    }

    /// The pipeline cache file from the options, if any: other on-disk caches (prefiltered
    /// environments) live beside it and are off when it is.
    pub fn pipeline_cache_path(&self) -> Option<&Path> {
        self.pipeline_cache_path.as_deref()
    }

    pub fn validation_enabled(&self) -> bool {
        self.shared.validation
    }

    /// Removes and returns the validation messages collected so far.
    pub fn take_validation_messages(&self) -> Vec<String> {
        self.shared.log.take()
    }

    /// A handle on the same messages that outlives the context. Object tracking reports leaked
    /// Vulkan objects while the device is destroyed, i.e. after the context and every resource
    /// made from it are dropped: keep this handle, drop them, then `take()` what shutdown said.
    pub fn validation_log(&self) -> ValidationLog {
        self.shared.log.clone()
    }

    /// Bytes of device memory allocated through gpu-allocator right now (the live buffers' and
    /// images' allocations, not the memory blocks they are carved from). The same set of live
    /// resources always gives the same number, so a growing figure between identical jobs is a
    /// leak.
    pub fn memory_in_use(&self) -> u64 {
        self.shared
            .allocator()
            .generate_report()
            .total_allocated_bytes
    }

    /// `Err` with every message if validation reported anything since the last call.
    pub fn check_validation(&self) -> Result<(), GpuError> {
        let messages = self.take_validation_messages();
        if messages.is_empty() {
            Ok(())
        } else {
            Err(GpuError::Validation {
                count: messages.len(),
                messages: messages.join("\n"),
            })
        }
    }

    pub fn create_buffer(&self, desc: BufferDesc) -> Result<Buffer, GpuError> {
        Buffer::new(&self.shared, desc)
    }

    pub fn create_image(&self, desc: ImageDesc) -> Result<Image, GpuError> {
        Image::new(&self.shared, desc)
    }

    pub fn create_timestamp_pool(&self, capacity: u32) -> Result<TimestampPool, GpuError> {
        TimestampPool::new(&self.shared, capacity)
    }

    pub fn create_sampler(&self) -> Result<Sampler, GpuError> {
        Sampler::linear_clamp(&self.shared)
    }

    pub fn create_compute_pipeline(
        &self,
        name: &'static str,
        spirv: &[u8],
        bindings: &[Binding],
        push_constant_size: u32,
    ) -> Result<ComputePipeline, GpuError> {
        ComputePipeline::new(&self.shared, name, spirv, bindings, push_constant_size, &[])
    }

    /// [`create_compute_pipeline`](Self::create_compute_pipeline) with 32-bit specialization
    /// constants: entry i sets `constant_id = i`.
    pub fn create_specialized_compute_pipeline(
        &self,
        name: &'static str,
        spirv: &[u8],
        bindings: &[Binding],
        constants: &[u32],
    ) -> Result<ComputePipeline, GpuError> {
        ComputePipeline::new(&self.shared, name, spirv, bindings, 0, constants)
    }

    pub fn create_graphics_pipeline(
        &self,
        desc: &GraphicsPipelineDesc<'_>,
    ) -> Result<GraphicsPipeline, GpuError> {
        GraphicsPipeline::new(&self.shared, desc)
    }

    /// A ray-tracing pipeline (the device traces rays by one: `RayQuery::Pipeline`).
    pub fn create_ray_tracing_pipeline(
        &self,
        desc: &RayTracingPipelineDesc<'_>,
    ) -> Result<RayTracingPipeline, GpuError> {
        RayTracingPipeline::new(&self.shared, desc)
    }

    pub fn create_descriptor_set(
        &self,
        layout: &PipelineLayout,
        resources: &[(u32, Resource<'_>)],
    ) -> Result<DescriptorSet, GpuError> {
        DescriptorSet::new(&self.shared, layout, resources)
    }

    /// Records commands with `record`, submits them and waits for completion. Host writes to
    /// mapped buffers made before this call are visible to the commands (queue submission is a
    /// host→device memory dependency); for readback, `record` must end with a barrier to
    /// `Access::HostRead`.
    pub fn submit_and_wait<R>(
        &self,
        record: impl FnOnce(&mut Recorder<'_>) -> Result<R, GpuError>,
    ) -> Result<R, GpuError> {
        let submission = self
            .submission
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner());
        let device = &self.shared.device;
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(submission.pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        // SAFETY: the pool is owned by this context and guarded by the mutex.
        let cmd = unsafe { device.allocate_command_buffers(&alloc) }
            .during("vkAllocateCommandBuffers")?[0];
        let result = self.record_and_run(&submission, cmd, record);
        // SAFETY: the command buffer has finished executing (or was never submitted).
        unsafe { device.free_command_buffers(submission.pool, std::slice::from_ref(&cmd)) };
        result
    }

    fn record_and_run<R>(
        &self,
        submission: &Submission,
        cmd: vk::CommandBuffer,
        record: impl FnOnce(&mut Recorder<'_>) -> Result<R, GpuError>,
    ) -> Result<R, GpuError> {
        let device = &self.shared.device;
        let begin = vk::CommandBufferBeginInfo::default()
            .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        // SAFETY: freshly allocated command buffer.
        unsafe { device.begin_command_buffer(cmd, &begin) }.during("vkBeginCommandBuffer")?;
        let mut recorder = Recorder { device, cmd };
        let recorded = record(&mut recorder);
        // SAFETY: the buffer is in the recording state; ending it is required even on error.
        let ended = unsafe { device.end_command_buffer(cmd) }.during("vkEndCommandBuffer");
        let value = recorded?;
        ended?;

        // SAFETY: valid device.
        let fence = unsafe { device.create_fence(&vk::FenceCreateInfo::default(), None) }
            .during("vkCreateFence")?;
        let cmd_info = vk::CommandBufferSubmitInfo::default().command_buffer(cmd);
        let submit =
            vk::SubmitInfo2::default().command_buffer_infos(std::slice::from_ref(&cmd_info));
        // SAFETY: queue access is serialised by the submission mutex held by our caller.
        let waited =
            unsafe { device.queue_submit2(submission.queue, std::slice::from_ref(&submit), fence) }
                .during("vkQueueSubmit2")
                .and_then(|()| {
                    // SAFETY: the fence belongs to this device.
                    unsafe {
                        device.wait_for_fences(
                            std::slice::from_ref(&fence),
                            true,
                            SUBMIT_TIMEOUT_SECONDS * 1_000_000_000,
                        )
                    }
                    .map_err(|result| match result {
                        vk::Result::TIMEOUT => GpuError::Timeout {
                            seconds: SUBMIT_TIMEOUT_SECONDS,
                        },
                        other => super::error::from_vk("vkWaitForFences", other),
                    })
                });
        if waited.is_ok() {
            // SAFETY: the fence has signalled, so nothing waits on it.
            unsafe { device.destroy_fence(fence, None) };
        } else {
            // The work may still be running: wait for the device before freeing anything.
            // SAFETY: valid device.
            unsafe {
                let _ = device.device_wait_idle();
                device.destroy_fence(fence, None);
            }
        }
        waited.map(|()| value)
    }
}

impl Drop for GpuContext {
    fn drop(&mut self) {
        let submission = self
            .submission
            .get_mut()
            .unwrap_or_else(|poisoned| poisoned.into_inner());
        // SAFETY: every submit waited on its fence; no command buffer from the pool is pending.
        unsafe {
            let _ = self.shared.device.device_wait_idle();
            self.shared
                .device
                .destroy_command_pool(submission.pool, None);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Validation's object tracking speaks while the device is destroyed; a log handle taken
    /// before must still hear it, or a leak could never fail a test.
    #[test]
    fn a_leaked_vulkan_object_is_reported_after_the_context_is_dropped() {
        let gpu = GpuContext::new(&ContextOptions {
            validation: true,
            device_name: std::env::var("SHIKKI_DEVICE").ok(),
            ..ContextOptions::default()
        })
        .unwrap_or_else(|e| panic!("cannot create a validated Vulkan context: {e}"));
        let log = gpu.validation_log();
        // SAFETY: a valid device; the fence is deliberately never destroyed (the leak under test).
        unsafe {
            gpu.shared
                .device
                .create_fence(&vk::FenceCreateInfo::default(), None)
        }
        .unwrap();
        assert!(log.take().is_empty());
        drop(gpu);
        let messages = log.take();
        assert!(
            messages.iter().any(|m| m.contains("VkFence")),
            "no leak report at shutdown: {messages:?}"
        );
    }

    #[test]
    fn memory_in_use_counts_live_allocations_only() {
        let gpu = GpuContext::new(&ContextOptions::default())
            .unwrap_or_else(|e| panic!("cannot create a Vulkan context: {e}"));
        let before = gpu.memory_in_use();
        let buffer = gpu
            .create_buffer(BufferDesc::upload(
                "probe",
                1 << 20,
                super::super::BufferUsage::STORAGE,
            ))
            .unwrap();
        assert!(gpu.memory_in_use() >= before + (1 << 20));
        drop(buffer);
        assert_eq!(gpu.memory_in_use(), before);
    }
}
