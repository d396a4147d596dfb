//! FMU states: save and restore continue bit-identically, in the same or
//! another instance, serialized or not; what fmi2DeSerializeFMUstate
//! refuses (truncation, corruption, another format or model, values the
//! setters would refuse); stale and foreign state pointers.

use super::scene::*;
use crate::*;
use fmi_core::description::{Causality, Kind, Variable};
use fmi_core::snapshot::fnv1a;
use crate::Tested;

/// Recomputes the trailing checksum after a deliberate change.
fn fix_checksum(bytes: &mut [u8]) {
    let n = bytes.len();
    let sum = fnv1a(&bytes[..n - 8]);
    bytes[n - 8..].copy_from_slice(&sum.to_le_bytes());
}

/// The serialized bytes of a state in step complete with `values` set.
fn state_bytes<M: Tested>(values: &[(&str, f64)]) -> Vec<u8> {
    let fmu = Fmu::<M>::new();
    fmu.set_all(values);
    fmu.init(0.0);
    let s = fmu.get_state().unwrap();
    fmu.serialize(s).unwrap()
}

/// A value of the Real `v` inside its range whose bits occur nowhere by chance.
fn distinctive(v: &Variable) -> f64 {
    let x = start_of(v);
    let odd = [1.2345678901234567, -1.2345678901234567, 0.012345678901234567, -0.012345678901234567];
    [x * 1.0123456789012345, x * 0.9876543210987654]
        .into_iter()
        .chain(odd)
        .find(|&y| y != x && v.range.contains(y))
        .unwrap_or_else(|| panic!("no distinctive value of {} in {}", v.name, v.range))
}

/// Proves that fmi2GetFMUstate disturbs nothing, that fmi2SetFMUstate
/// brings back everything (time, inputs, state) so that the continuation
/// with varying inputs and step sizes is bit-identical to an uninterrupted
/// run, also when the same state is restored twice, that fmi2GetFMUstate
/// into an own slot updates it in place, and that fmi2FreeFMUstate frees
/// and NULLs the slot.
pub fn fmu_state_round_trip_continues_bit_identically<M: Tested>() {
    let (uninterrupted, t_end) = {
        let (b, t) = running::<M>(20);
        run(&b, t, 20, 50)
    };
    let (a, t) = running::<M>(20);
    let at_save = all_values(&a);
    let mut s = a.get_state().unwrap();
    let (first, t1) = run(&a, t, 20, 50);
    assert_eq!(first, uninterrupted, "fmi2GetFMUstate must not disturb the run");
    assert_eq!(t1, t_end);
    let input = first_real_input::<M>();
    for _ in 0..2 {
        assert_eq!(a.set(&input.name, other_value(input, a.real(&input.name))), OK);
        assert_eq!(a.set_state(s), OK);
        assert_eq!(a.time(), t);
        assert_eq!(all_values(&a), at_save, "inputs, outputs and state as saved");
        assert_eq!(run(&a, t, 20, 50).0, uninterrupted);
    }
    let old = s;
    assert_eq!(a.get_state_into(&mut s), OK);
    assert_eq!(s, old, "an own state is updated in place");
    assert_eq!(a.set_state(s), OK);
    assert_eq!(a.time(), t_end);
    assert_eq!(a.free_state(&mut s), OK);
    assert!(s.is_null());
    assert!(a.logs().is_empty(), "{:?}", a.logs());
}

