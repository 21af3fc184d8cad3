//! Loading Vulkan and creating the instance (with the validation layer and its messenger when
//! asked for).

use super::debug::{messenger_info, ValidationLog};
use super::error::{GpuError, VkResultExt};
use ash::vk;
use std::ffi::CStr;

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// The loaded library, the instance and (with validation) the messenger.
pub(crate) struct InstanceParts {
    pub entry: ash::Entry,
    pub instance: ash::Instance,
    pub debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
}

pub(crate) fn create_instance(
    validation: bool,
    synchronization_validation: bool,
    log: &ValidationLog,
) -> Result<InstanceParts, GpuError> {
    // SAFETY: loading libvulkan runs its initialisers; we trust the system's Vulkan loader.
    let entry = unsafe { ash::Entry::load() }.map_err(|e| GpuError::NoLoader {
        detail: e.to_string(),
    })?;

    if validation && !has_layer(&entry, VALIDATION_LAYER)? {
        return Err(GpuError::ValidationLayerMissing);
    }

    let app_info = vk::ApplicationInfo::default()
        .application_name(c"shikki")
        .engine_name(c"shikki")
        .api_version(vk::API_VERSION_1_3);
    let layers = [VALIDATION_LAYER.as_ptr()];
    let extensions = [ash::ext::debug_utils::NAME.as_ptr()];
    let mut debug_info = messenger_info(log);
    let enabled_features = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
    let mut features =
        vk::ValidationFeaturesEXT::default().enabled_validation_features(&enabled_features);
    let mut create_info = vk::InstanceCreateInfo::default().application_info(&app_info);
    if validation {
        create_info = create_info
            .enabled_layer_names(&layers)
            .enabled_extension_names(&extensions)
            .push_next(&mut debug_info);
        if synchronization_validation {
            create_info = create_info.push_next(&mut features);
        }
    }
    // SAFETY: create_info and everything it points to live until the call returns.
    let instance =
        unsafe { entry.create_instance(&create_info, None) }.during("vkCreateInstance")?;

    let debug = if validation {
        let loader = ash::ext::debug_utils::Instance::new(&entry, &instance);
        let info = messenger_info(log);
        // SAFETY: the instance is valid and the log outlives the messenger (see debug.rs).
        match unsafe { loader.create_debug_utils_messenger(&info, None) } {
            Ok(messenger) => Some((loader, messenger)),
            Err(result) => {
                // SAFETY: nothing else was created from the instance yet.
                unsafe { instance.destroy_instance(None) };
                return Err(super::error::from_vk(
                    "vkCreateDebugUtilsMessengerEXT",
                    result,
                ));
            }
        }
    } else {
        None
    };
    Ok(InstanceParts {
        entry,
        instance,
        debug,
    })
}

fn has_layer(entry: &ash::Entry, name: &CStr) -> Result<bool, GpuError> {
    // SAFETY: a plain query on a loaded entry.
    let layers = unsafe { entry.enumerate_instance_layer_properties() }
        .during("vkEnumerateInstanceLayerProperties")?;
    Ok(layers
        .iter()
        .any(|layer| layer.layer_name_as_c_str().is_ok_and(|n| n == name)))
}
