//! FMU states (`fmi2GetFMUstate` and friends) and their serialized form.
//!
//! Serialized layout, all integers little-endian:
//!
//! | bytes        | content                                              |
//! |--------------|------------------------------------------------------|
//! | 0..8         | magic `FMI2SNAP`                                     |
//! | 8..12        | format version (u32)                                 |
//! | 12..20       | FNV-1a hash of the model's GUID (u64): foreign states|
//! | 20..24       | payload length n (u32)                               |
//! | 24..24+n     | payload: phase (u8), time (f64), experiment, model   |
//! | 24+n..32+n   | FNV-1a checksum of bytes 0..24+n (u64)               |
//!
//! Reals are stored as their bit patterns, so a restored state continues
//! bit-identically.

use super::model::{Experiment, Model};
use super::persist::{StateReader, StateWriter};
use super::phase::Phase;
use super::status::{FmiError, FmiResult};

const MAGIC: &[u8; 8] = b"FMI2SNAP";
/// 2: the experiment (interface, tolerance, start and stop time) is saved too;
/// 3: the model's variables in the order of its binding table, then its own state;
/// 4: String variables too (length-prefixed UTF-8), and the model's own data may vary in length.
const FORMAT_VERSION: u32 = 4;
const HEADER: usize = 24;
const TRAILER: usize = 8;

/// Everything an instance needs to continue from a saved point.
#[derive(Clone, Debug, PartialEq)]
pub struct Snapshot<M> {
    pub phase: Phase,
    pub time: f64,
    pub experiment: Experiment,
    pub model: M,
}

/// FNV-1a, 64 bit: cheap, and any change of a byte changes it.
pub fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3))
}

impl<M: Model> Snapshot<M> {
    pub fn to_bytes(&self) -> Vec<u8> {
        let description = self.model.description();
        let mut payload = StateWriter::default();
        payload.bytes.push(self.phase as u8);
        payload.f64(self.time);
        let e = &self.experiment;
        payload.bool(e.model_exchange);
        payload.bool(e.tolerance.is_some());
        payload.f64(e.tolerance.unwrap_or(0.0));
        payload.f64(e.start_time);
        payload.bool(e.stop_time.is_some());
        payload.f64(e.stop_time.unwrap_or(0.0));
        self.model.save_variables(&mut payload);
        self.model.save_state(&mut payload);
        let n = payload.bytes.len();
        let mut out = Vec::with_capacity(HEADER + n + TRAILER);
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
        out.extend_from_slice(&fnv1a(description.guid.as_bytes()).to_le_bytes());
        out.extend_from_slice(&(n as u32).to_le_bytes());
        out.extend_from_slice(&payload.bytes);
        out.extend_from_slice(&fnv1a(&out).to_le_bytes());
        out
    }

    /// Rejects bytes that are short, corrupted, of another format version or
    /// of another model, with the reason.
    /// The state in `bytes`, read into a copy of `template` (a model of this FMU at its start values).
    pub fn from_bytes(bytes: &[u8], template: &M) -> FmiResult<Self> {
        let description = template.description();
        let fail = |message: String| Err(FmiError::error(message));
        if bytes.len() < HEADER + TRAILER {
            return fail(format!("{} bytes is too short for an FMU state (at least {})", bytes.len(), HEADER + TRAILER));
        }
        if &bytes[0..8] != MAGIC {
            return fail("the bytes are not an FMU state of this FMU (wrong magic number)".into());
        }
        let u32_at = |i: usize| u32::from_le_bytes(bytes[i..i + 4].try_into().expect("4 bytes"));
        let u64_at = |i: usize| u64::from_le_bytes(bytes[i..i + 8].try_into().expect("8 bytes"));
        let version = u32_at(8);
        if version != FORMAT_VERSION {
            return fail(format!("format version {version} is not supported (this FMU writes version {FORMAT_VERSION})"));
        }
        if u64_at(12) != fnv1a(description.guid.as_bytes()) {
            return fail(format!("the state belongs to another model (GUID differs from {})", description.guid));
        }
        let n = u32_at(20) as usize;
        if bytes.len() != HEADER + n + TRAILER {
            return fail(format!("the state is truncated or padded ({} bytes, its header says {})", bytes.len(), HEADER + n + TRAILER));
        }
        if u64_at(HEADER + n) != fnv1a(&bytes[..HEADER + n]) {
            return fail("checksum mismatch: the state is corrupted".into());
        }
        let mut reader = StateReader { bytes: &bytes[HEADER..HEADER + n] };
        let phase_byte = reader.take::<1>("phase")?[0];
        let Some(phase) = Phase::from_u8(phase_byte) else { return fail(format!("phase {phase_byte} is unknown")) };
        let time = reader.finite("time")?;
        let model_exchange = reader.bool("interface")?;
        let tolerance_given = reader.bool("tolerance given")?;
        let tolerance = Some(reader.finite("tolerance")?).filter(|_| tolerance_given);
        let start_time = reader.finite("start time")?;
        let stop_given = reader.bool("stop time given")?;
        let stop_time = Some(reader.finite("stop time")?).filter(|_| stop_given);
        let experiment = Experiment { model_exchange, tolerance, start_time, stop_time };
        let mut model = template.clone();
        model.load_variables(&mut reader)?;
        model.load_state(&mut reader)?;
        if !reader.bytes.is_empty() {
            return fail(format!("{} bytes left over after the model's fields", reader.bytes.len()));
        }
        Ok(Snapshot { phase, time, experiment, model })
    }
}