/// Proves that fmi2SerializedFMUstateSize gives the serialized length, and
/// that a serialized state deserialized into the same instance, and into
/// another instance that was only instantiated (never initialized),
/// continues bit-identically; that serialization is deterministic; and that
/// deserializing into an own slot replaces that state in place.
pub fn serialized_state_continues_bit_identically_in_any_instance<M: Tested>() {
    let (a, t) = running::<M>(20);
    let s = a.get_state().unwrap();
    let size = a.serialized_size(s).unwrap();
    let bytes = a.serialize(s).unwrap();
    assert_eq!(bytes.len(), size);
    assert_eq!(&bytes[..8], b"FMI2SNAP");
    let at_save = all_values(&a);
    let (reference, _) = run(&a, t, 20, 40);

    let s2 = a.deserialize(&bytes).unwrap();
    assert_ne!(s2, s);
    assert_eq!(a.set_state(s2), OK);
    assert_eq!(all_values(&a), at_save);
    assert_eq!(run(&a, t, 20, 40).0, reference, "same instance");

    let b = Fmu::<M>::new();
    let sb = b.deserialize(&bytes).unwrap();
    assert_eq!(b.serialized_size(sb), Ok(size));
    assert_eq!(b.serialize(sb).unwrap(), bytes, "serialization is deterministic");
    assert_eq!(b.set_state(sb), OK);
    assert_eq!(phase_of(&b), Phase::Complete);
    assert_eq!(b.time(), t);
    assert_eq!(all_values(&b), at_save);
    assert_eq!(run(&b, t, 20, 40).0, reference, "another, never initialized instance");

    let mut slot = b.get_state().unwrap();
    let old = slot;
    assert_eq!(b.deserialize_into(&bytes, &mut slot), OK);
    assert_eq!(slot, old, "an own state is replaced in place");
    assert_eq!(b.set_state(slot), OK);
    assert_eq!(b.time(), t);
    assert!(a.logs().is_empty() && b.logs().is_empty());
}

/// Proves that an FMU state saved in initialization mode carries the
/// experiment given to fmi2SetupExperiment (tolerance, start and stop
/// time): restored into another instance, or into the same instance after
/// fmi2Reset, initialization ends at the start time and the states saved
/// then are byte for byte those of the original run.
pub fn fmu_state_saved_in_initialization_mode_keeps_the_experiment<M: Tested>() {
    let a = Fmu::<M>::new();
    assert_eq!(a.setup_experiment_full(Some(1e-5), 0.25, Some(9.5)), OK);
    assert_eq!(a.enter_init(), OK);
    let s = a.get_state().unwrap();
    let bytes = a.serialize(s).unwrap();
    let after_init = |fmu: &Fmu<M>| {
        assert_eq!(fmu.exit_init(), OK, "{:?}", fmu.logs());
        assert_eq!(fmu.time(), 0.25);
        let state = fmu.get_state().unwrap();
        fmu.serialize(state).unwrap()
    };
    let reference = after_init(&a);
    // The control: another experiment gives other bytes, so the comparison can tell.
    let control = Fmu::<M>::new();
    assert_eq!(control.setup_experiment_full(None, 0.25, None), OK);
    assert_eq!(control.enter_init(), OK);
    assert_ne!(after_init(&control), reference, "the experiment must be part of the state");

    let b = Fmu::<M>::new();
    let sb = b.deserialize(&bytes).unwrap();
    assert_eq!(b.set_state(sb), OK);
    assert_eq!(after_init(&b), reference, "restored in another instance");

    assert_eq!(a.reset(), OK);
    assert_eq!(a.set_state(s), OK);
    assert_eq!(after_init(&a), reference, "restored after fmi2Reset");
}

/// Proves that an FMU state saved in initialization mode after an output was read there (which
/// initializes the model provisionally) and a parameter was changed since restores, and saves to
/// its own bytes again, for every parameter and in both interfaces: what the provisional
/// initialization left must not depend on a value that has changed (the Line's fuzzing met a
/// roller's profile checked against its `carriage`, and a network of the states a roll's
/// `wound.thickness` decides, each refused when its state was restored).
pub fn state_saved_after_a_parameter_changed_in_initialization_mode_restores<M: Tested>() {
    let output = first_real_output::<M>();
    let interfaces: &[i32] = if M::description().model_exchange { &[CS, ME] } else { &[CS] };
    let mut checked = 0;
    for &fmu_type in interfaces {
        for p in settable_parameters::<M>().into_iter().filter(|p| p.kind != Kind::String) {
            let fmu = Fmu::<M>::with(&Setup { fmu_type, ..Setup::default() });
            assert_eq!(fmu.enter_init(), OK);
            assert!(fmu.get(&output.name).is_ok(), "{}: {:?}", output.name, fmu.logs());
            if fmu.set(&p.name, other_value(p, start_of(p))) != OK {
                continue; // a value the model refuses when it is set: nothing changed
            }
            let bytes = fmu.serialize(fmu.get_state().unwrap()).unwrap();
            let back = fmu.deserialize(&bytes).unwrap_or_else(|_| panic!("{} changed (type {fmu_type}): {:?}", p.name, fmu.logs()));
            assert_eq!(fmu.serialize(back).unwrap(), bytes, "{} changed (type {fmu_type})", p.name);
            checked += 1;
        }
    }
    assert!(checked > 0, "no parameter could be changed");
}

