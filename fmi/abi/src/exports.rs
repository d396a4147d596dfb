//! The exports of one standard's list of C signatures (`fmi2_functions!`,
//! `fmi3_functions!`): `#[no_mangle] extern "C"` functions running their
//! bodies, in a module of the model's crate.

/// `export_fmi2!` and `export_fmi3!`: the exports of `$standard`'s list, in the module `$module`.
#[doc(hidden)]
#[macro_export]
macro_rules! __export {
    ($model:ty; $standard:ident in $module:ident; $($name:ident($($arg:ident: $ty:ty),*) $(-> $ret:ty)? => $body:expr;)*) => {
        /// The C API of this library's model for one standard, written by `fmi_abi::export_fmi2!` or `export_fmi3!`.
        #[allow(non_snake_case, unused_variables, unused_imports, clippy::missing_safety_doc, clippy::too_many_arguments)]
        pub mod $module {
            use $crate::$standard::calls::*;
            use $crate::$standard::*;
            use $crate::fmi_core::standard::{$standard::Call, Standard};
            use $crate::{alike, fmu_states, handle};
            $(
                #[no_mangle]
                pub unsafe extern "C" fn $name($($arg: $ty),*) $(-> $ret)? {
                    $body
                }
            )*
        }
    };
}
