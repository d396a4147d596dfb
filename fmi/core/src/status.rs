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
/// importer to retry) with the one-line message that explains it. Boxed, so
/// that a result is one word and the calls that succeed pay nothing for it.
#[derive(Clone, Debug, PartialEq)]
pub struct FmiError(Box<Failure>);

/// What a failed call reports.
#[derive(Clone, Debug, PartialEq)]
pub struct Failure {
    pub status: Status,
    pub message: String,
}

impl std::ops::Deref for FmiError {
    type Target = Failure;
    fn deref(&self) -> &Failure {
        &self.0
    }
}

impl std::ops::DerefMut for FmiError {
    fn deref_mut(&mut self) -> &mut Failure {
        &mut self.0
    }
}

impl FmiError {
    #[cold]
    pub fn error(message: impl Into<String>) -> Self {
        FmiError(Box::new(Failure { status: Status::Error, message: message.into() }))
    }

    #[cold]
    pub fn discard(message: impl Into<String>) -> Self {
        FmiError(Box::new(Failure { status: Status::Discard, message: message.into() }))
    }

    /// The same error, its message prefixed with where it happened.
    #[cold]
    pub fn prefixed(mut self, what: &str) -> Self {
        self.0.message = format!("{what}: {}", self.0.message);
        self
    }

    /// The message, for callers that keep only the text.
    pub fn into_message(self) -> String {
        self.0.message
    }
}

pub type FmiResult<T = ()> = Result<T, FmiError>;