/// Proves that a state saved by a Co-Simulation instance is refused by
/// fmi2SetFMUstate of a Model Exchange instance (the phases do not carry
/// over) with fmi2Error and one line naming both interfaces, and that the
/// Model Exchange instance is not changed by the attempt.
pub fn state_of_the_other_interface_is_refused<M: Tested>() {
    if !M::description().model_exchange {
        return;
    }
    let (a, _) = running::<M>(3);
    let bytes = a.serialize(a.get_state().unwrap()).unwrap();
    let me = Fmu::<M>::with(&Setup { fmu_type: ME, ..Setup::default() });
    me.init(0.0);
    let before = all_values(&me);
    let s = me.deserialize(&bytes).expect("the bytes themselves are a valid state");
    assert_eq!(me.set_state(s), ERROR);
    assert_one_error(&me.take_logs(), &["fmi2SetFMUstate", "Co-Simulation", "Model Exchange"]);
    assert_eq!(all_values(&me), before);
}

/// Proves that fmi2SerializeFMUstate refuses a buffer one byte too small (and
/// an empty one) with one line giving both sizes and without writing to the
/// buffer, and writes exactly `size` bytes into a larger one.
pub fn serialize_checks_the_buffer_size<M: Tested>() {
    let (a, _) = running::<M>(3);
    let s = a.get_state().unwrap();
    let size = a.serialized_size(s).unwrap();
    let bytes = a.serialize(s).unwrap();

    let mut small = vec![0xAAu8; size - 1];
    assert_eq!(a.serialize_into(s, &mut small), ERROR);
    assert_one_error(&a.take_logs(), &["fmi2SerializeFMUstate", &format!("holds {} bytes", size - 1), &format!("needs {size}")]);
    assert!(small.iter().all(|&b| b == 0xAA), "nothing written");
    assert_eq!(a.serialize_into(s, &mut []), ERROR);
    assert_one_error(&a.take_logs(), &["holds 0 bytes"]);

    let mut big = vec![0xAAu8; size + 16];
    assert_eq!(a.serialize_into(s, &mut big), OK);
    assert_eq!(&big[..size], &bytes[..]);
    assert!(big[size..].iter().all(|&b| b == 0xAA), "only `size` bytes written");
}

/// Proves that fmi2DeSerializeFMUstate refuses every truncation (each length
/// from 0 to len-1), a padded state, and every single flipped bit, each with
/// fmi2Error, one line, and the slot left NULL.
pub fn deserialize_refuses_truncated_padded_and_corrupted_bytes<M: Tested>() {
    let (a, _) = running::<M>(3);
    let s = a.get_state().unwrap();
    let bytes = a.serialize(s).unwrap();
    let b = Fmu::<M>::new();
    let refuse = |data: &[u8], what: &str| {
        let mut slot = State::NULL;
        assert_eq!(b.deserialize_into(data, &mut slot), ERROR, "{what}");
        assert!(slot.is_null(), "{what}");
        assert_one_error(&b.take_logs(), &["fmi2DeSerializeFMUstate", "rejected"]);
    };
    for len in 0..bytes.len() {
        refuse(&bytes[..len], &format!("truncated to {len}"));
    }
    let mut padded = bytes.clone();
    padded.push(0);
    refuse(&padded, "padded");
    for i in 0..bytes.len() {
        for bit in 0..8 {
            let mut flipped = bytes.clone();
            flipped[i] ^= 1 << bit;
            refuse(&flipped, &format!("bit {bit} of byte {i} flipped"));
        }
    }
    // The control: the intact bytes are accepted by the same instance.
    assert!(b.deserialize(&bytes).is_ok());
}

