//! Collects what the Khronos validation layer reports, so that tests and the CLI can treat any message as a
//! failure instead of letting it scroll past on stderr.

use std::ffi::{CStr, c_void};
use std::sync::{Arc, Mutex};

use ash::vk;

const PRINTED: usize = 10;

/// Messages of severity warning or error reported by the debug messenger, in arrival order.
#[derive(Default, Debug)]
pub struct ValidationLog {
    messages: Mutex<Vec<String>>,
}

impl ValidationLog {
    pub fn messages(&self) -> Vec<String> {
        self.messages.lock().unwrap().clone()
    }

    pub fn is_empty(&self) -> bool {
        self.messages.lock().unwrap().is_empty()
    }

    fn push(&self, message: String) {
        let mut messages = self.messages.lock().unwrap();
        // The first few are printed as they come; a broken loop can report thousands.
        if messages.len() < PRINTED {
            eprintln!("validation: {message}");
        } else if messages.len() == PRINTED {
            eprintln!("validation: further messages are counted, not printed");
        }
        messages.push(message);
    }
}

/// Severities and types that count: warnings and errors from validation, and errors of any type.
pub(crate) fn messenger_info(log: &Arc<ValidationLog>) -> vk::DebugUtilsMessengerCreateInfoEXT<'static> {
    vk::DebugUtilsMessengerCreateInfoEXT::default()
        .message_severity(vk::DebugUtilsMessageSeverityFlagsEXT::WARNING | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR)
        .message_type(
            vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE
                | vk::DebugUtilsMessageTypeFlagsEXT::GENERAL,
        )
        .pfn_user_callback(Some(callback))
        // The instance keeps an `Arc` clone alive for as long as the messenger exists.
        .user_data(Arc::as_ptr(log) as *mut c_void)
}

unsafe extern "system" fn callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    kind: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user_data: *mut c_void,
) -> vk::Bool32 {
    let is_validation =
        kind.intersects(vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE);
    if !is_validation && severity != vk::DebugUtilsMessageSeverityFlagsEXT::ERROR {
        return vk::FALSE; // loader chatter at warning level is not a validation finding
    }
    // SAFETY: the layer passes valid callback data; `user_data` points at the `ValidationLog` held by the
    // instance that owns this messenger.
    let (log, text) = unsafe {
        let data = &*data;
        let text = if data.p_message.is_null() {
            String::from("(no message)")
        } else {
            CStr::from_ptr(data.p_message).to_string_lossy().into_owned()
        };
        (&*(user_data as *const ValidationLog), text)
    };
    log.push(format!("[{severity:?}] {text}"));
    vk::FALSE
}
