//! [`bind_variables!`](crate::bind_variables): each variable of a model
//! description bound to its field once, beside the XML. Get, set, the
//! variables' part of an FMU state and the fields of input derivatives all
//! follow from that one binding. The matches are over the enums the
//! generator emits, so a variable added to or removed from the XML without
//! its binding stops the build.
//!
//! A binding is one of
//! * `param(path)` — a parameter stored at `self.path`;
//! * `input(path)` — an input stored at `self.inputs.path`; input
//!   derivatives land at the same path in a value of the `inputs` type;
//! * `computed(expr)` — a value computed as `self.expr` (outputs, locals);
//! * `group(field)` — a field of the group the model computes together
//!   (`group: (path): Type`, read as `self.path.field`); a caller that holds
//!   the group reads every variable of it with `group_real`.
//!
//! With `tangents: Type` the binding also writes `along`: the tangent of each
//! computed variable read off the model's tangents, where `t.x` is the
//! derivative of `self.x()` (the binding's expression without its empty
//! calls: `outputs().stress` is `t.outputs.stress`). So the tangents mirror
//! the model's computed values, and no variable is mapped to them by hand.
//!
//! The Boolean block may begin with `@effects(path)`: the model's effects
//! (the generated `Effects` set at `self.path`) are then bound all at once,
//! and the block lists the other Booleans (the generated `Switch`es). A new
//! effect in the XML needs no line here.
//!
//! String parameters are stored as `Arc<str>`: cloning a model (which the
//! layer does to make a call all-or-nothing) then never allocates.
//!
//! The caller has the generated `Real`, `Integer`, `Boolean`, `Text`, `Effect`,
//! `Switch`, `BooleanKind` and `DESCRIPTION` in scope; the binding makes the
//! model `Compiled` (its interface is that generated table).

/// Writes the `Variables` impl and the inherent `real`, `integer`,
/// `boolean` and `input_field` functions of a model from its bindings (and
/// `group_real` and `along` where it has a group and tangents).
#[macro_export]
macro_rules! bind_variables {
    (model: $model:ty, inputs: $inputs:ty, group: $group:tt: $group_ty:ty, tangents: $tangents:ty, $($bindings:tt)*) => {
        $crate::__bind_variables! { $model; $inputs; $group; [$group_ty]; [$tangents]; $($bindings)* }
    };
    (model: $model:ty, inputs: $inputs:ty, tangents: $tangents:ty, $($bindings:tt)*) => {
        $crate::__bind_variables! { $model; $inputs; (); []; [$tangents]; $($bindings)* }
    };
    (model: $model:ty, inputs: $inputs:ty, $($bindings:tt)*) => {
        $crate::__bind_variables! { $model; $inputs; (); []; []; $($bindings)* }
    };
}