/// Where a Boolean parameter's byte is: the one byte that differs between
/// states with it off and on (the first Boolean for which there is one).
fn boolean_field<M: Tested>(base: &[(&str, f64)], reference: &[u8]) -> Option<(&'static str, usize)> {
    let booleans = settable_parameters::<M>().into_iter().filter(|v| v.kind == Kind::Boolean);
    booleans.into_iter().find_map(|v| {
        let flipped = state_bytes::<M>(&[base, &[(v.name.as_ref(), 1.0 - start_of(v))]].concat());
        let differing: Vec<usize> = (0..reference.len() - 8).filter(|&i| reference.get(i) != flipped.get(i)).collect();
        (flipped.len() == reference.len() && differing.len() == 1).then(|| (v.name.as_ref(), differing[0]))
    })
}

/// Proves that states with a valid checksum but a wrong magic number, an
/// unknown format version (0, and the current one + 1), another model's
/// GUID hash, a length field that disagrees, an unknown phase, a non-finite
/// time or Real parameter, or a non-Boolean byte are refused with a message
/// giving the reason; the control (checksum recomputed, nothing else
/// changed) is accepted, so each refusal is for the reason stated and not a
/// checksum mismatch. Header, phase and time are at the offsets
/// fmi_core::snapshot documents; the model fields are located by their
/// values (the first Real parameter by a distinctive bit pattern, a Boolean
/// parameter as the one byte that differs between states with it off and on).
pub fn deserialize_refuses_wrong_magic_version_model_and_payload<M: Tested>() {
    let real = settable_parameters::<M>().into_iter().find(|v| v.kind == Kind::Real).expect("a Real parameter");
    let x0 = distinctive(real);
    let base = [(real.name.as_ref(), x0)];
    let bytes = state_bytes::<M>(&base);
    let b = Fmu::<M>::new();
    let version = u32::from_le_bytes(bytes[8..12].try_into().unwrap());
    let real_at = bytes.windows(8).position(|w| w == x0.to_le_bytes()).expect("the Real parameter in the state");
    let (newer, older) = (format!("format version {}", version + 1), "format version 0".to_string());
    let real_is_nan = format!("{} is NaN", real.name);

    let mut control = bytes.clone();
    fix_checksum(&mut control);
    assert_eq!(control, bytes);
    assert!(b.deserialize(&control).is_ok());

    type Patch = Box<dyn Fn(&mut Vec<u8>)>;
    let mut cases: Vec<(Patch, String)> = vec![
        (Box::new(|x| x[..8].copy_from_slice(b"FMI2SNAQ")), "wrong magic".into()),
        (Box::new(|x| x[..8].copy_from_slice(b"FMI3SNAP")), "wrong magic".into()),
        (Box::new(move |x| x[8..12].copy_from_slice(&(version + 1).to_le_bytes())), newer),
        (Box::new(|x| x[8..12].copy_from_slice(&0u32.to_le_bytes())), older),
        (
            Box::new(|x| x[12..20].copy_from_slice(&fnv1a(b"{00000000-0000-0000-0000-000000000000}").to_le_bytes())),
            "another model".into(),
        ),
        (
            Box::new(|x| {
                let n = u32::from_le_bytes(x[20..24].try_into().unwrap());
                x[20..24].copy_from_slice(&(n + 1).to_le_bytes())
            }),
            "truncated or padded".into(),
        ),
        (Box::new(|x| x[24] = 8), "phase 8".into()),
        (Box::new(|x| x[24] = 255), "phase 255".into()),
        (Box::new(|x| x[25..33].copy_from_slice(&f64::NAN.to_bits().to_le_bytes())), "time is NaN".into()),
        (Box::new(|x| x[25..33].copy_from_slice(&f64::INFINITY.to_bits().to_le_bytes())), "time is inf".into()),
        (Box::new(move |x| x[real_at..real_at + 8].copy_from_slice(&f64::NAN.to_bits().to_le_bytes())), real_is_nan),
    ];
    if let Some((name, at)) = boolean_field::<M>(&base, &bytes) {
        cases.push((Box::new(move |x| x[at] = 2), format!("{name} is 2")));
    } else {
        assert!(!settable_parameters::<M>().iter().any(|v| v.kind == Kind::Boolean), "no Boolean parameter found in the state");
    }
    for (patch, needle) in cases {
        let mut data = bytes.clone();
        patch(&mut data);
        fix_checksum(&mut data);
        let mut slot = State::NULL;
        assert_eq!(b.deserialize_into(&data, &mut slot), ERROR, "{needle}");
        assert!(slot.is_null());
        assert_one_error(&b.take_logs(), &["fmi2DeSerializeFMUstate", &needle]);
    }
}

