//! The importer's logger, for FMI 2.0 and FMI 3.0 alike: the callback it gave
//! at instantiation and what to pass back with each message.

use crate::fmi2::{fmi2CallbackFunctions, fmi2CallbackLogger, fmi2ComponentEnvironment};
use crate::fmi3::{fmi3InstanceEnvironment, fmi3LogMessageCallback};
use crate::handle::c_text;
use fmi_core::logging::Log;
use fmi_core::Status;
use std::ffi::{c_int, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};

pub enum Logger {
    /// FMI 2.0's logger is variadic, a printf format: this FMU formats its messages itself
    /// and passes none of the variadic arguments.
    Fmi2 { callback: Option<fmi2CallbackLogger>, environment: fmi2ComponentEnvironment, instance_name: CString },
    /// FMI 3.0's is not: the message goes as it is.
    Fmi3 { callback: Option<fmi3LogMessageCallback>, environment: fmi3InstanceEnvironment },
}

impl Logger {
    /// The logger of `fmi2CallbackFunctions`, copied out.
    pub fn fmi2(functions: &fmi2CallbackFunctions, instance_name: &str) -> Logger {
        Logger::Fmi2 { callback: functions.logger, environment: functions.componentEnvironment, instance_name: c_text(instance_name) }
    }

    pub fn fmi3(callback: Option<fmi3LogMessageCallback>, environment: fmi3InstanceEnvironment) -> Logger {
        Logger::Fmi3 { callback, environment }
    }

    /// One error line where no instance exists to report it (instantiation refused); no panic
    /// of the importer's logger crosses back.
    pub fn refuse(&self, message: &str) {
        let _ = catch_unwind(AssertUnwindSafe(|| self.log(Status::Error, "logStatusError", message)));
    }
}

impl Log for Logger {
    fn log(&self, status: Status, category: &str, message: &str) {
        // SAFETY: the importer handed us these callbacks for the instance's lifetime.
        unsafe {
            match self {
                Logger::Fmi2 { callback: Some(callback), environment, instance_name } => {
                    // Loggers treat the message as a printf format: escape '%'.
                    let (category, message) = (c_text(category), c_text(&message.replace('%', "%%")));
                    callback(*environment, instance_name.as_ptr(), status as c_int, category.as_ptr(), message.as_ptr())
                }
                Logger::Fmi3 { callback: Some(callback), environment } => {
                    let (category, message) = (c_text(category), c_text(message));
                    callback(*environment, status as c_int, category.as_ptr(), message.as_ptr())
                }
                Logger::Fmi2 { callback: None, .. } | Logger::Fmi3 { callback: None, .. } => {}
            }
        }
    }
}
