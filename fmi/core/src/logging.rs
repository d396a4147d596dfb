//! Which log categories reach the importer's logger.
//!
//! Messages that report a status (warning, discard, error, fatal) are on
//! from the start so that an importer learns why a call failed even with
//! debug logging off; the other categories follow `loggingOn`.
//! `fmi2SetDebugLogging` switches any of them, and `logAll` lets everything through.

use super::status::{FmiError, FmiResult, Status};

const LOG_ALL: &str = "logAll";

/// Where an instance's messages go (the FFI module passes the importer's
/// logger callback; tests may pass anything else).
pub trait Log {
    fn log(&self, status: Status, category: &str, message: &str);
}

#[derive(Clone, Debug)]
pub struct LogFilter {
    categories: &'static [&'static str],
    enabled: Vec<bool>,
    all: bool,
}

impl LogFilter {
    pub fn new(categories: &'static [&'static str], logging_on: bool) -> Self {
        let enabled = categories
            .iter()
            .map(|c| if c.starts_with("logStatus") { true } else { logging_on && *c != LOG_ALL })
            .collect();
        LogFilter { categories, enabled, all: false }
    }

    /// `fmi2SetDebugLogging`: no names switches every category.
    pub fn set(&mut self, on: bool, names: &[String]) -> FmiResult {
        if names.is_empty() {
            self.enabled.iter_mut().for_each(|e| *e = on);
        } else {
            let unknown: Vec<&str> = names
                .iter()
                .filter(|n| !self.categories.contains(&n.as_str()))
                .map(String::as_str)
                .collect();
            if !unknown.is_empty() {
                return Err(FmiError::error(format!(
                    "unknown log categories {unknown:?}; this FMU has {:?}",
                    self.categories
                )));
            }
            for (c, e) in self.categories.iter().zip(self.enabled.iter_mut()) {
                if names.iter().any(|n| n == c) {
                    *e = on;
                }
            }
        }
        self.all = self.categories.iter().zip(&self.enabled).any(|(c, &e)| *c == LOG_ALL && e);
        Ok(())
    }

    pub fn allows(&self, category: &str) -> bool {
        self.all || self.categories.iter().zip(&self.enabled).any(|(c, &e)| e && *c == category)
    }

    /// `logAll` is on: trace every call.
    pub fn traces_calls(&self) -> bool {
        self.all
    }
}
