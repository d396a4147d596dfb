//! The importer's raw pointers made into slices, references and texts, for
//! FMI 2.0 and FMI 3.0 alike: errors name the call and the argument.

use fmi_core::standard::Call as CallName;
use fmi_core::{FmiError, FmiResult};
use std::ffi::{c_char, CStr, CString};

/// `n` elements from the importer; NULL is fine only for `n == 0`.
#[inline]
pub unsafe fn slice<'a, T>(call: impl CallName, ptr: *const T, n: usize, what: &str) -> FmiResult<&'a [T]> {
    if n == 0 {
        Ok(&[])
    } else if ptr.is_null() {
        Err(null_argument(call, what))
    } else {
        Ok(std::slice::from_raw_parts(ptr, n))
    }
}

#[inline]
pub unsafe fn slice_mut<'a, T>(call: impl CallName, ptr: *mut T, n: usize, what: &str) -> FmiResult<&'a mut [T]> {
    if n == 0 {
        Ok(&mut [])
    } else if ptr.is_null() {
        Err(null_argument(call, what))
    } else {
        Ok(std::slice::from_raw_parts_mut(ptr, n))
    }
}

#[inline]
pub fn out_ref<'a, T>(call: impl CallName, ptr: *mut T, what: &str) -> FmiResult<&'a mut T> {
    // SAFETY: the importer passes a valid pointer or NULL, as the standard requires.
    unsafe { ptr.as_mut() }.ok_or_else(|| null_argument(call, what))
}

#[cold]
pub fn null_argument(call: impl CallName, what: &str) -> FmiError {
    FmiError::error(format!("{}: {what} is NULL", call.name()))
}

/// Element `i` of the String array `what`: `Ok(None)` for NULL, an error for bytes that are not UTF-8.
pub unsafe fn utf8<'a>(call: impl CallName, s: *const c_char, what: &str, i: usize) -> FmiResult<Option<&'a str>> {
    if s.is_null() {
        return Ok(None);
    }
    CStr::from_ptr(s)
        .to_str()
        .map(Some)
        .map_err(|_| FmiError::error(format!("{}: {what}[{i}] is not UTF-8 text", call.name())))
}

/// A copy of a C string (lossy UTF-8); `None` for NULL.
pub unsafe fn text(s: *const c_char) -> Option<String> {
    (!s.is_null()).then(|| CStr::from_ptr(s).to_string_lossy().into_owned())
}

/// A C string with any interior NUL dropped.
pub fn c_text(s: &str) -> CString {
    CString::new(s.replace('\0', "")).expect("NULs removed")
}
