//! What a roll with runout [R15] conserves: the power a taut web's tension delivers at its span's fixed
//! end B is the tension times the material's speed through B, and a rigid roll takes torque times omega.
//! For a web leaving (or arriving at) a turning convex roll, the material passes B at omega*p, p the axis's
//! distance from the web's line; the Roller gives the speed across the moving tangent point,
//! v = omega*p + s*dL/dt, and the tangent point's place along the span (its length L). So with b = 0 and
//! no drive, J*omega*omega' = s*F*(v - s*dL/dt) at every angle (s = +1: the web leaving an unwinder is
//! pulled along its motion; s = -1: the web arriving at a winder is held back): the web's arm in [R1] and its payout are one
//! law, tested here against the work at B, not against each other's code (a torque at r instead of p
//! misses by F*e*omega*cos(psi), 1e-2 of it here). `cargo test -p roller --test energy`.

use fmi_core::{Compiled, Experiment, Model, Resources, Variables};
use roller::description::{Boolean, Integer, Real};
use roller::state::State;
use roller::Roller;

fn get(m: &Roller, var: Real) -> f64 {
    m.get_real(var.vr()).unwrap()
}

/// A roll (1 unwinder, 2 winder) of J = 0.5 kg m^2, R = 0.3 m with 3 mm of runout, no bearing or drive,
/// turning at 10 rad/s, its web at the roll pulled by 200 N towards B, 1 m from the round roll's tangent
/// point; `lobed`: oval by 2 mm and three-lobed by 0.5 mm besides (its support function's harmonics).
fn roll(kind: i32, lobed: bool) -> Roller {
    let mut m = Roller::at_start_values();
    m.set_integer(Integer::roll.vr(), kind).unwrap();
    m.set_boolean(Boolean::runout.vr(), true).unwrap();
    let pulled = if kind == 1 { Real::web_b_F } else { Real::web_a_F };
    for (var, x) in [(Real::J, 0.5), (Real::R, 0.3), (Real::b, 0.0), (Real::v_start, 3.0), (Real::runout_e, 3e-3), (Real::runout_phase, 0.2), (Real::runout_L, 1.0), (pulled, 200.0)] {
        m.set_real(var.vr(), x).unwrap();
    }
    if lobed {
        m.set_integer(Integer::runout_h2_k.vr(), 3).unwrap();
        for (var, x) in [(Real::runout_h1_a, 2e-3), (Real::runout_h1_phase, 0.5), (Real::runout_h2_a, 5e-4), (Real::runout_h2_phase, -1.0)] {
            m.set_real(var.vr(), x).unwrap();
        }
    }
    m.initialize(&Experiment::default(), &Resources::default()).unwrap_or_else(|e| panic!("{}", e.message));
    m
}

/// The span's length L at the roll's angle (an unwinder's web_b.y is runout.L - L, a winder's web_a.y is L).
fn length(m: &mut Roller, kind: i32, angle: f64) -> f64 {
    m.set_active_states(&[State::Angle.index()], &[angle]).unwrap();
    if kind == 1 {
        1.0 - get(m, Real::web_b_y)
    } else {
        get(m, Real::web_a_y)
    }
}

/// At 64 angles over a turn, on an unwinder and a winder, round with runout and out of round: J*omega*omega' = s*F*(omega*p) with omega*p =
/// v - s*dL/dt, dL/dt = omega*dL/d(angle) by a central difference (h = 1e-5 rad: its truncation, 1e-10 of
/// dL/dt's swing, and its rounding, 1e-16/1e-5 of L, far below the 1e-8 asked of the power, whose terms
/// are all of 600 W).
#[test]
fn a_roll_with_runout_takes_the_power_its_web_delivers_at_the_span_end() {
    let (j, omega, tension) = (0.5, 10.0, 200.0);
    for (kind, lobed) in [(1, false), (2, false), (1, true), (2, true)] {
        let mut m = roll(kind, lobed);
        let s = if kind == 1 { 1.0 } else { -1.0 };
        let (mut worst, mut swing) = (0.0f64, 0.0f64);
        for k in 0..64 {
            let angle = k as f64 * std::f64::consts::TAU / 64.0;
            let h = 1e-5;
            let rate = omega * (length(&mut m, kind, angle + h) - length(&mut m, kind, angle - h)) / (2.0 * h);
            length(&mut m, kind, angle);
            let speed = get(&m, if kind == 1 { Real::web_b_v } else { Real::web_a_v });
            let taken = j * omega * get(&m, Real::der_omega);
            let delivered = s * tension * (speed - s * rate);
            worst = worst.max((taken - delivered).abs() / delivered.abs());
            swing = swing.max((delivered.abs() - tension * omega * 0.3).abs() / (tension * omega * 0.3));
        }
        eprintln!("roll {kind}, lobed {lobed}: power taken against delivered at B, worst {worst:e}; the arm swings by {swing:e} of r");
        assert!(worst < 1e-8, "roll {kind}: J omega omega' and F v_B differ by {worst:e} relative");
        assert!(swing > 5e-3, "roll {kind}: the runout must move the arm ({swing:e})");
    }
}
