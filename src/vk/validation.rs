//! The validation layer as a test oracle: a debug-utils messenger records every warning and error into a
//! [`ValidationLog`], and [`ValidationLog::check`] fails on anything not on the [`ALLOWED`] list.
use ash::vk;
use std::ffi::{c_void, CStr};
use std::fmt;
use std::sync::Mutex;

/// A message the validation layer may report without failing a run, with why and for which layer version.
#[derive(Debug, Clone, Copy)]
pub struct AllowedMessage {
    /// The message id name (`VUID-...` or a best-practices id).
    pub id: &'static str,
    /// Why it is allowed.
    pub reason: &'static str,
    /// The layer version it was seen with.
    pub layer_version: &'static str,
}

/// Messages the layer reports that are not bugs in strata. Each names its reason.
pub const ALLOWED: &[AllowedMessage] = &[AllowedMessage {
    id: "UNASSIGNED-BestPractices-vkCreateInstance-specialuse-extension-debugging",
    reason: "VK_EXT_debug_utils and VK_EXT_validation_features are enabled on purpose: they carry object names, \
                 the messenger and the validation settings themselves",
    layer_version: "1.3.239",
}];

/// One message as the layer reported it.
#[derive(Debug, Clone)]
pub struct ValidationMessage {
    pub severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    pub kind: vk::DebugUtilsMessageTypeFlagsEXT,
    pub id_name: String,
    pub id_number: i32,
    pub text: String,
    /// Debug names (or handles) of the objects the message is about.
    pub objects: Vec<String>,
}

impl ValidationMessage {
    pub fn is_error_or_warning(&self) -> bool {
        self.severity
            .intersects(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR | vk::DebugUtilsMessageSeverityFlagsEXT::WARNING)
    }

    pub fn allowed_by(&self) -> Option<&'static AllowedMessage> {
        ALLOWED.iter().find(|a| a.id == self.id_name)
    }
}

impl fmt::Display for ValidationMessage {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let severity = if self.severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR) {
            "ERROR"
        } else if self.severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::WARNING) {
            "WARNING"
        } else if self.severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::INFO) {
            "INFO"
        } else {
            "VERBOSE"
        };
        write!(f, "[{severity}] {} ({:#x})", self.id_name, self.id_number)?;
        if !self.objects.is_empty() {
            write!(f, " objects: {}", self.objects.join(", "))?;
        }
        write!(f, "\n    {}", self.text)
    }
}

/// Everything the messenger has seen; shared between the messenger callback and whoever checks it.
#[derive(Debug, Default)]
pub struct ValidationLog {
    messages: Mutex<Vec<ValidationMessage>>,
    /// Echo warnings and errors to stderr as they arrive (the command line's `--validate`).
    pub echo: bool,
}

impl ValidationLog {
    pub fn new(echo: bool) -> Self {
        Self { messages: Mutex::default(), echo }
    }

    pub fn push(&self, message: ValidationMessage) {
        if self.echo && message.is_error_or_warning() && message.allowed_by().is_none() {
            eprintln!("validation: {message}");
        }
        self.lock().push(message);
    }

    /// Every message recorded so far, in order.
    pub fn messages(&self) -> Vec<ValidationMessage> {
        self.lock().clone()
    }

    /// Warnings and errors that are not on the allow-list.
    pub fn failures(&self) -> Vec<ValidationMessage> {
        self.lock().iter().filter(|m| m.is_error_or_warning() && m.allowed_by().is_none()).cloned().collect()
    }

    /// Ok when no warning or error outside the allow-list was reported; otherwise every such message, printed.
    pub fn check(&self) -> Result<(), String> {
        let failures = self.failures();
        if failures.is_empty() {
            return Ok(());
        }
        let mut report = format!("the validation layer reported {} message(s):\n", failures.len());
        for m in &failures {
            report.push_str(&format!("  {m}\n"));
        }
        Err(report)
    }

    /// Forget what was recorded (a test that provokes messages on purpose starts clean afterwards).
    pub fn clear(&self) {
        self.lock().clear();
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Vec<ValidationMessage>> {
        // A panic while holding the lock leaves plain data; keep going.
        self.messages.lock().unwrap_or_else(|p| p.into_inner())
    }
}

/// The messenger callback. `user_data` is a `*const ValidationLog` kept alive by the instance.
pub(crate) unsafe extern "system" fn messenger_callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    kind: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user_data: *mut c_void,
) -> vk::Bool32 {
    if data.is_null() || user_data.is_null() {
        return vk::FALSE;
    }
    let data = &*data;
    let text_of = |p: *const std::ffi::c_char| {
        if p.is_null() {
            String::new()
        } else {
            CStr::from_ptr(p).to_string_lossy().into_owned()
        }
    };
    let objects = if data.object_count == 0 || data.p_objects.is_null() {
        Vec::new()
    } else {
        std::slice::from_raw_parts(data.p_objects, data.object_count as usize)
            .iter()
            .map(|o| {
                let name = text_of(o.p_object_name);
                if name.is_empty() {
                    format!("{:?} {:#x}", o.object_type, o.object_handle)
                } else {
                    format!("{:?} \"{name}\"", o.object_type)
                }
            })
            .collect()
    };
    let log = &*(user_data as *const ValidationLog);
    log.push(ValidationMessage {
        severity,
        kind,
        id_name: text_of(data.p_message_id_name),
        id_number: data.message_id_number,
        text: text_of(data.p_message),
        objects,
    });
    vk::FALSE
}