/// Two allowed values of `v`, as set by name and as stored (little-endian),
/// and a value the setters or initialization would refuse, as stored.
fn field_values(v: &Variable) -> Option<(f64, f64, Vec<u8>, Vec<u8>, Vec<u8>)> {
    match v.kind {
        Kind::Real if !v.range.is_unbounded() => {
            let (a, b) = (distinctive(v), other_value(v, start_of(v)));
            let bad = if v.range.lo > f64::MIN { f64::MIN } else { f64::MAX };
            Some((a, b, a.to_le_bytes().to_vec(), b.to_le_bytes().to_vec(), bad.to_le_bytes().to_vec()))
        }
        Kind::Integer if !v.range.is_unbounded() => {
            let (a, b) = (start_of(v), other_value(v, start_of(v)));
            let bad = if v.range.lo > i32::MIN as f64 { v.range.lo - 1.0 } else { v.range.hi + 1.0 };
            let le = |x: f64| (x as i32).to_le_bytes().to_vec();
            Some((a, b, le(a), le(b), le(bad)))
        }
        Kind::Enumeration { values, .. } => {
            let (a, b) = (start_of(v), other_value(v, start_of(v)));
            let le = |x: i32| x.to_le_bytes().to_vec();
            Some((a, b, le(a as i32), le(b as i32), le(values.iter().max().unwrap() + 1)))
        }
        _ => None,
    }
}

/// Proves that fmi2DeSerializeFMUstate refuses a state whose checksum is
/// valid but whose values the FMU would refuse through fmi2SetInteger /
/// fmi2SetReal and fmi2ExitInitializationMode: every parameter with an
/// allowed range or enumeration items, set to a value outside them (a
/// state in step complete, so after initialization). The field is located
/// as the place where two serializations that differ only in it hold its
/// two values.
pub fn deserialize_refuses_values_outside_the_declared_ranges<M: Tested>() {
    let mut accepted = Vec::new();
    let mut cases = 0;
    let parameters = settable_parameters::<M>().into_iter().filter(|v| v.causality == Causality::Parameter);
    for v in parameters {
        let Some((a, b, a_le, b_le, bad)) = field_values(v) else { continue };
        let x = state_bytes::<M>(&[(&v.name, a)]);
        let y = state_bytes::<M>(&[(&v.name, b)]);
        let w = a_le.len();
        let candidates: Vec<usize> = (0..=x.len() - 8 - w).filter(|&i| x[i..i + w] == a_le[..] && y[i..i + w] == b_le[..]).collect();
        assert!(!candidates.is_empty(), "{} not found in the state", v.name);
        // In a model of connected parts the value can also sit in another
        // part's input that it feeds (a line: the web speed of the span before
        // a roller): the field is the place whose forgery is refused naming it.
        let needle = format!("{} = ", v.name);
        let mut refused = None;
        for at in candidates {
            let mut z = x.clone();
            z[at..at + w].copy_from_slice(&bad);
            fix_checksum(&mut z);
            let fmu = Fmu::<M>::new();
            if let Err(status) = fmu.deserialize(&z) {
                let lines = fmu.take_logs();
                if lines.iter().any(|l| l.message.contains(&needle)) {
                    refused = Some((status, lines));
                    break;
                }
            }
        }
        match refused {
            None => accepted.push(v.name.as_ref()),
            Some((status, lines)) => {
                assert_eq!(status, ERROR);
                assert_one_error(&lines, &["fmi2DeSerializeFMUstate", &needle]);
            }
        }
        cases += 1;
    }
    assert!(cases > 0, "no parameter with an allowed range: nothing to check");
    assert!(accepted.is_empty(), "accepted crafted states with out-of-range {accepted:?}");
}

