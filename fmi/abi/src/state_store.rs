//! The FMU states an instance has handed out, held as the raw pointers the
//! importer keeps: a NULL, freed or foreign pointer is refused, never used.
//! FMI 2.0 and FMI 3.0 share it (both pass states as `void*`).

use fmi_core::snapshot::Snapshot;
use fmi_core::{FmiError, FmiResult, Model};
use std::ffi::c_void;

pub struct StateStore<M: Model> {
    states: Vec<*mut Snapshot<M>>,
}

impl<M: Model> Default for StateStore<M> {
    fn default() -> Self {
        StateStore { states: Vec::new() }
    }
}

impl<M: Model> StateStore<M> {
    fn owns(&self, state: *mut c_void) -> bool {
        !state.is_null() && self.states.contains(&(state as *mut Snapshot<M>))
    }

    /// The state `state` points to, if this store handed it out; `call` names the function.
    pub fn get(&self, call: &str, state: *mut c_void) -> FmiResult<&Snapshot<M>> {
        if self.owns(state) {
            // SAFETY: in `states`, so allocated by `keep` and not yet freed.
            Ok(unsafe { &*(state as *const Snapshot<M>) })
        } else {
            Err(FmiError::error(format!(
                "{call}: {state:?} is not an FMU state of this instance (NULL, freed, or from another instance)"
            )))
        }
    }

    /// Stores `snapshot` in `*slot` (`what` names the argument): in place when
    /// the slot already holds a state of this instance, otherwise in a new allocation.
    pub fn keep(&mut self, call: &str, what: &str, slot: &mut *mut c_void, snapshot: Snapshot<M>) -> FmiResult {
        if self.owns(*slot) {
            // SAFETY: owned, see `get`; no other reference is alive.
            unsafe { *(*slot as *mut Snapshot<M>) = snapshot };
        } else if slot.is_null() {
            let raw = Box::into_raw(Box::new(snapshot));
            self.states.push(raw);
            *slot = raw as *mut c_void;
        } else {
            return Err(FmiError::error(format!(
                "{call}: *{what} = {:?} is neither NULL nor an FMU state of this instance",
                *slot
            )));
        }
        Ok(())
    }

    /// Frees the state in `*slot` (NULL: nothing to do) and sets the slot to NULL.
    pub fn free(&mut self, call: &str, slot: &mut *mut c_void) -> FmiResult {
        if slot.is_null() {
            return Ok(());
        }
        self.get(call, *slot)?;
        self.states.retain(|&s| s as *mut c_void != *slot);
        // SAFETY: owned and now removed from `states`, so dropped exactly once.
        drop(unsafe { Box::from_raw(*slot as *mut Snapshot<M>) });
        *slot = std::ptr::null_mut();
        Ok(())
    }
}

impl<M: Model> Drop for StateStore<M> {
    fn drop(&mut self) {
        for state in self.states.drain(..) {
            // SAFETY: every entry came from `Box::into_raw` and is dropped once.
            drop(unsafe { Box::from_raw(state) });
        }
    }
}
