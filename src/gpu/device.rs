//! The logical device and everything whose lifetime is the device's: instance, messenger,
//! allocator. Resources hold an `Arc<DeviceShared>`, so the device outlives every buffer, image and
//! pipeline made from it, and `Drop` tears down in reverse creation order.

use super::adapter::{
    choose_adapter, AdapterInfo, ChosenAdapter, RayTracingChoice, RAY_PIPELINE_EXTENSIONS,
    RAY_QUERY_EXTENSIONS,
};
use super::debug::ValidationLog;
use super::error::{GpuError, VkResultExt};
use super::instance::{create_instance, InstanceParts};
use ash::vk;
use gpu_allocator::vulkan::{Allocation, Allocator, AllocatorCreateDesc};
use std::mem::ManuallyDrop;
use std::sync::{Mutex, MutexGuard};

pub(crate) struct DeviceShared {
    pub device: ash::Device,
    pub queue_family: u32,
    pub info: AdapterInfo,
    pub log: ValidationLog,
    pub validation: bool,
    /// Handed to every pipeline creation; null when there is none.
    pub pipeline_cache: vk::PipelineCache,
    /// The acceleration-structure functions, on a device that traces rays.
    pub acceleration: Option<ash::khr::acceleration_structure::Device>,
    /// The ray-tracing pipeline functions and the device's shader-group handle layout, on a
    /// device that traces rays by a ray-tracing pipeline (`RayQuery::Pipeline`).
    pub ray_pipeline: Option<RayPipelineFunctions>,
    allocator: ManuallyDrop<Mutex<Allocator>>,
    instance: InstanceParts,
}

impl DeviceShared {
    pub fn create(
        validation: bool,
        synchronization_validation: bool,
        device_name: Option<&str>,
        ray_tracing: RayTracingChoice,
        cache_data: impl FnOnce(&AdapterInfo) -> Vec<u8>,
    ) -> Result<Self, GpuError> {
        let log = ValidationLog::default();
        let instance = create_instance(validation, synchronization_validation, &log)?;
        // `log` stays alive here until the instance (and its messenger) is gone on every path.
        match create_device(&instance, device_name, ray_tracing) {
            Ok((device, adapter, allocator)) => {
                let initial = cache_data(&adapter.info);
                let info = vk::PipelineCacheCreateInfo::default().initial_data(&initial);
                // SAFETY: valid device; the initial data was checked against this device's cache
                // header by the caller (and drivers must reject incompatible data anyway). A cache
                // that cannot be made only costs speed.
                let pipeline_cache = unsafe { device.create_pipeline_cache(&info, None) }
                    .or_else(|_| {
                        // SAFETY: as above, with no initial data.
                        unsafe {
                            device.create_pipeline_cache(
                                &vk::PipelineCacheCreateInfo::default(),
                                None,
                            )
                        }
                    })
                    .unwrap_or(vk::PipelineCache::null());
                let acceleration = adapter.info.ray_query.is_enabled().then(|| {
                    ash::khr::acceleration_structure::Device::new(&instance.instance, &device)
                });
                let ray_pipeline = adapter.info.ray_query.uses_pipeline().then(|| {
                    RayPipelineFunctions::new(&instance.instance, &device, adapter.physical_device)
                });
                Ok(DeviceShared {
                    device,
                    queue_family: adapter.queue_family,
                    info: adapter.info,
                    log,
                    validation,
                    pipeline_cache,
                    acceleration,
                    ray_pipeline,
                    allocator: ManuallyDrop::new(Mutex::new(allocator)),
                    instance,
                })
            }
            Err(err) => {
                destroy_instance(&instance);
                Err(err)
            }
        }
    }

    pub fn allocator(&self) -> MutexGuard<'_, Allocator> {
        // A panic while holding the lock leaves the allocator's bookkeeping intact (its methods
        // don't unwind midway through an update), so the poisoned guard is still usable.
        self.allocator
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    pub fn free(&self, allocation: Allocation) {
        // Freeing only fails for an allocation not from this allocator, which cannot happen here.
        let _ = self.allocator().free(allocation);
    }
}

impl Drop for DeviceShared {
    fn drop(&mut self) {
        // SAFETY: every resource holding an Arc to this struct is gone, so nothing uses the device;
        // wait for queued work, then destroy allocator → device → messenger → instance.
        unsafe {
            let _ = self.device.device_wait_idle();
            self.device
                .destroy_pipeline_cache(self.pipeline_cache, None);
            ManuallyDrop::drop(&mut self.allocator);
            self.device.destroy_device(None);
        }
        destroy_instance(&self.instance);
    }
}

