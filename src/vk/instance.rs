//! The Vulkan loader and instance, with the validation layer and its messenger when asked for.

use std::ffi::{CStr, c_char};
use std::sync::{Arc, Mutex, MutexGuard};

use anyhow::{Context as _, Result, bail};
use ash::vk;

use super::validation::{ValidationLog, messenger_info};

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// How to install a driver, for messages that report a machine without one.
pub const INSTALL_HINT: &str = "install a Vulkan loader and driver, e.g. on Debian/Ubuntu \
    `sudo apt-get install libvulkan1 mesa-vulkan-drivers` (lavapipe, a CPU implementation), or your GPU vendor's driver";

/// Held around every creation and destruction of an instance or a device, and every device-level function
/// lookup. The loader keeps one process-wide list of devices that `vkCreateDevice` reads without the writer
/// holding its lock (Vulkan-Loader issue 2018): devices opened and closed on several threads at once, as the
/// tests do, crash in the loader even with an instance each. One device per process never contends for it.
pub(crate) fn loader_lock() -> MutexGuard<'static, ()> {
    static LOCK: Mutex<()> = Mutex::new(());
    LOCK.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// Owns the loader, the instance and (with validation) the debug messenger; destroys them in that reverse order.
pub struct Instance {
    pub entry: ash::Entry,
    pub raw: ash::Instance,
    debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    log: Arc<ValidationLog>,
}

impl Instance {
    /// `validation` enables `VK_LAYER_KHRONOS_validation` and records its messages in [`Instance::log`];
    /// `wanted` are further instance extensions (a window surface's).
    pub fn new(validation: bool, wanted: &[*const c_char]) -> Result<Self> {
        // SAFETY: loading the system's libvulkan; its symbols are only used through ash's checked tables.
        let entry = unsafe { ash::Entry::load() }
            .map_err(|e| anyhow::anyhow!("cannot load the Vulkan loader ({e}); {INSTALL_HINT}"))?;
        let log = Arc::new(ValidationLog::default());

        let mut layers: Vec<*const c_char> = Vec::new();
        let mut extensions: Vec<*const c_char> = wanted.to_vec();
        if validation {
            // SAFETY: plain enumeration calls on a loaded entry.
            let available = unsafe { entry.enumerate_instance_layer_properties() }?;
            let found = available.iter().any(|l| l.layer_name_as_c_str() == Ok(VALIDATION_LAYER));
            if !found {
                bail!(
                    "validation was requested but the Khronos validation layer is not installed; \
                     install it, e.g. `sudo apt-get install vulkan-validationlayers`"
                );
            }
            layers.push(VALIDATION_LAYER.as_ptr());
            extensions.push(ash::ext::debug_utils::NAME.as_ptr());
        }

        let app = vk::ApplicationInfo::default()
            .application_name(c"sensorlight")
            .engine_name(c"sensorlight")
            .api_version(vk::API_VERSION_1_2);
        // Chained into the create info so that messages from vkCreateInstance/vkDestroyInstance are caught too.
        let mut instance_messenger = messenger_info(&log);
        let mut info = vk::InstanceCreateInfo::default()
            .application_info(&app)
            .enabled_layer_names(&layers)
            .enabled_extension_names(&extensions);
        if validation {
            info = info.push_next(&mut instance_messenger);
        }
        let _loader = loader_lock();
        // SAFETY: every pointer in `info` outlives the call.
        let raw = unsafe { entry.create_instance(&info, None) }.map_err(|e| match e {
            vk::Result::ERROR_INCOMPATIBLE_DRIVER => anyhow::anyhow!("no Vulkan driver found; {INSTALL_HINT}"),
            other => anyhow::anyhow!("vkCreateInstance failed: {other}"),
        })?;

        let debug = if validation {
            let loader = ash::ext::debug_utils::Instance::new(&entry, &raw);
            // SAFETY: valid instance; the messenger's user data (the log) is kept alive by `self.log`.
            match unsafe { loader.create_debug_utils_messenger(&messenger_info(&log), None) } {
                Ok(messenger) => Some((loader, messenger)),
                Err(e) => {
                    // SAFETY: nothing else was created from this instance.
                    unsafe { raw.destroy_instance(None) };
                    return Err(e).context("vkCreateDebugUtilsMessengerEXT");
                }
            }
        } else {
            None
        };
        Ok(Self { entry, raw, debug, log })
    }

    /// Messages the validation layer reported so far (always empty without validation).
    pub fn log(&self) -> &Arc<ValidationLog> {
        &self.log
    }
}

impl Drop for Instance {
    fn drop(&mut self) {
        let _loader = loader_lock();
        // SAFETY: the owner (`Device`) has destroyed the logical device before dropping its instance.
        unsafe {
            if let Some((loader, messenger)) = self.debug.take() {
                loader.destroy_debug_utils_messenger(messenger, None);
            }
            self.raw.destroy_instance(None);
        }
    }
}