/// `bind_variables!` with the group as one token tree (its path, `()` for none), the group's
/// type and the tangents' as `[]` or `[Type]`.
#[doc(hidden)]
#[macro_export]
macro_rules! __bind_variables {
    (
        $model:ty;
        $inputs:ty;
        $group:tt;
        $group_ty:tt;
        $tangents:tt;
        real { $($r:ident: $rk:ident($($rf:tt)+)),* $(,)? }
        integer { $($i:ident: $ik:ident($($if:tt)+)),* $(,)? }
        boolean { $(@effects($($ef:tt)+),)? $($b:ident: $bk:ident($($bf:tt)+)),* $(,)? }
        string { $($s:ident: $sk:ident($($sf:tt)+)),* $(,)? }
    ) => {
        impl $model {
            /// The value of a Real variable.
            #[inline(always)]
            pub fn real(&self, var: Real) -> f64 {
                match var { $(Real::$r => $crate::__bound!(self, $group, $rk, $($rf)+),)* }
            }

            /// The value of an Integer or enumeration variable.
            pub fn integer(&self, var: Integer) -> i32 {
                match var { $(Integer::$i => $crate::IntegerValue::to_i32($crate::__bound!(self, (), $ik, $($if)+)),)* }
            }

            /// Sets a parameter or input; `Err` for computed variables.
            #[inline(always)]
            pub fn set_real_var(&mut self, var: Real, value: f64) -> $crate::FmiResult {
                match var { $(Real::$r => $crate::__bound_set!(self, var, value, $rk, $($rf)+),)* }
            }

            pub fn boolean(&self, var: Boolean) -> bool {
                match var.kind() {
                    BooleanKind::Effect(effect) => $crate::__effects!(get, self, effect; $($($ef)+)?),
                    BooleanKind::Switch(switch) => match switch { $(Switch::$b => $crate::__bound!(self, (), $bk, $($bf)+),)* },
                }
            }

            /// The field of an input in a set of input values or of their
            /// rates; `None` for variables that are not inputs.
            #[allow(unused_variables)]
            pub fn input_field(u: &mut $inputs, var: Real) -> Option<&mut f64> {
                match var { $(Real::$r => $crate::__bound_input!(u, $rk, $($rf)+),)* }
            }
        }

        $crate::__bind_group!($model; $group_ty; $($r: $rk($($rf)+)),*);
        $crate::__bind_tangents!($model; $tangents; $group; $($r: $rk($($rf)+)),*);

        impl $crate::Compiled for $model {
            fn compiled() -> &'static $crate::description::ModelDescription {
                &DESCRIPTION
            }
        }

        impl $crate::Variables for $model {
            #[inline(always)]
            fn get_real(&self, vr: u32) -> $crate::FmiResult<f64> {
                match Real::from_vr(vr) {
                    Some(var) => Ok(self.real(var)),
                    None => Err($crate::model::unknown_vr(vr)),
                }
            }

            #[inline(always)]
            fn set_real(&mut self, vr: u32, value: f64) -> $crate::FmiResult {
                self.set_real_var(Real::from_vr(vr).ok_or_else(|| $crate::model::unknown_vr(vr))?, value)
            }

            fn get_integer(&self, vr: u32) -> $crate::FmiResult<i32> {
                Ok(self.integer(Integer::from_vr(vr).ok_or_else(|| $crate::model::unknown_vr(vr))?))
            }

            fn set_integer(&mut self, vr: u32, value: i32) -> $crate::FmiResult {
                let var = Integer::from_vr(vr).ok_or_else(|| $crate::model::unknown_vr(vr))?;
                match var {
                    $(Integer::$i => $crate::__bound_set!(self, var, $crate::model::integer_value(var.name(), value)?, $ik, $($if)+),)*
                }
            }

            fn get_boolean(&self, vr: u32) -> $crate::FmiResult<bool> {
                Ok(self.boolean(Boolean::from_vr(vr).ok_or_else(|| $crate::model::unknown_vr(vr))?))
            }

            fn set_boolean(&mut self, vr: u32, value: bool) -> $crate::FmiResult {
                let var = Boolean::from_vr(vr).ok_or_else(|| $crate::model::unknown_vr(vr))?;
                match var.kind() {
                    BooleanKind::Effect(effect) => $crate::__effects!(set, self, effect, value; $($($ef)+)?),
                    BooleanKind::Switch(switch) => match switch { $(Switch::$b => $crate::__bound_set!(self, var, value, $bk, $($bf)+),)* },
                }
            }

            fn get_string(&self, vr: u32) -> $crate::FmiResult<&str> {
                match Text::from_vr(vr).ok_or_else(|| $crate::model::unknown_vr(vr))? {
                    $(Text::$s => Ok(&*$crate::__bound!(self, (), $sk, $($sf)+)),)*
                }
            }

            fn set_string(&mut self, vr: u32, value: &str) -> $crate::FmiResult {
                let var = Text::from_vr(vr).ok_or_else(|| $crate::model::unknown_vr(vr))?;
                match var { $(Text::$s => $crate::__bound_set!(self, var, ::std::sync::Arc::from(value), $sk, $($sf)+),)* }
            }

            fn save_variables(&self, out: &mut $crate::StateWriter) {
                $($crate::__bound_save!(out.f64, self, $rk, ::core::convert::identity, $($rf)+);)*
                $($crate::__bound_save!(out.i32, self, $ik, $crate::IntegerValue::to_i32, $($if)+);)*
                $crate::__effects!(save, self, out; $($($ef)+)?);
                $($crate::__bound_save!(out.bool, self, $bk, ::core::convert::identity, $($bf)+);)*
                $($crate::__bound_save!(out.str, self, $sk, @ref, $($sf)+);)*
            }

            fn load_variables(&mut self, input: &mut $crate::StateReader) -> $crate::FmiResult {
                $($crate::__bound_load!(self, $rk, input.finite(Real::$r.name())?, $($rf)+);)*
                $($crate::__bound_load!(self, $ik,
                    $crate::model::integer_value(Integer::$i.name(), input.i32(Integer::$i.name())?)?, $($if)+);)*
                $crate::__effects!(load, self, input; $($($ef)+)?);
                $($crate::__bound_load!(self, $bk, input.bool(Boolean::$b.name())?, $($bf)+);)*
                $($crate::__bound_load!(self, $sk, ::std::sync::Arc::from(input.string(Text::$s.name())?), $($sf)+);)*
                Ok(())
            }
        }
    };
}

