//! Outcomes of FMI calls inside the crate: errors are values here; only the
//! FFI module turns them into an `fmi2Status` and a log message.

/// `fmi2Status`, with the numbering of the FMI 2.0 headers.
#[repr(i32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Status {
    Ok = 0,
    Warning = 1,
    Discard = 2,
    Error = 3,
    Fatal = 4,
    Pending = 5,
}

impl Status {
    /// The log category FMI 2.0 suggests for messages of this status.
    pub fn log_category(self) -> &'static str {
        match self {
            Status::Ok => "logEvents",
            Status::Warning => "logStatusWarning",
            Status::Discard => "logStatusDiscard",
            Status::Error => "logStatusError",
            Status::Fatal => "logStatusFatal",
            Status::Pending => "logStatusPending",
        }
    }
}

/// A failed call: `Error` (or `Discard` where the standard allows the
/// importer to retry) with the one-line message that explains it.
#[derive(Clone, Debug, PartialEq)]
pub struct FmiError {
    pub status: Status,
    pub message: String,
}

impl FmiError {
    pub fn error(message: impl Into<String>) -> Self {
        FmiError { status: Status::Error, message: message.into() }
    }

    pub fn discard(message: impl Into<String>) -> Self {
        FmiError { status: Status::Discard, message: message.into() }
    }

    /// The same error, its message prefixed with where it happened.
    #[cold]
    pub fn prefixed(self, what: &str) -> Self {
        FmiError { status: self.status, message: format!("{what}: {}", self.message) }
    }
}

pub type FmiResult<T = ()> = Result<T, FmiError>;
