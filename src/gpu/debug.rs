//! Validation messages: collected, never just printed, so a test can fail on any of them.
//!
//! The messenger's callback receives a pointer to the [`ValidationLog`]'s shared vector; the log
//! is kept alive by the device (`DeviceShared`) for as long as the messenger exists.

use ash::vk;
use std::ffi::{c_void, CStr};
use std::sync::{Arc, Mutex};

/// Messages of severity warning or error, in arrival order.
#[derive(Clone, Default)]
pub struct ValidationLog {
    messages: Arc<Mutex<Vec<String>>>,
}

impl ValidationLog {
    /// Removes and returns the messages collected so far.
    pub fn take(&self) -> Vec<String> {
        match self.messages.lock() {
            Ok(mut guard) => std::mem::take(&mut *guard),
            Err(poisoned) => std::mem::take(&mut *poisoned.into_inner()),
        }
    }

    /// The pointer handed to Vulkan as `pUserData`.
    pub(crate) fn user_data(&self) -> *mut c_void {
        Arc::as_ptr(&self.messages) as *mut c_void
    }
}

/// The create-info for the messenger (also chained into instance creation, so messages from
/// `vkCreateInstance` itself are caught).
pub(crate) fn messenger_info(log: &ValidationLog) -> vk::DebugUtilsMessengerCreateInfoEXT<'static> {
    vk::DebugUtilsMessengerCreateInfoEXT::default()
        .message_severity(
            vk::DebugUtilsMessageSeverityFlagsEXT::WARNING
                | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR,
        )
        .message_type(
            vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
        )
        .pfn_user_callback(Some(on_message))
        .user_data(log.user_data())
}

unsafe extern "system" fn on_message(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    kind: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user_data: *mut c_void,
) -> vk::Bool32 {
    if data.is_null() || user_data.is_null() {
        return vk::FALSE;
    }
    // SAFETY: Vulkan passes a valid callback-data struct for the duration of the call.
    let data = unsafe { &*data };
    let text = if data.p_message.is_null() {
        "(no message)".to_string()
    } else {
        // SAFETY: p_message is a NUL-terminated string owned by the layer for this call.
        unsafe { CStr::from_ptr(data.p_message) }
            .to_string_lossy()
            .into_owned()
    };
    // SAFETY: user_data is the Arc<Mutex<Vec<String>>> of a ValidationLog that the device keeps
    // alive until after the messenger is destroyed.
    let messages = unsafe { &*(user_data as *const Mutex<Vec<String>>) };
    if let Ok(mut guard) = messages.lock() {
        guard.push(format!("[{severity:?} {kind:?}] {text}"));
    }
    vk::FALSE
}
