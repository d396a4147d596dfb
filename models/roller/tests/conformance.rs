//! The conformance suite of the FMI layer (fmi/testkit), run on the Roller's library.

use fmi_testkit::conformance::{Hints, Point};

/// A speed drive from a profile: the drive's torque then answers the web
/// tensions within the step (tau lists web_a.F and web_b.F); the same with
/// every inlet and outlet in use, where the extra ports' tensions reach tau
/// and their strains the merged web_b.eps [R5]; a web that may slip on a wrap
/// and at a nip, under an air film [R6]-[R8], with the web pulling on both sides, running forward with
/// the nip at the entry and back with it at the exit; a drive's loop; a brake;
/// an ideal speed drive on its input; a dancer loop [R13], without a lag (its position reaches tau) and with one;
/// a speed-driven winder of four webs, whose r' reads their merged strain [R3] (it reaches tau); a
/// winder and an unwinder with runout [R15]; a winder with a lay-on roller [R18] pressed on it, round and with runout.
fn hints() -> Hints {
    let speed_drive = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/scenes/speed_drive.json");
    let nip = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/scenes/traction_nip.json");
    let brake = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/scenes/brake.json");
    let all_ports = vec![("inlets", 4.0), ("outlets", 4.0), ("load_cell.wrap", 1.5)];
    let slipping = vec![
        ("includeTraction", 1.0),
        ("traction.wrap", 1.5),
        ("nip.mu", 0.4),
        ("air.roughness", 1.5e-5), // the film (about 28 um here) between sigma and 3 sigma
        ("v_start", 12.0),
        ("web_a.F", 100.0),
        ("web_b.F", 108.0),
    ];
    // A force loop [R10] without a lag (its command reaches tau within the step), and one with a
    // lag and a limit it presses into [R11].
    let force_loop = vec![("loop.kind", 1.0), ("loop.kp", 0.2), ("loop.ki", 2.0), ("loop.set", 400.0), ("loop.measured", 380.0), ("v_start", 5.0)];
    let lagged_loop = vec![
        ("loop.kind", 1.0),
        ("loop.kp", 0.2),
        ("loop.ki", 2.0),
        ("loop.sign", -1.0),
        ("loop.set", 400.0),
        ("loop.measured", 380.0),
        ("motor.limit", 4.0),
        ("motor.lag", 0.02),
        ("v_start", 5.0),
    ];
    let dancer_loop = vec![
        ("loop.kind", 3.0),
        ("loop.kp", 20.0),
        ("loop.ki", 100.0),
        ("loop.speed", 5.0),
        ("dancer.kp", 2.0),
        ("dancer.ki", 3.0),
        ("dancer.set", 0.3),
        ("dancer.y", 0.25),
        ("v_start", 5.0),
    ];
    let lagged_dancer_loop = [dancer_loop.clone(), vec![("motor.lag", 0.02)]].concat();
    Hints {
        points: vec![
            Point { values: dancer_loop, texts: vec![] },
            Point { values: lagged_dancer_loop, texts: vec![] },
            Point { values: force_loop, texts: vec![] },
            // A powder brake near rest, where its torque bends through 0 [R12].
            Point { values: vec![("v_start", 0.004), ("R", 0.2)], texts: vec![("profile", brake.into())] },
            Point { values: lagged_loop, texts: vec![] },
            Point { values: vec![], texts: vec![("profile", speed_drive.into())] },
            Point { values: all_ports, texts: vec![("profile", speed_drive.into())] },
            Point { values: vec![("roll", 2.0), ("wound.thickness", 1e-3), ("wound.density", 1000.0), ("inlets", 4.0)], texts: vec![("profile", speed_drive.into())] },
            Point { values: slipping.clone(), texts: vec![("profile", nip.into())] },
            // The same web running back, the nip at the exit: the air film forms at web_b [R8].
            Point { values: [slipping, vec![("v_start", -12.0), ("nip.side", 1.0)]].concat(), texts: vec![("profile", nip.into())] },
            // Rolls with runout [R15] that wind: the web's speed at the roll moves with the angle.
            Point { values: vec![("roll", 2.0), ("runout", 1.0), ("runout.e", 0.03), ("runout.L", 0.1), ("runout.phase", 0.5), ("wound.thickness", 1e-2), ("wound.density", 1000.0), ("inlets", 4.0), ("web_a.F", 100.0)], texts: vec![] },
            Point { values: vec![("roll", 1.0), ("runout", 1.0), ("runout.e", 0.03), ("runout.L", 0.1), ("runout.phase", -0.5), ("wound.thickness", 1e-2), ("wound.density", 1000.0), ("inlets", 4.0), ("web_b.F", 100.0)], texts: vec![] },
            // An out-of-round roll [R15] (oval and five-lobed besides its runout) that winds.
            Point {
                values: vec![("roll", 2.0), ("runout", 1.0), ("runout.e", 0.01), ("runout.L", 0.1), ("runout.phase", 0.5), ("runout.h1.a", 2e-3), ("runout.h2.k", 5.0), ("runout.h2.a", 1e-3), ("runout.h2.phase", 0.4), ("wound.thickness", 1e-2), ("wound.density", 1000.0), ("inlets", 4.0), ("web_a.F", 100.0)],
                texts: vec![],
            },
            // A lay-on roller [R18] pressed on a winding roll with runout (its nip reads r' through the strains, and the
            // angle), and on a round one.
            Point {
                values: vec![("roll", 2.0), ("layon", 1.0), ("layon.angle", 0.3), ("layon.F", 300.0), ("runout", 1.0), ("runout.e", 1e-4), ("runout.L", 0.1), ("runout.phase", 0.5), ("wound.thickness", 1e-2), ("wound.density", 1000.0), ("inlets", 4.0), ("web_a.F", 100.0), ("v_start", 5.0)],
                texts: vec![],
            },
            Point { values: vec![("roll", 2.0), ("layon", 1.0), ("wound.thickness", 1e-3), ("wound.density", 1000.0), ("web_a.F", 100.0), ("v_start", 5.0)], texts: vec![] },
            // An ideal speed drive on its input loop.speed (speed.input), the web pulling on both sides.
            Point { values: vec![("speed.input", 1.0), ("loop.speed", 6.0), ("web_a.F", 100.0), ("web_b.F", 120.0)], texts: vec![] },
        ],
        texts: vec![("profile", speed_drive.into())],
        refusals: vec!["a nip table needs includeTraction", "a web slips only on a roller", "a loop on a roller where the web may slip", "a loop drives by torque", "a brake acts on a roller whose speed is free", "a brake table with includeTraction", "the surface speed is loop.speed", "an ideal speed drive has no loop", "a sampled loop's period is 0 (continuous) or at least", "a sampled loop's delay is at most its period", "runout [R15] is a roll's", "a stepwise radius [R17] runs in Model Exchange", "runout with a stepwise radius [R17] is not modelled", "the span's fixed end must lie beyond the roll", "a lay-on roller [R18] presses on a winder", "a layon table needs layon = true", "a lay-on roller on a stepwise radius", "the roll's surface must stay convex", "a lay-on roller is modelled on runout's offset circle only"],
    }
}

fmi_testkit::conformance_tests!(roller::Roller, hints = hints);