/// Proves that an FMU state pointer is checked before use: freeing a state
/// twice (through a stale copy of the pointer), setting, sizing or
/// serializing a freed state, and using a pointer that this instance never
/// handed out (a foreign address, or another instance's state) as the state
/// or as a non-NULL `*FMUstate` slot all give fmi2Error with one line,
/// leave the slot as it was, and do not harm the owner; freeing a NULL slot
/// is a no-op.
pub fn stale_and_foreign_state_pointers_are_refused<M: Tested>() {
    let (a, _) = running::<M>(3);
    let bytes = a.serialize(a.get_state().unwrap()).unwrap();
    let mut s = a.get_state().unwrap();
    let stale = s;
    assert_eq!(a.free_state(&mut s), OK);
    assert!(s.is_null());

    let mut copy = stale;
    assert_eq!(a.free_state(&mut copy), ERROR, "second free");
    assert_one_error(&a.take_logs(), &["fmi2FreeFMUstate", "not an FMU state of this instance"]);
    assert_eq!(copy, stale);
    assert_eq!(a.set_state(stale), ERROR);
    assert_one_error(&a.take_logs(), &["fmi2SetFMUstate", "not an FMU state of this instance"]);
    assert_eq!(a.serialized_size(stale), Err(ERROR));
    assert_one_error(&a.take_logs(), &["fmi2SerializedFMUstateSize"]);
    assert_eq!(a.serialize_into(stale, &mut [0u8; 4096]), ERROR);
    assert_one_error(&a.take_logs(), &["fmi2SerializeFMUstate"]);

    let (b, _) = running::<M>(2);
    let sb = b.get_state().unwrap();
    for foreign in [State::foreign(), sb] {
        assert_eq!(a.set_state(foreign), ERROR);
        assert_one_error(&a.take_logs(), &["fmi2SetFMUstate"]);
        let mut slot = foreign;
        assert_eq!(a.get_state_into(&mut slot), ERROR);
        assert_one_error(&a.take_logs(), &["fmi2GetFMUstate", "neither NULL nor an FMU state of this instance"]);
        assert_eq!(a.deserialize_into(&bytes, &mut slot), ERROR);
        assert_one_error(&a.take_logs(), &["fmi2DeSerializeFMUstate", "neither NULL nor"]);
        assert_eq!(a.free_state(&mut slot), ERROR);
        assert_one_error(&a.take_logs(), &["fmi2FreeFMUstate"]);
        assert_eq!(slot, foreign);
    }
    assert_eq!(b.set_state(sb), OK, "the owner's state is unharmed");
    let mut null = State::NULL;
    assert_eq!(a.free_state(&mut null), OK);
    assert!(a.take_logs().is_empty());
}

/// Proves that restoring a state saved in step complete brings an instance
/// back from the error state: fmi2DoStep, refused in the error state, works
/// again and continues exactly like an undisturbed run.
pub fn set_fmu_state_recovers_from_the_error_state<M: Tested>() {
    let (reference, _) = {
        let (r, t) = running::<M>(10);
        run(&r, t, 10, 20)
    };
    let (a, t) = running::<M>(10);
    let s = a.get_state().unwrap();
    assert_eq!(a.enter_init(), ERROR);
    assert_eq!(phase_of(&a), Phase::Error);
    assert_eq!(a.do_step(t, 0.01), ERROR);
    assert_eq!(a.set_state(s), OK);
    assert_eq!(phase_of(&a), Phase::Complete);
    assert_eq!(run(&a, t, 10, 20).0, reference);
}
