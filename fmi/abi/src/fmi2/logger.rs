//! FMI 2.0's logger: the callback the importer gave at instantiation and what
//! to pass back with each message.

use super::{fmi2CallbackFunctions, fmi2CallbackLogger, fmi2ComponentEnvironment};
use crate::handle::c_text;
use fmi_core::logging::Log;
use fmi_core::Status;
use std::ffi::{c_int, CString};

/// The logger is variadic, a printf format: this FMU formats its messages itself
/// and passes none of the variadic arguments.
pub struct Logger {
    callback: Option<fmi2CallbackLogger>,
    environment: fmi2ComponentEnvironment,
    instance_name: CString,
}

impl Logger {
    /// The logger of `fmi2CallbackFunctions`, copied out.
    pub fn new(functions: &fmi2CallbackFunctions, instance_name: &str) -> Logger {
        Logger { callback: functions.logger, environment: functions.componentEnvironment, instance_name: c_text(instance_name) }
    }
}

impl Log for Logger {
    fn log(&self, status: Status, category: &str, message: &str) {
        let Some(callback) = self.callback else { return };
        // Loggers treat the message as a printf format: escape '%'.
        let (category, message) = (c_text(category), c_text(&message.replace('%', "%%")));
        // SAFETY: the importer handed us this callback for the instance's lifetime.
        unsafe { callback(self.environment, self.instance_name.as_ptr(), status as c_int, category.as_ptr(), message.as_ptr()) }
    }
}
