//! The FMU-state functions of FMI 2.0 and FMI 3.0 alike (`fmi2GetFMUstate`,
//! `fmi3GetFMUState`, ...): the instance's snapshots, handed out through the
//! state store and serialized by `fmi_core`. Each takes its standard's `call`
//! (for the state mask and the messages) and `slot`, the standard's name of
//! the state argument ("FMUstate", "FMUState").

use crate::handle::{enter, out_ref, slice, slice_mut};
use fmi_core::instance::Instance;
use fmi_core::snapshot::Snapshot;
use fmi_core::standard::Call;
use fmi_core::{FmiError, Model};
use std::ffi::{c_int, c_void};

pub unsafe fn get<M: Model, C: Call>(c: *mut c_void, call: C, state: *mut *mut c_void, slot: &str) -> c_int {
    enter::<M, C>(c, call, |h| {
        let snapshot = h.instance.snapshot();
        h.keep_state(call, state, slot, snapshot)
    })
}

pub unsafe fn set<M: Model, C: Call>(c: *mut c_void, call: C, state: *mut c_void) -> c_int {
    enter::<M, C>(c, call, |h| {
        let snapshot = h.own_state(call, state)?.clone();
        h.instance.restore(call.name(), &snapshot)
    })
}

pub unsafe fn free<M: Model, C: Call>(c: *mut c_void, call: C, state: *mut *mut c_void, slot: &str) -> c_int {
    enter::<M, C>(c, call, |h| h.free_state(call, state, slot))
}

pub unsafe fn serialized_size<M: Model, C: Call>(c: *mut c_void, call: C, state: *mut c_void, size: *mut usize) -> c_int {
    enter::<M, C>(c, call, |h| {
        let n = h.own_state(call, state)?.to_bytes().len();
        *out_ref(call, size, "size")? = n;
        Ok(())
    })
}

/// `size_call`: the standard's function that tells the size, named where the buffer is short.
pub unsafe fn serialize<M: Model, C: Call>(c: *mut c_void, call: C, size_call: C, state: *mut c_void, serialized: *mut u8, size: usize) -> c_int {
    enter::<M, C>(c, call, |h| {
        let bytes = h.own_state(call, state)?.to_bytes();
        if size < bytes.len() {
            return Err(FmiError::error(format!(
                "{}: the buffer holds {size} bytes, the state needs {} (ask {})",
                call.name(),
                bytes.len(),
                size_call.name()
            )));
        }
        slice_mut(call, serialized, bytes.len(), "serializedState")?.copy_from_slice(&bytes);
        Ok(())
    })
}

pub unsafe fn deserialize<M: Model, C: Call>(c: *mut c_void, call: C, serialized: *const u8, size: usize, state: *mut *mut c_void, slot: &str) -> c_int {
    enter::<M, C>(c, call, |h| {
        let bytes = slice(call, serialized, size, "serializedState")?;
        let snapshot = Snapshot::<M>::from_bytes(bytes, h.instance.start_model())
            .and_then(|s| Instance::<M>::check_snapshot(&s).map(|()| s))
            .map_err(|why| FmiError::error(format!("{}: rejected: {}", call.name(), why.message)))?;
        h.keep_state(call, state, slot, snapshot)
    })
}
