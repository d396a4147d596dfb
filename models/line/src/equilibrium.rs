//! The steady state a line starts in: every state derivative zero at the
//! start time, the drives at their start values. Newton's method on the
//! same evaluation and banded Jacobian the integrator uses. A roll's radius
//! is never steady while web winds on or off, so it keeps its start value
//! (the steady state of the line at that radius), and its surface speed is
//! what is steady: omega' = -omega*r'/r, not 0. The speed of a roller whose
//! speed a table prescribes keeps its start value too. A laminate whose span stands still
//! is steady at any strains of its layers that pull as one: they move together
//! from their start. A contact that may slip starts sticking: its grip's rate is held at the
//! slip (`Roller::hold_contact`), so the steady state has zero slip and the grip the force
//! balance needs; a grip beyond its static limit means the web slides from the start, refused.

use crate::ode::{residual_and_jacobian, Ode};
use crate::spec::Spec;
use solver::band::{Band, BandLu};

const MAX_ITERATIONS: usize = 50;
/// Converged when no state moves by more than this fraction of its size.
const STEP_TOLERANCE: f64 = 1e-13;

/// Per state, the first layer's state of a laminate it moves with (the other layers of a laminate
/// whose span stands still, both its speeds 0: their rates are 0 at any strain, [M6]); else None.
fn tied_layers(ode: &Ode, spec: &Spec) -> Vec<Option<usize>> {
    let net = ode.net.as_ref().expect("initialized");
    let mut tied = vec![None; net.len()];
    for lam in &spec.laminates {
        let parts: Vec<usize> = lam.layers.iter().filter_map(|l| spec.part(&l.part)).collect();
        let still = parts.iter().all(|&p| {
            let d = ode.parts[p].description();
            ["web_a.v", "web_b.v"].iter().all(|name| d.variable_by_name(name).and_then(|v| ode.parts[p].get_real(v.vr).ok()) == Some(0.0))
        });
        if still {
            for &p in &parts[1..] {
                tied[net.first_state[p]] = Some(net.first_state[parts[0]]);
            }
        }
    }
    tied
}

/// (omega, r) of each roll being wound: the line's indices of its angular speed and its radius.
fn wound_rolls(ode: &Ode) -> Vec<(usize, usize)> {
    let net = ode.net.as_ref().expect("initialized");
    let at = |part: usize, index: usize| net.states.iter().position(|s| s.part == part && s.index == index);
    (0..net.len())
        .filter_map(|k| {
            let s = net.states[k];
            let radius = ode.parts[s.part].wound_roll_radius(s.index)?;
            Some((k, at(s.part, radius)?))
        })
        .collect()
}

/// A roll's residual for a steady surface speed v = r*omega: omega' + omega*r'/r (= v'/r) in place
/// of omega', and its row of the Jacobian to match (before the radius's row is replaced).
fn steady_surfaces(rolls: &[(usize, usize)], x: &[f64], f: &mut [f64], mut jac: Option<&mut Band>) {
    for &(w, r) in rolls {
        let (omega, radius, radius_rate) = (x[w], x[r], f[r]);
        f[w] += omega * radius_rate / radius;
        if let Some(jac) = jac.as_deref_mut() {
            let (kl, ku, n) = (jac.lower(), jac.upper(), jac.n());
            for j in w.saturating_sub(kl)..(w + ku + 1).min(n) {
                let mut d = jac.get(w, j) + omega / radius * jac.get(r, j);
                if j == w {
                    d += radius_rate / radius;
                }
                if j == r {
                    d -= omega * radius_rate / (radius * radius);
                }
                jac.set(w, j, d);
            }
        }
    }
}

/// Why a line has no steady state to start in.
#[derive(Debug)]
pub enum NoStart {
    /// The search found none (the line then starts from its parts' start values, with this warning).
    Search(String),
    /// A contact cannot stick: what it needs against what it can give (refused).
    Slides(String),
}

/// Moves the line's states to its steady state, or says why there is none
/// (the states are then as they were).
pub fn solve(ode: &mut Ode, spec: &Spec) -> Result<(), NoStart> {
    for part in &mut ode.parts {
        part.hold_contact(true);
    }
    let solved = search(ode, spec).map_err(NoStart::Search);
    for part in &mut ode.parts {
        part.hold_contact(false);
    }
    solved?;
    let slides: Vec<String> = ode.parts.iter().zip(&spec.parts).filter_map(|(part, ps)| Some(format!("{}: {}", ps.name, part.beyond_grip()?))).collect();
    if slides.is_empty() {
        return Ok(());
    }
    Err(NoStart::Slides(format!("{}: the web slides from the start; use a given start (\"start\": \"given\")", slides.join("; "))))
}