/// Picks the adapter and creates the logical device and its allocator; on error, everything it
/// created is destroyed again (the instance is the caller's).
fn create_device(
    instance: &InstanceParts,
    device_name: Option<&str>,
    ray_tracing: RayTracingChoice,
) -> Result<(ash::Device, ChosenAdapter, Allocator), GpuError> {
    let adapter = choose_adapter(&instance.instance, device_name, ray_tracing)?;
    // Rays traced at all (below: the features both paths share) and by a ray-tracing pipeline.
    let ray_query = adapter.info.ray_query.is_enabled();
    let ray_pipeline = adapter.info.ray_query.uses_pipeline();
    let priorities = [1.0f32];
    let queue_info = vk::DeviceQueueCreateInfo::default()
        .queue_family_index(adapter.queue_family)
        .queue_priorities(&priorities);
    let mut features13 = vk::PhysicalDeviceVulkan13Features::default()
        .dynamic_rendering(true)
        .synchronization2(true);
    // geometryShader: the ray-traced G-buffer pass reads gl_PrimitiveID; independentBlend: its
    // shading pass writes one of two colour targets in one draw (both checked with the
    // ray-query features).
    let features = vk::PhysicalDeviceFeatures::default()
        .shader_float64(adapter.info.shader_float64)
        .geometry_shader(ray_query)
        .independent_blend(ray_query);
    // Ray queries: the KHR extension structs, not Vulkan 1.4 core ones (the validation layer
    // 1.3.239 that Debian 12 ships rejects those).
    let mut features12 = vk::PhysicalDeviceVulkan12Features::default().buffer_device_address(true);
    let mut acceleration =
        vk::PhysicalDeviceAccelerationStructureFeaturesKHR::default().acceleration_structure(true);
    let mut ray_query_features = vk::PhysicalDeviceRayQueryFeaturesKHR::default().ray_query(true);
    let mut ray_pipeline_features =
        vk::PhysicalDeviceRayTracingPipelineFeaturesKHR::default().ray_tracing_pipeline(true);
    let extensions: Vec<*const std::ffi::c_char> = match (ray_query, ray_pipeline) {
        (true, false) => RAY_QUERY_EXTENSIONS.iter().map(|e| e.as_ptr()).collect(),
        (true, true) => RAY_PIPELINE_EXTENSIONS.iter().map(|e| e.as_ptr()).collect(),
        (false, _) => Vec::new(),
    };
    let mut create_info = vk::DeviceCreateInfo::default()
        .queue_create_infos(std::slice::from_ref(&queue_info))
        .enabled_features(&features)
        .enabled_extension_names(&extensions)
        .push_next(&mut features13);
    if ray_query {
        create_info = create_info
            .push_next(&mut features12)
            .push_next(&mut acceleration);
        create_info = match ray_pipeline {
            true => create_info.push_next(&mut ray_pipeline_features),
            false => create_info.push_next(&mut ray_query_features),
        };
    }
    // SAFETY: the physical device comes from this instance; create_info lives until return.
    let device = unsafe {
        instance
            .instance
            .create_device(adapter.physical_device, &create_info, None)
    }
    .during("vkCreateDevice")?;
    let allocator = Allocator::new(&AllocatorCreateDesc {
        instance: instance.instance.clone(),
        device: device.clone(),
        physical_device: adapter.physical_device,
        debug_settings: Default::default(),
        // Acceleration structures live in buffers addressed by device address.
        buffer_device_address: ray_query,
        allocation_sizes: Default::default(),
    });
    match allocator {
        Ok(allocator) => Ok((device, adapter, allocator)),
        Err(e) => {
            // SAFETY: nothing was created from the device yet.
            unsafe { device.destroy_device(None) };
            Err(GpuError::Allocation {
                name: "allocator".into(),
                detail: e.to_string(),
            })
        }
    }
}

fn destroy_instance(parts: &InstanceParts) {
    if let Some((loader, messenger)) = &parts.debug {
        // SAFETY: the messenger was created from this instance and is destroyed once.
        unsafe { loader.destroy_debug_utils_messenger(*messenger, None) };
    }
    // SAFETY: all children of the instance are destroyed by now.
    unsafe { parts.instance.destroy_instance(None) };
    let _ = &parts.entry;
}

/// The ray-tracing pipeline functions and the layout of the device's shader-group handles, which
/// a shader binding table follows (gpu/ray_pipeline.rs).
pub(crate) struct RayPipelineFunctions {
    pub functions: ash::khr::ray_tracing_pipeline::Device,
    /// Bytes of one shader group's handle.
    pub handle_size: u32,
    /// A record's stride is a multiple of this.
    pub handle_alignment: u32,
    /// Each table region starts at a multiple of this.
    pub base_alignment: u32,
}

impl RayPipelineFunctions {
    fn new(
        instance: &ash::Instance,
        device: &ash::Device,
        physical_device: vk::PhysicalDevice,
    ) -> Self {
        let mut properties = vk::PhysicalDeviceRayTracingPipelinePropertiesKHR::default();
        let mut properties2 = vk::PhysicalDeviceProperties2::default().push_next(&mut properties);
        // SAFETY: plain query on a valid physical device; the chained struct lives on this frame.
        unsafe { instance.get_physical_device_properties2(physical_device, &mut properties2) };
        RayPipelineFunctions {
            functions: ash::khr::ray_tracing_pipeline::Device::new(instance, device),
            handle_size: properties.shader_group_handle_size,
            handle_alignment: properties.shader_group_handle_alignment.max(1),
            base_alignment: properties.shader_group_base_alignment.max(1),
        }
    }
}
