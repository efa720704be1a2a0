//! The Vulkan instance: loader entry, optional Khronos validation (synchronization validation and best practices
//! through `VkValidationFeaturesEXT`), and the debug-utils messenger that feeds a [`ValidationLog`].
use super::validation::{messenger_callback, ValidationLog};
use anyhow::{bail, Context as _, Result};
use ash::vk;
use std::ffi::{c_void, CStr};
use std::sync::Arc;

pub const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";
/// The API version strata asks for: the loader on Debian 12 is 1.3.239, and 1.3 brings dynamic rendering
/// and synchronization2 into core.
pub const API_VERSION: u32 = vk::API_VERSION_1_3;

/// How to create the instance.
#[derive(Debug, Clone, Default)]
pub struct InstanceOptions {
    /// Enable the Khronos validation layer with synchronization validation and best practices.
    pub validation: bool,
    /// Print validation warnings and errors to stderr as they arrive.
    pub echo_messages: bool,
}

/// Owns the loader, the instance and the messenger; shared by everything created from it.
pub struct Instance {
    pub entry: ash::Entry,
    pub raw: ash::Instance,
    /// Present when `VK_EXT_debug_utils` is available (always with validation).
    pub debug_utils: Option<ash::ext::debug_utils::Instance>,
    messenger: vk::DebugUtilsMessengerEXT,
    /// Boxed so its address stays fixed: the messenger callback holds a raw pointer to it.
    log: Arc<ValidationLog>,
    pub validation: bool,
}

/// Facts about the loader and layers, for `strata info` and for clear errors.
#[derive(Debug, Clone)]
pub struct LoaderInfo {
    pub loader_version: u32,
    pub validation_layer: Option<String>,
}

/// What the loader offers, without creating an instance.
pub fn loader_info() -> Result<LoaderInfo> {
    let entry = load_entry()?;
    let loader_version = unsafe { entry.try_enumerate_instance_version() }
        .context("vkEnumerateInstanceVersion")?
        .unwrap_or(vk::API_VERSION_1_0);
    let validation_layer = find_layer(&entry, VALIDATION_LAYER)?.map(|l| {
        // implementationVersion is a plain counter; the spec version says which Vulkan headers it follows.
        format!("{} (Vulkan {})", VALIDATION_LAYER.to_string_lossy(), version_string(l.spec_version))
    });
    Ok(LoaderInfo { loader_version, validation_layer })
}

fn load_entry() -> Result<ash::Entry> {
    unsafe { ash::Entry::load() }
        .context("cannot load the Vulkan loader (libvulkan.so.1); install it with scripts/setup.sh")
}

fn find_layer(entry: &ash::Entry, name: &CStr) -> Result<Option<vk::LayerProperties>> {
    let layers =
        unsafe { entry.enumerate_instance_layer_properties() }.context("vkEnumerateInstanceLayerProperties")?;
    Ok(layers.into_iter().find(|l| l.layer_name_as_c_str().ok() == Some(name)))
}

/// `1.3.239` from a packed Vulkan version.
pub fn version_string(v: u32) -> String {
    format!("{}.{}.{}", vk::api_version_major(v), vk::api_version_minor(v), vk::api_version_patch(v))
}