#[doc(hidden)]
#[macro_export]
macro_rules! __bound {
    ($s:tt, $g:tt, param, $($f:tt)+) => { $s.$($f)+ };
    ($s:tt, $g:tt, input, $($f:tt)+) => { $s.inputs.$($f)+ };
    ($s:tt, $g:tt, computed, $($f:tt)+) => { $s.$($f)+ };
    ($s:tt, ($($g:tt)+), group, $f:ident) => { $s.$($g)+.$f };
}

/// `group_real`, where the model has a group: its variables read off a value of the group.
#[doc(hidden)]
#[macro_export]
macro_rules! __bind_group {
    ($model:ty; []; $($r:ident: $rk:ident($($rf:tt)+)),*) => {};
    ($model:ty; [$group_ty:ty]; $($r:ident: $rk:ident($($rf:tt)+)),*) => {
        impl $model {
            /// A variable of the group read off `group` (computed once for several); None for
            /// the variables outside it.
            #[inline(always)]
            pub fn group_real(group: &$group_ty, var: Real) -> Option<f64> {
                match var { $(Real::$r => $crate::__bound_in_group!(group, $rk, $($rf)+),)* }
            }
        }
    };
}

#[doc(hidden)]
#[macro_export]
macro_rules! __bound_in_group {
    ($g:ident, group, $f:ident) => { Some($g.$f) };
    ($g:ident, $kind:ident, $($f:tt)+) => { None };
}

/// `along`, where the model has tangents: each computed variable's tangent, `t.x` for `self.x()`.
#[doc(hidden)]
#[macro_export]
macro_rules! __bind_tangents {
    ($model:ty; []; $group:tt; $($r:ident: $rk:ident($($rf:tt)+)),*) => {};
    ($model:ty; [$tangents:ty]; $group:tt; $($r:ident: $rk:ident($($rf:tt)+)),*) => {
        impl $model {
            /// The tangent of the computed variable `var` in `t` (None: a parameter or an input).
            #[inline]
            pub fn along(t: &$tangents, var: Real) -> Option<f64> {
                match var { $(Real::$r => $crate::__tangent!(t, $group, $rk, $($rf)+),)* }
            }
        }
    };
}

#[doc(hidden)]
#[macro_export]
macro_rules! __tangent {
    ($t:ident, $g:tt, param, $($f:tt)+) => { None };
    ($t:ident, $g:tt, input, $($f:tt)+) => { None };
    ($t:ident, $g:tt, computed, $($f:tt)+) => { Some($crate::__field_path!([$t .] $($f)+)) };
    ($t:ident, ($($g:tt)+), group, $f:ident) => { Some($crate::__field_path!([$t .] $($g)+ . $f)) };
}

