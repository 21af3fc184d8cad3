//! [`GpuContext`]: the device, one queue, one command pool. The renderer creates every GPU object
//! through it and submits work with [`GpuContext::submit_and_wait`].

use super::adapter::AdapterInfo;
use super::buffer::{Buffer, BufferDesc};
use super::command::Recorder;
use super::device::DeviceShared;
use super::error::{GpuError, VkResultExt};
use super::image::{Image, ImageDesc, Sampler};
use super::pipeline::{
    Binding, ComputePipeline, DescriptorSet, GraphicsPipeline, GraphicsPipelineDesc,
    PipelineLayout, Resource,
};
use super::query::TimestampPool;
use ash::vk;
use std::sync::{Arc, Mutex};

/// How long a submit may take before shikki reports a hung driver instead of waiting forever.
/// lavapipe renders a 4096² MSAA image in seconds; ten minutes is far beyond any real job.
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
}

impl ContextOptions {
    /// `SHIKKI_VALIDATION=1` turns validation on (`SHIKKI_SYNC_VALIDATION=1` adds its
    /// synchronisation checks); `SHIKKI_DEVICE=<substring>` picks the device.
    pub fn from_env() -> Self {
        Self {
            validation: std::env::var("SHIKKI_VALIDATION").is_ok_and(|v| v == "1"),
            device_name: std::env::var("SHIKKI_DEVICE")
                .ok()
                .filter(|s| !s.is_empty()),
            synchronization_validation: std::env::var("SHIKKI_SYNC_VALIDATION")
                .is_ok_and(|v| v == "1"),
        }
    }
}

struct Submission {
    queue: vk::Queue,
    pool: vk::CommandPool,
}

/// The Vulkan device shikki renders with.
pub struct GpuContext {
    submission: Mutex<Submission>,
    shared: Arc<DeviceShared>,
}

impl GpuContext {
    pub fn new(options: &ContextOptions) -> Result<Self, GpuError> {
        let shared = Arc::new(DeviceShared::create(
            options.validation,
            options.synchronization_validation,
            options.device_name.as_deref(),
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
        })
    }

    pub fn info(&self) -> &AdapterInfo {
        &self.shared.info
    }

    pub fn validation_enabled(&self) -> bool {
        self.shared.validation
    }

    /// Removes and returns the validation messages collected so far.
    pub fn take_validation_messages(&self) -> Vec<String> {
        self.shared.log.take()
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
        ComputePipeline::new(&self.shared, name, spirv, bindings, push_constant_size)
    }

    pub fn create_graphics_pipeline(
        &self,
        desc: &GraphicsPipelineDesc<'_>,
    ) -> Result<GraphicsPipeline, GpuError> {
        GraphicsPipeline::new(&self.shared, desc)
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
