//! The library's own reference to itself, held by every live instance: an
//! importer that unloads the library and loads it again while an instance
//! lives (one engine does so when it instantiates the same FMU twice) must
//! not pull the code and static data (a logger's vtable) from under it.
//! Taken at instantiation, given back when the instance is freed, so the
//! library unloads as usual after the last free.

use std::ffi::c_void;

/// An address inside this library: the function that asks for it.
fn own_address() -> *const c_void {
    own_address as *const c_void
}

#[cfg(unix)]
mod os {
    use std::ffi::{c_char, c_int, c_void};

    #[repr(C)]
    struct DlInfo {
        dli_fname: *const c_char,
        dli_fbase: *mut c_void,
        dli_sname: *const c_char,
        dli_saddr: *mut c_void,
    }

    const RTLD_NOW: c_int = 2;
    #[cfg(target_os = "macos")]
    const RTLD_NOLOAD: c_int = 0x10;
    #[cfg(not(target_os = "macos"))]
    const RTLD_NOLOAD: c_int = 4;

    extern "C" {
        fn dladdr(address: *const c_void, info: *mut DlInfo) -> c_int;
        fn dlopen(filename: *const c_char, flags: c_int) -> *mut c_void;
        fn dlclose(handle: *mut c_void) -> c_int;
    }

    pub type Module = *mut c_void;

    /// dlopen of the file the address lies in, without loading anything:
    /// it is loaded, so this only counts one more reference. NULL if that fails.
    pub fn acquire(address: *const c_void) -> Module {
        let mut info = DlInfo {
            dli_fname: std::ptr::null(),
            dli_fbase: std::ptr::null_mut(),
            dli_sname: std::ptr::null(),
            dli_saddr: std::ptr::null_mut(),
        };
        // SAFETY: dladdr writes `info` and reads nothing else; the file name it
        // gives stays valid while the library is loaded, which it is here.
        unsafe {
            if dladdr(address, &mut info) == 0 || info.dli_fname.is_null() {
                return std::ptr::null_mut();
            }
            dlopen(info.dli_fname, RTLD_NOW | RTLD_NOLOAD)
        }
    }

    pub fn release(module: Module) {
        if !module.is_null() {
            // SAFETY: a handle of `acquire`'s dlopen, closed once.
            unsafe { dlclose(module) };
        }
    }
}

#[cfg(windows)]
mod os {
    use std::ffi::c_void;

    const GET_MODULE_HANDLE_EX_FLAG_FROM_ADDRESS: u32 = 0x4;

    #[link(name = "kernel32")]
    extern "system" {
        fn GetModuleHandleExW(flags: u32, module_name: *const c_void, module: *mut *mut c_void) -> i32;
        fn FreeLibrary(module: *mut c_void) -> i32;
    }

    pub type Module = *mut c_void;

    /// The module the address lies in, its reference count raised by one; NULL if that fails.
    pub fn acquire(address: *const c_void) -> Module {
        let mut module = std::ptr::null_mut();
        // SAFETY: with FROM_ADDRESS the name argument is an address inside the module.
        let ok = unsafe { GetModuleHandleExW(GET_MODULE_HANDLE_EX_FLAG_FROM_ADDRESS, address, &mut module) };
        if ok == 0 { std::ptr::null_mut() } else { module }
    }

    pub fn release(module: Module) {
        if !module.is_null() {
            // SAFETY: a reference `acquire` took, given back once.
            unsafe { FreeLibrary(module) };
        }
    }
}

/// One reference to this library, given back on drop.
pub struct LibraryRef(os::Module);

impl LibraryRef {
    pub fn acquire() -> Self {
        LibraryRef(os::acquire(own_address()))
    }
}

impl Drop for LibraryRef {
    fn drop(&mut self) {
        os::release(self.0);
    }
}
