//! Timestamp queries: GPU time per pass, for benchmarks (`shikki bench`, `cargo bench`).

use super::device::DeviceShared;
use super::error::{GpuError, VkResultExt};
use ash::vk;
use std::sync::Arc;

/// A pool of `capacity` timestamps. Reset inside the command buffer before use.
pub struct TimestampPool {
    pub(crate) raw: vk::QueryPool,
    capacity: u32,
    period_ns: f64,
    shared: Arc<DeviceShared>,
}

impl TimestampPool {
    pub(crate) fn new(shared: &Arc<DeviceShared>, capacity: u32) -> Result<Self, GpuError> {
        let info = vk::QueryPoolCreateInfo::default()
            .query_type(vk::QueryType::TIMESTAMP)
            .query_count(capacity);
        // SAFETY: valid device; info lives until return.
        let raw =
            unsafe { shared.device.create_query_pool(&info, None) }.during("vkCreateQueryPool")?;
        Ok(Self {
            raw,
            capacity,
            period_ns: f64::from(shared.info.timestamp_period_ns),
            shared: Arc::clone(shared),
        })
    }

    pub fn capacity(&self) -> u32 {
        self.capacity
    }

    /// The first `count` timestamps in nanoseconds, after the submit that wrote them finished.
    pub fn read_ns(&self, count: u32) -> Result<Vec<f64>, GpuError> {
        let count = count.min(self.capacity);
        let mut ticks = vec![0u64; count as usize];
        // SAFETY: the queries were written by a completed submit; WAIT makes the call block
        // until results are available, and the slice holds exactly `count` u64 values.
        unsafe {
            self.shared.device.get_query_pool_results(
                self.raw,
                0,
                &mut ticks,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }
        .during("vkGetQueryPoolResults")?;
        Ok(ticks.iter().map(|&t| t as f64 * self.period_ns).collect())
    }
}

impl Drop for TimestampPool {
    fn drop(&mut self) {
        // SAFETY: no pending work uses the pool (submits wait on their fences).
        unsafe { self.shared.device.destroy_query_pool(self.raw, None) };
    }
}