/// `t` followed by a path with its empty calls dropped: `[t] outputs().stress` is `t.outputs.stress`.
#[doc(hidden)]
#[macro_export]
macro_rules! __field_path {
    ([$($done:tt)*]) => { $($done)* };
    ([$($done:tt)*] () $($rest:tt)*) => { $crate::__field_path!([$($done)*] $($rest)*) };
    ([$($done:tt)*] $next:tt $($rest:tt)*) => { $crate::__field_path!([$($done)* $next] $($rest)*) };
}

#[doc(hidden)]
#[macro_export]
macro_rules! __bound_set {
    ($s:tt, $var:ident, $value:expr, param, $($f:tt)+) => {{ $s.$($f)+ = $value; Ok(()) }};
    ($s:tt, $var:ident, $value:expr, input, $($f:tt)+) => {{ $s.inputs.$($f)+ = $value; Ok(()) }};
    ($s:tt, $var:ident, $value:expr, computed, $($f:tt)+) => { Err($crate::model::not_settable($var.name())) };
    ($s:tt, $var:ident, $value:expr, group, $($f:tt)+) => { Err($crate::model::not_settable($var.name())) };
}

#[doc(hidden)]
#[macro_export]
macro_rules! __bound_input {
    ($u:ident, input, $($f:tt)+) => { Some(&mut $u.$($f)+) };
    ($u:ident, $kind:ident, $($f:tt)+) => { None };
}

#[doc(hidden)]
#[macro_export]
macro_rules! __bound_save {
    ($out:ident.$put:ident, $s:tt, param, @ref, $($f:tt)+) => { $out.$put(&$s.$($f)+) };
    ($out:ident.$put:ident, $s:tt, param, $conv:path, $($f:tt)+) => { $out.$put($conv($s.$($f)+)) };
    ($out:ident.$put:ident, $s:tt, input, $conv:path, $($f:tt)+) => { $out.$put($conv($s.inputs.$($f)+)) };
    ($out:ident.$put:ident, $s:tt, computed, $conv:path, $($f:tt)+) => { () };
    ($out:ident.$put:ident, $s:tt, group, $conv:path, $($f:tt)+) => { () };
}

#[doc(hidden)]
#[macro_export]
macro_rules! __bound_load {
    ($s:tt, param, $value:expr, $($f:tt)+) => { $s.$($f)+ = $value };
    ($s:tt, input, $value:expr, $($f:tt)+) => { $s.inputs.$($f)+ = $value };
    ($s:tt, computed, $value:expr, $($f:tt)+) => { () };
    ($s:tt, group, $value:expr, $($f:tt)+) => { () };
}

/// The effects' part of a binding: every effect through the `Effects` set
/// at the given path (in `Effect::ALL`'s order), or none when there is no path.
#[doc(hidden)]
#[macro_export]
macro_rules! __effects {
    (get, $s:tt, $e:ident;) => { match $e {} };
    (get, $s:tt, $e:ident; $($f:tt)+) => { $s.$($f)+.get($e) };
    (set, $s:tt, $e:ident, $v:expr;) => { match $e {} };
    (set, $s:tt, $e:ident, $v:expr; $($f:tt)+) => {{ *$s.$($f)+.get_mut($e) = $v; Ok(()) }};
    (save, $s:tt, $out:ident;) => { () };
    (save, $s:tt, $out:ident; $($f:tt)+) => { for effect in Effect::ALL { $out.bool($s.$($f)+.get(effect)) } };
    (load, $s:tt, $input:ident;) => { () };
    (load, $s:tt, $input:ident; $($f:tt)+) => {
        for effect in Effect::ALL { *$s.$($f)+.get_mut(effect) = $input.bool(effect.name())? }
    };
}
