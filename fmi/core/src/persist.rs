//! The byte form of a model's fields inside an FMU state: written in a fixed
//! order, read back with a check of every value (see `snapshot` for the
//! framing, version and checksum around them).

use super::status::{FmiError, FmiResult};

/// Writes the fields of a model's state in a fixed order.
#[derive(Default)]
pub struct StateWriter {
    pub(crate) bytes: Vec<u8>,
}

impl StateWriter {
    pub fn f64(&mut self, x: f64) {
        self.bytes.extend_from_slice(&x.to_bits().to_le_bytes());
    }
    pub fn i32(&mut self, x: i32) {
        self.bytes.extend_from_slice(&x.to_le_bytes());
    }
    pub fn bool(&mut self, x: bool) {
        self.bytes.push(x as u8);
    }
    /// Length (u32) then the UTF-8 bytes.
    pub fn str(&mut self, x: &str) {
        self.bytes.extend_from_slice(&(x.len() as u32).to_le_bytes());
        self.bytes.extend_from_slice(x.as_bytes());
    }
}

/// Reads fields back in the order `StateWriter` wrote them; every read
/// checks that the bytes are there and make a legal value.
pub struct StateReader<'a> {
    pub(crate) bytes: &'a [u8],
}

fn malformed(message: String) -> FmiError {
    FmiError::error(message)
}

impl<'a> StateReader<'a> {
    pub(crate) fn take<const N: usize>(&mut self, what: &str) -> FmiResult<[u8; N]> {
        if self.bytes.len() < N {
            return Err(malformed(format!("payload ends before {what}")));
        }
        let (head, rest) = self.bytes.split_at(N);
        self.bytes = rest;
        Ok(head.try_into().expect("split_at gives N bytes"))
    }
    pub fn f64(&mut self, what: &str) -> FmiResult<f64> {
        Ok(f64::from_bits(u64::from_le_bytes(self.take(what)?)))
    }
    /// A Real that must be finite (all of a model's stored Reals are).
    pub fn finite(&mut self, what: &str) -> FmiResult<f64> {
        let x = self.f64(what)?;
        if x.is_finite() {
            Ok(x)
        } else {
            Err(malformed(format!("{what} is {x}")))
        }
    }
    pub fn i32(&mut self, what: &str) -> FmiResult<i32> {
        Ok(i32::from_le_bytes(self.take(what)?))
    }
    pub fn string(&mut self, what: &str) -> FmiResult<&'a str> {
        let n = u32::from_le_bytes(self.take(what)?) as usize;
        if self.bytes.len() < n {
            return Err(malformed(format!("payload ends inside {what}")));
        }
        let (head, rest) = self.bytes.split_at(n);
        self.bytes = rest;
        std::str::from_utf8(head).map_err(|_| malformed(format!("{what} is not UTF-8")))
    }
    pub fn bool(&mut self, what: &str) -> FmiResult<bool> {
        match self.take::<1>(what)?[0] {
            0 => Ok(false),
            1 => Ok(true),
            b => Err(malformed(format!("{what} is {b}, not a Boolean"))),
        }
    }
}
