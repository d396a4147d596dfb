//! FMI 3.0's logger: the callback the importer gave at instantiation and what
//! to pass back with each message.

use super::{fmi3InstanceEnvironment, fmi3LogMessageCallback};
use crate::handle::c_text;
use fmi_core::logging::Log;
use fmi_core::Status;
use std::ffi::c_int;

/// Unlike FMI 2.0's, the callback is no printf format: the message goes as it is.
pub struct Logger {
    callback: Option<fmi3LogMessageCallback>,
    environment: fmi3InstanceEnvironment,
}

impl Logger {
    pub fn new(callback: Option<fmi3LogMessageCallback>, environment: fmi3InstanceEnvironment) -> Logger {
        Logger { callback, environment }
    }
}

impl Log for Logger {
    fn log(&self, status: Status, category: &str, message: &str) {
        let Some(callback) = self.callback else { return };
        let (category, message) = (c_text(category), c_text(message));
        // SAFETY: the importer handed us this callback for the instance's lifetime.
        unsafe { callback(self.environment, status as c_int, category.as_ptr(), message.as_ptr()) }
    }
}