/// Newton's method for the steady state, the parts as `solve` set them.
fn search(ode: &mut Ode, spec: &Spec) -> Result<(), String> {
    let net = ode.net.as_ref().expect("initialized");
    let n = net.len();
    if n == 0 {
        return Ok(());
    }
    let (kl, ku) = (net.kl, net.ku);
    let frozen: Vec<bool> = net.states.iter().map(|s| ode.parts[s.part].held_at_steady_state(s.index)).collect();
    let tied = tied_layers(ode, spec);
    let rolls = wound_rolls(ode);
    let size: Vec<f64> = (0..n).map(|k| ode.scratch.atol[k] / (ode.rtol * ode.scratch.rtol_scale[k])).collect();
    let x0 = ode.x.clone();
    // The parts as they are: a failed search leaves them where its last trial took them (a
    // span's frames at a dancer's far position), where the start state may not even evaluate.
    ode.backup.clone_from(&ode.parts);
    let mut x = x0.clone();
    let (mut f, mut trial_f) = (vec![0.0; n], vec![0.0; n]);
    let mut jac = Band::zeros(n, kl, ku);
    let mut lu = BandLu::new(n, kl, ku);
    let (mut trial, mut simplified) = (vec![0.0; n], vec![0.0; n]);
    let norm = |f: &[f64]| f.iter().zip(&size).map(|(r, s)| (r / s).abs()).fold(0.0, f64::max);
    // A held state's residual: its move from the start, less its first layer's where it is tied to one.
    let held = |i: usize, x: &[f64]| x[i] - x0[i] - tied[i].map_or(0.0, |f| x[f] - x0[f]);
    let result = (|| {
        for _ in 0..MAX_ITERATIONS {
            residual_and_jacobian(ode, &x, &mut f, Some(&mut jac)).map_err(|e| e.into_message())?;
            steady_surfaces(&rolls, &x, &mut f, Some(&mut jac));
            for i in 0..n {
                if frozen[i] || tied[i].is_some() {
                    f[i] = held(i, &x);
                    for j in i.saturating_sub(kl)..(i + ku + 1).min(n) {
                        jac.set(i, j, if i == j { 1.0 } else if tied[i] == Some(j) { -1.0 } else { 0.0 });
                    }
                }
            }
            // c I - a with c = 0 and a = J factors -J: the solve gives -J^-1 f, Newton's step.
            if !lu.factor_shifted(0.0, &jac) {
                return Err("no steady state: the line's Jacobian is singular (a speed or a position that nothing holds, such as a line of torque drives without a speed reference or damping)".to_string());
            }
            let mut step = f.clone();
            lu.solve(&mut step);
            // Damped: halve the step until the simplified Newton step from the trial, J^-1 f(trial) with
            // this J, is shorter than this one (Deuflhard's natural monotonicity test): a residual's
            // norm would weigh each rate by its own time scale, and a contact's web (its small mass)
            // has the shortest.
            let r0 = norm(&step);
            let mut lambda = 1.0;
            loop {
                for i in 0..n {
                    trial[i] = x[i] + lambda * step[i];
                }
                let ok = residual_and_jacobian(ode, &trial, &mut trial_f, None).is_ok();
                if ok {
                    steady_surfaces(&rolls, &trial, &mut trial_f, None);
                    for i in 0..n {
                        if frozen[i] || tied[i].is_some() {
                            trial_f[i] = held(i, &trial);
                        }
                    }
                }
                if ok {
                    simplified.copy_from_slice(&trial_f);
                    lu.solve(&mut simplified);
                }
                if ok && (norm(&simplified) < r0 || lambda < 1e-3) {
                    break;
                }
                lambda *= 0.5;
                if lambda < 1e-4 {
                    return Err("no steady state: Newton's method stalls (the drives may not hold the line at rest)".to_string());
                }
            }
            let moved = (0..n).map(|i| (lambda * step[i] / size[i]).abs()).fold(0.0, f64::max);
            x.copy_from_slice(&trial);
            if moved < STEP_TOLERANCE {
                return Ok(());
            }
        }
        Err(format!("no steady state: Newton's method did not converge in {MAX_ITERATIONS} iterations"))
    })();
    match result {
        Ok(()) => {
            ode.x = x;
            Ok(())
        }
        Err(why) => {
            ode.x = x0;
            std::mem::swap(&mut ode.parts, &mut ode.backup);
            Err(why)
        }
    }
}