impl Instance {
    pub fn new(options: &InstanceOptions) -> Result<Arc<Self>> {
        let entry = load_entry()?;
        let loader_version = unsafe { entry.try_enumerate_instance_version() }
            .context("vkEnumerateInstanceVersion")?
            .unwrap_or(vk::API_VERSION_1_0);
        if loader_version < API_VERSION {
            bail!(
                "the Vulkan loader is version {}, strata needs 1.3 or newer; run scripts/setup.sh",
                version_string(loader_version)
            );
        }
        if options.validation && find_layer(&entry, VALIDATION_LAYER)?.is_none() {
            bail!(
                "validation was requested but the layer {} is not installed; run scripts/setup.sh \
                 (it installs vulkan-validationlayers)",
                VALIDATION_LAYER.to_string_lossy()
            );
        }
        let available: Vec<vk::ExtensionProperties> = unsafe {
            entry.enumerate_instance_extension_properties(if options.validation {
                Some(VALIDATION_LAYER)
            } else {
                None
            })
        }
        .context("vkEnumerateInstanceExtensionProperties")?;
        let has_ext = |name: &CStr| available.iter().any(|e| e.extension_name_as_c_str().ok() == Some(name));
        let has_debug_utils = has_ext(ash::ext::debug_utils::NAME);
        if options.validation && !has_debug_utils {
            bail!("the validation layer is present but VK_EXT_debug_utils is not; run scripts/setup.sh");
        }

        let mut extensions = Vec::new();
        if has_debug_utils {
            extensions.push(ash::ext::debug_utils::NAME.as_ptr());
        }
        let mut layers = Vec::new();
        if options.validation {
            layers.push(VALIDATION_LAYER.as_ptr());
            extensions.push(ash::ext::validation_features::NAME.as_ptr());
        }

        let log = Arc::new(ValidationLog::new(options.echo_messages));
        let app_info = vk::ApplicationInfo::default()
            .application_name(c"strata")
            .application_version(vk::make_api_version(0, 0, 1, 0))
            .engine_name(c"strata")
            .api_version(API_VERSION);
        let enabled_features = [
            vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION,
            vk::ValidationFeatureEnableEXT::BEST_PRACTICES,
        ];
        let mut validation_features =
            vk::ValidationFeaturesEXT::default().enabled_validation_features(&enabled_features);
        // Chained into the instance create-info too, so messages from vkCreateInstance itself are caught.
        let mut messenger_info = messenger_create_info(&log);
        let mut create_info = vk::InstanceCreateInfo::default()
            .application_info(&app_info)
            .enabled_layer_names(&layers)
            .enabled_extension_names(&extensions);
        if has_debug_utils {
            create_info = create_info.push_next(&mut messenger_info);
        }
        if options.validation {
            create_info = create_info.push_next(&mut validation_features);
        }
        let raw = match unsafe { entry.create_instance(&create_info, None) } {
            Ok(raw) => raw,
            Err(vk::Result::ERROR_INCOMPATIBLE_DRIVER) => bail!(
                "vkCreateInstance: no Vulkan driver found (ERROR_INCOMPATIBLE_DRIVER); run scripts/setup.sh to \
                 install Mesa's lavapipe, or check VK_DRIVER_FILES / VK_ICD_FILENAMES"
            ),
            Err(e) => return Err(e).context("vkCreateInstance"),
        };

        let (debug_utils, messenger) = if has_debug_utils {
            let loader = ash::ext::debug_utils::Instance::new(&entry, &raw);
            let info = messenger_create_info(&log);
            match unsafe { loader.create_debug_utils_messenger(&info, None) } {
                Ok(m) => (Some(loader), m),
                Err(e) => {
                    unsafe { raw.destroy_instance(None) };
                    return Err(e).context("vkCreateDebugUtilsMessengerEXT");
                }
            }
        } else {
            (None, vk::DebugUtilsMessengerEXT::null())
        };
        Ok(Arc::new(Self { entry, raw, debug_utils, messenger, log, validation: options.validation }))
    }

    /// The log the messenger writes into; it outlives the instance if a caller keeps it.
    pub fn validation_log(&self) -> Arc<ValidationLog> {
        self.log.clone()
    }
}

fn messenger_create_info(log: &Arc<ValidationLog>) -> vk::DebugUtilsMessengerCreateInfoEXT<'static> {
    vk::DebugUtilsMessengerCreateInfoEXT::default()
        .message_severity(
            // INFO is left out: the loader reports every ICD it scans there.
            vk::DebugUtilsMessageSeverityFlagsEXT::ERROR | vk::DebugUtilsMessageSeverityFlagsEXT::WARNING,
        )
        .message_type(
            vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
        )
        .pfn_user_callback(Some(messenger_callback))
        .user_data(Arc::as_ptr(log) as *mut c_void)
}

impl Drop for Instance {
    fn drop(&mut self) {
        unsafe {
            if let Some(loader) = &self.debug_utils {
                loader.destroy_debug_utils_messenger(self.messenger, None);
            }
            self.raw.destroy_instance(None);
        }
    }
}
