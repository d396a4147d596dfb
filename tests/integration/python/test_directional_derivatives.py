"""Directional derivatives (fmi2GetDirectionalDerivative) of the span against
central finite differences of the same FMU, through FMPy.

Every known is perturbed on its own: an input by fmi2SetReal, the state (Model
Exchange) by fmi2SetContinuousStates. A central difference with step h has a
truncation error ~ h^2/6 * |y'''| and a rounding error ~ eps_mach * |y| / h.
The steps are 1e-6 of each known's scale (|value|, at least its nominal), on
which the outputs are smooth (rational in the state and the speeds; the
stress-strain curve is a cubic between nodes 5e-3 apart in strain, and no
stencil crosses a node or the slack kink): truncation ~ 1e-12 relative. The
rounding bound is computed per entry from the output's magnitude. An entry
passes when |analytic - FD| <= RTOL * |FD| + the rounding bound; RTOL = 1e-6
is far above both errors and far below what a missing term costs (the
smallest terms of the equations are O(strain) ~ 1e-3 of the leading one).
Every comparison also checks that the negated Jacobian would fail it.
"""

import itertools
from pathlib import Path

import pytest
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Model, FMU2Slave, fmi2Real
from webline.fmus import effects as effects_of

RTOL = 1e-6
STEP = 1e-6
EPS = 2.2e-16
# Rounding of an output relative to its size: the strain L/x - 1 loses
# log10(1/strain) digits, so its absolute error is ~ eps_mach * (1 + strain); a
# margin of 1e3 over eps_mach covers that and the few operations after it.
ROUNDING = 1e3 * EPS

# The span's effects as its model description names them: every combination is checked.
EFFECTS = effects_of(Path(__file__).resolve().parents[3] / "modelDescription.xml")
COMBINATIONS = [dict(zip(EFFECTS, bits)) for bits in itertools.product([False, True], repeat=len(EFFECTS))]
INPUTS = ("web_a.v", "web_a.eps", "web_b.v", "frame_a.x", "frame_a.y", "frame_b.x", "frame_b.y")
NOMINAL = {"web_a.v": 1.0, "web_a.eps": 1e-3, "web_b.v": 1.0, "unstretchedLength": 1.0}
UNKNOWNS = ("v", "T", "web_a.F", "web_b.F", "web_b.eps", "summary_Tension", "summary_Length",
            "summary_Strain", "summary_Stress", "m_web", "der(unstretchedLength)")
# A taut span away from equilibrium (dx/dt != 0, so the damping term's every
# part counts); the rollers 1 m apart on a slant, so that every position matters.
POINT = {"web_a.v": 5.0, "web_a.eps": 1e-3, "web_b.v": 5.02,
         "frame_a.x": 0.1, "frame_a.y": 0.2, "frame_b.x": 0.9, "frame_b.y": 0.8}
PARAMS = {"startAtEquilibrium": False, "eps_start": 2e-3, "wp2.d_r": 0.01, "toUnitF": 3, "toUnitV": 2}


def label(effects):
    on = [k for k, v in effects.items() if v]
    return "+".join(on) or "none"


def refused_in_me(effects):
    """The span refuses these in Model Exchange: includeMass needs dv_b/dt and
    damping with variableLength needs dL/dt, input rates ME does not give."""
    return effects.get("includeMass") or (effects.get("includeDamping") and effects.get("variableLength"))


@pytest.fixture(scope="module")
def md(fmu_path):
    return read_model_description(str(fmu_path))


@pytest.fixture(scope="module")
def vr(md):
    return {v.name: v.valueReference for v in md.modelVariables}


def instantiate(unzipdir, md, kind, log=None):
    cls = FMU2Model if kind == "ModelExchange" else FMU2Slave
    fmu = cls(guid=md.guid, unzipDirectory=unzipdir, modelIdentifier=md.coSimulation.modelIdentifier,
              instanceName="jacobian")
    fmu.instantiate(loggingOn=log is not None, callbacks=None)
    return fmu


def set_values(fmu, vr, values):
    for name, value in values.items():
        if isinstance(value, bool):
            fmu.setBoolean([vr[name]], [value])
        elif isinstance(value, str):
            fmu.setString([vr[name]], [value])
        elif isinstance(value, int):
            fmu.setInteger([vr[name]], [value])
        else:
            fmu.setReal([vr[name]], [value])


def start(fmu, vr, values, me):
    fmu.setupExperiment(startTime=0.0)
    set_values(fmu, vr, values)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    if me:
        fmu.newDiscreteStates()
        fmu.enterContinuousTimeMode()


class Perturb:
    """Sets one known to a value and back: an input, or the state (ME)."""

    def __init__(self, fmu, vr, name):
        self.fmu, self.name = fmu, name
        self.state = name == "unstretchedLength"
        self.vr = vr[name]
        self.value = fmu.getReal([self.vr])[0]

    def set(self, value):
        if self.state:
            self.fmu.setContinuousStates((fmi2Real * 1)(value), 1)
        else:
            self.fmu.setReal([self.vr], [value])


def jacobians(fmu, vr, unknowns, knowns):
    """The analytic and the finite-difference Jacobian, and each entry's rounding bound."""
    u_refs = [vr[n] for n in unknowns]
    analytic, fd, noise = {}, {}, {}
    # dx/dt is a difference of flows ~ the speeds: it rounds on their scale, not its own.
    speeds = fmu.getReal([vr["web_a.v"], vr["web_b.v"]])
    scale = {"der(unstretchedLength)": max(abs(s) for s in speeds)}
    for k in knowns:
        column = fmu.getDirectionalDerivative(u_refs, [vr[k]], [1.0])
        p = Perturb(fmu, vr, k)
        h = STEP * max(abs(p.value), NOMINAL.get(k, 1.0))
        p.set(p.value + h)
        up = fmu.getReal(u_refs)
        p.set(p.value - h)
        down = fmu.getReal(u_refs)
        p.set(p.value)
        for i, n in enumerate(unknowns):
            analytic[n, k] = column[i]
            fd[n, k] = (up[i] - down[i]) / (2 * h)
            noise[n, k] = ROUNDING * max(abs(up[i]), abs(down[i]), scale.get(n, 0.0)) / h
    return analytic, fd, noise


def compare(what, analytic, fd, noise):
    """Max relative error over the entries; fails on any entry out of tolerance."""
    worst, flipped_caught, nonzero = 0.0, 0, 0
    for key, a in analytic.items():
        err = abs(a - fd[key])
        allowed = RTOL * abs(fd[key]) + noise[key]
        assert err <= allowed, f"{what}: d({key[0]})/d({key[1]}) = {a!r}, finite difference {fd[key]!r}"
        if abs(fd[key]) > noise[key] / RTOL:
            nonzero += 1
            worst = max(worst, err / abs(fd[key]))
            flipped_caught += abs(-a - fd[key]) > RTOL * abs(fd[key]) + noise[key]
    assert nonzero > 0, f"{what}: every entry is zero, nothing was tested"
    assert flipped_caught == nonzero, f"{what}: a wrong sign would pass"
    return worst


ME_RESULTS, CS_RESULTS = {}, {}


@pytest.mark.parametrize("effects", COMBINATIONS, ids=label)
def test_model_exchange_matches_finite_differences(unzipdir, md, vr, effects):
    if refused_in_me(effects):
        pytest.skip("refused in Model Exchange (needs input rates ME does not give)")
    fmu = instantiate(unzipdir, md, "ModelExchange")
    try:
        start(fmu, vr, {**PARAMS, **effects, **POINT}, me=True)
        knowns = INPUTS + ("unstretchedLength",)
        a, f, n = jacobians(fmu, vr, UNKNOWNS, knowns)
    finally:
        fmu.terminate()
        fmu.freeInstance()
    worst = compare(f"ME {label(effects)}", a, f, n)
    ME_RESULTS[label(effects)] = worst
    print(f"ME {label(effects)}: max relative error {worst:.1e}")


def cs_after_steps(fmu, vr, given_rates):
    """Three steps with moving inputs (backward-difference rates), then the
    point; optionally input derivatives given for the next step."""
    t, h = 0.0, 1e-3
    for i in range(3):
        fmu.setReal([vr["web_b.v"], vr["frame_b.x"]], [POINT["web_b.v"] - 0.01 * (3 - i), POINT["frame_b.x"] - 1e-4 * (3 - i)])
        fmu.doStep(t, h)
        t += h
    fmu.setReal([vr[k] for k in POINT], list(POINT.values()))
    if given_rates:
        names = ["web_b.v", "frame_a.x", "frame_b.y", "frame_b.x"]
        fmu.setRealInputDerivatives([vr[k] for k in names], [1, 1, 1, 1], [3.0, 0.02, -0.05, 0.1])


@pytest.mark.parametrize("given_rates", [False, True], ids=["estimated-rates", "given-rates"])
@pytest.mark.parametrize("effects", COMBINATIONS, ids=label)
def test_co_simulation_matches_finite_differences(unzipdir, md, vr, effects, given_rates):
    """After steps: d(outputs)/d(inputs) at the current state, the input rates
    the outputs read (the given derivatives, or the estimate from the last
    step) held; with given rates dL/dt still moves with the roller positions."""
    fmu = instantiate(unzipdir, md, "CoSimulation")
    try:
        start(fmu, vr, {**PARAMS, **effects, **POINT}, me=False)
        cs_after_steps(fmu, vr, given_rates)
        a, f, n = jacobians(fmu, vr, UNKNOWNS, INPUTS)
    finally:
        fmu.terminate()
        fmu.freeInstance()
    what = f"CS {label(effects)} {'given' if given_rates else 'estimated'} rates"
    worst = compare(what, a, f, n)
    CS_RESULTS[what] = worst
    print(f"{what}: max relative error {worst:.1e}")


@pytest.mark.parametrize("kind", ["ModelExchange", "CoSimulation"])
@pytest.mark.parametrize("damping", [False, True], ids=["elastic", "damped"])
def test_nonlinear_record_matches_finite_differences(unzipdir, md, vr, kind, damping):
    """The PCHIP curve's tangent modulus (and its slope, with damping), at a
    strain of 1.5e-2 between the nodes 1e-2 and 2e-2."""
    me = kind == "ModelExchange"
    fmu = instantiate(unzipdir, md, kind)
    values = {**PARAMS, **POINT, "wp2.record": "nonwoven-PP-spunbond", "eps_start": 1.5e-2,
              "includeDamping": damping, "preventNegativeTension": True}
    try:
        start(fmu, vr, values, me=me)
        if not me:
            cs_after_steps(fmu, vr, False)
        knowns = INPUTS + (("unstretchedLength",) if me else ())
        a, f, n = jacobians(fmu, vr, UNKNOWNS, knowns)
    finally:
        fmu.terminate()
        fmu.freeInstance()
    worst = compare(f"{kind} nonwoven", a, f, n)
    print(f"{kind} nonwoven-PP-spunbond damping={damping}: max relative error {worst:.1e}")


@pytest.mark.parametrize("kind", ["ModelExchange", "CoSimulation"])
def test_slack_web_has_zero_tension_derivatives(unzipdir, md, vr, kind):
    """preventNegativeTension on a slack web: the tension is clamped at 0, so
    its derivatives are 0, while the strain's are not."""
    me = kind == "ModelExchange"
    fmu = instantiate(unzipdir, md, kind)
    try:
        start(fmu, vr, {**PARAMS, **POINT, "eps_start": -1e-3, "preventNegativeTension": True,
                        "includeDamping": True}, me=me)
        knowns = INPUTS + (("unstretchedLength",) if me else ())
        a, f, n = jacobians(fmu, vr, UNKNOWNS, knowns)
    finally:
        fmu.terminate()
        fmu.freeInstance()
    for name in ("T", "web_a.F", "web_b.F", "summary_Tension", "summary_Stress"):
        assert all(a[name, k] == 0.0 for k in knowns), name
    compare(f"{kind} slack", a, f, n)


@pytest.mark.parametrize("effects", COMBINATIONS, ids=label)
def test_initialization_mode_matches_finite_differences(unzipdir, md, vr, effects):
    """In initialization mode the initial unknowns (the state among them)
    depend on the inputs through the start at equilibrium; input derivatives
    given before initialization make the state's own terms (x dv_b/dt, the
    moving rollers' dL/dt / x) count too."""
    fmu = instantiate(unzipdir, md, "CoSimulation")
    try:
        fmu.setupExperiment(startTime=0.0)
        set_values(fmu, vr, {**PARAMS, **effects, **POINT, "startAtEquilibrium": True})
        names = ["web_b.v", "frame_a.x", "frame_b.y"]
        fmu.setRealInputDerivatives([vr[k] for k in names], [1, 1, 1], [3.0, 0.02, -0.05])
        fmu.enterInitializationMode()
        unknowns = UNKNOWNS + ("unstretchedLength",)
        a, f, n = jacobians(fmu, vr, unknowns, INPUTS)
        fmu.exitInitializationMode()
    finally:
        fmu.terminate()
        fmu.freeInstance()
    worst = compare(f"init {label(effects)}", a, f, n)
    print(f"initialization {label(effects)}: max relative error {worst:.1e}")


class Log:
    def __init__(self):
        self.messages = []

    def __call__(self, component, instance, status, category, message):
        self.messages.append(message.decode())


@pytest.mark.parametrize("kind, unknown, known, says", [
    ("CoSimulation", "T", "unstretchedLength", "unstretchedLength (value reference 31) is not a known in Co-Simulation"),
    ("CoSimulation", "T", "L", "L (value reference 1) is not a known"),
    ("ModelExchange", "T", "wp2.E", "wp2.E (value reference 7) is not a known"),
    ("ModelExchange", "unstretchedLength", "web_a.v", "unstretchedLength (value reference 31) is not an unknown"),
    ("CoSimulation", "L", "web_a.v", "L (value reference 1) is not an unknown"),
    ("CoSimulation", 9999, "web_a.v", "value reference 9999 (no variable) is not an unknown"),
])
def test_bad_value_references_are_refused_with_a_message(unzipdir, md, vr, kind, unknown, known, says):
    from fmpy.fmi2 import fmi2CallbackFunctions, fmi2CallbackLoggerTYPE, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE
    from fmpy import calloc, free

    log = Log()
    fmu = FMU2Model if kind == "ModelExchange" else FMU2Slave
    fmu = fmu(guid=md.guid, unzipDirectory=unzipdir, modelIdentifier=md.coSimulation.modelIdentifier, instanceName="bad")
    callbacks = fmi2CallbackFunctions()
    callbacks.logger = fmi2CallbackLoggerTYPE(lambda c, i, s, cat, msg: log(c, i, s, cat, msg))
    callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
    callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
    fmu.instantiate(loggingOn=True, callbacks=callbacks)
    try:
        start(fmu, vr, {}, me=kind == "ModelExchange")
        ref = lambda x: x if isinstance(x, int) else vr[x]
        with pytest.raises(FMICallException):
            fmu.getDirectionalDerivative([ref(unknown)], [ref(known)], [1.0])
        assert any(says in m for m in log.messages), log.messages
        # The instance is in the error state; fmi2Reset brings it back.
        fmu.reset()
        start(fmu, vr, {}, me=kind == "ModelExchange")
        assert len(fmu.getDirectionalDerivative([vr["T"]], [vr["web_b.v"]], [1.0])) == 1
    finally:
        fmu.freeInstance()


# ---------------------------------------------------------------- the Roller
# The same check on the Roller: states omega, r, y, y', v_web, loop.I, motor.torque, dancer.I, grip,
# brake.grip, angle (ME), inputs web_a.F, web_b.F, web_a.eps, tau_m, F_load and those of the extra inlets and outlets
# (a merge and a split: cases with ports; elsewhere unused, their derivatives 0).
# The outputs are polynomials in the states and inputs (degree <= 4 in r), or
# the merged strain, a smooth ratio, so the same steps and tolerances apply.

ROLLER_INPUTS = ("web_a.F", "web_b.F", "web_a.eps", "tau_m", "F_load", "web_a2.F", "web_a2.eps", "web_a3.F", "web_a3.eps",
                 "web_a4.F", "web_a4.eps", "web_b2.F", "web_b3.F", "web_b4.F")
ROLLER_STATES = ("omega", "r", "y", "y_dot", "v_web", "loop.I", "motor.torque", "dancer.I", "grip", "brake.grip", "angle",
                 "layon.x", "layon.v", "layon.omega")
ROLLER_UNKNOWNS = ("web_a.v", "web_b.v", "web_b.eps", "omega", "r", "y", "y_dot", "tau", "web_a.x", "web_a.y",
                   "web_b.x", "web_b.y", "der(omega)", "der(r)", "der(y)", "der(y_dot)", "web_a2.v", "web_a4.v",
                   "web_b2.v", "web_b2.eps", "web_b4.eps", "v_web", "der(v_web)")
ROLLER_POINT = {"web_a.F": 180.0, "web_b.F": 230.0, "web_a.eps": 1e-3, "tau_m": 1.5, "F_load": 400.0,
                "web_a2.F": 120.0, "web_a2.eps": 4e-3, "web_a3.F": 60.0, "web_a3.eps": -5e-4, "web_a4.F": 90.0,
                "web_a4.eps": 2e-2, "web_b2.F": 70.0, "web_b3.F": 110.0, "web_b4.F": 40.0}
ROLLER_PARAMS = {"J": 0.3, "R": 0.15, "b": 0.02, "v_start": 5.0, "wound.thickness": 1e-4, "wound.density": 900.0,
                 "wound.width": 1.2, "carriage.m": 3.0, "carriage.d": 40.0, "carriage.k": 2000.0, "carriage.y_start": 0.5,
                 "web_a.m": 0.12, "web_a2.m": 0.05, "web_a3.m": 0.3, "web_a4.m": 0.02}
# Tables linear over the first 10 s: the test points sit inside one piece.
DRIVES = {
    "idler": {},
    "torque": {"torque": [[0, 1.0], [10, 3.0]]},
    "tension": {"tension": [[0, 200.0], [10, 260.0]]},
    "speed": {"speed": [[0, 5.0], [10, 6.0]]},
}
ROLLER_CASES = [
    (drive, roll, carriage, (1, 1))
    for drive in DRIVES
    for roll in (0, 1, 2)
    if not (drive == "tension" and roll == 0)  # a tension drive is an unwinder's or a winder's
    for carriage in (False, True)
] + [
    # (inlets, outlets): a nip on a dancer, a slitter's unwinder, a winder of four webs.
    ("speed", 0, True, (3, 2)),
    ("tension", 1, False, (2, 4)),
    ("idler", 2, True, (4, 4)),
    ("torque", 0, False, (4, 1)),
]


def roller_label(case):
    drive, roll, carriage, (inlets, outlets) = case
    ports = f"-{inlets}in{outlets}out" if (inlets, outlets) != (1, 1) else ""
    return f"{drive}-{['roller', 'unwinder', 'winder'][roll]}{'-dancer' if carriage else ''}{ports}"


@pytest.mark.parametrize("kind", ["ModelExchange", "CoSimulation"])
@pytest.mark.parametrize("roll", [1, 2])
@pytest.mark.parametrize("lobed", [False, True], ids=["round", "lobed"])
def test_roller_with_runout_matches_finite_differences(roller, tmp_path, kind, roll, lobed):
    """A roll with runout [R15], winding, its angle 1.3 rad (ME): the arm p, the span's end and the
    web's speed at the moving tangent point move with the angle, omega and r; `lobed`: an out-of-round
    roll besides (an oval and a three-lobed harmonic), its tangent found by Newton's method."""
    me = kind == "ModelExchange"
    params = {k: v for k, v in ROLLER_PARAMS.items() if not k.startswith("carriage.")}
    harmonics = {"runout.h1.a": 3e-3, "runout.h1.phase": 0.2, "runout.h2.a": 1e-3, "runout.h2.phase": -0.6} if lobed else {}
    values = {**params, **ROLLER_POINT, "roll": roll, "runout": True, "runout.e": 0.01, "runout.phase": 0.4, "runout.L": 0.6,
              **harmonics}
    (a, f, n), _ = roller_case(roller, tmp_path, kind, {"torque": [[0, 1.0], [10, 3.0]]}, values,
                               (33.0, 0.16, 0.0, 0.0, 33.0 * 0.16, 0.0, 0.0, 0.0, 0.0, 0.0, 1.3), *every_pair(roller, me)[::-1])
    if me:
        assert a["web_b.y" if roll == 1 else "web_a.y", "angle"] != 0.0, "the span's end must move with the angle"
        assert a["der(omega)", "angle"] != 0.0, "the web's arm must move with the angle"
    what = f"Roller {kind} runout roll {roll}{' lobed' if lobed else ''}"
    print(f"{what}: max relative error {compare(what, a, f, n):.1e}")


@pytest.mark.parametrize("kind", ["ModelExchange", "CoSimulation"])
def test_roller_with_a_layon_roller_matches_finite_differences(roller, tmp_path, kind):
    """A lay-on roller [R18] pressed on a winding roll with 0.1 mm of runout, its carriage moving and its
    roller slipping (ME): the nip's force moves with the carriage, the roll's angle, omega, r and, through
    r's rate, the arriving strains; its traction reaches the roll's der(omega)."""
    me = kind == "ModelExchange"
    params = {k: v for k, v in ROLLER_PARAMS.items() if not k.startswith("carriage.")}
    values = {**params, **ROLLER_POINT, "roll": 2, "runout": True, "runout.e": 1e-4, "runout.phase": 0.4, "runout.L": 0.6,
              "layon": True, "layon.F": 300.0, "layon.angle": 0.7}
    # Pressed by 3e-4 m (3000 N at k = 1e7), moving out at 2 mm/s, slipping by 1 mm/s (on tanh's slope). The
    # traction curves over v_slip = 1 mm/s: along the states a step of 1e-8 keeps the difference's truncation at 1e-9, as the web's.
    states = (33.0, 0.16, 0.0, 0.0, 33.0 * 0.16, 0.0, 0.0, 0.0, 0.0, 0.0, 1.3, 0.26 - 3e-4, 2e-3, (33.0 * 0.16 - 1e-3) / 0.1)
    (a, f, n), (force,) = roller_case(roller, tmp_path, kind, {"torque": [[0, 1.0], [10, 3.0]]}, values, states,
                                      *every_pair(roller, me)[::-1], step=1e-8 if me else STEP, read=("layon.N",))
    assert force > 0.0, "the nip must be pressed"
    if me:
        assert a["der(layon.v)", "layon.x"] < 0.0, "pressed further, the nip must push the carriage back harder"
        assert a["der(omega)", "layon.omega"] != 0.0, "the lay-on roller's traction must reach the roll"
        assert a["layon.N", "web_a.eps"] != 0.0, "the nip's damper must read the roll's growth"
    what = f"Roller {kind} lay-on"
    print(f"{what}: N {force:.1f} N, max relative error {compare(what, a, f, n):.1e}")


@pytest.fixture(scope="module")
def roller(fmus):
    from fmpy import extract

    path = fmus / "Roller.fmu"
    md = read_model_description(str(path))
    return md, extract(str(path)), {v.name: v.valueReference for v in md.modelVariables}


def every_pair(roller, me):
    """Every Roller output and state derivative (unknowns), every Real input and in Model Exchange
    every state (knowns), from its model description: a variable added later is covered too."""
    md = roller[0]
    unknowns = tuple(u.variable.name for u in md.outputs) + tuple(d.variable.name for d in md.derivatives)
    inputs = tuple(v.name for v in md.modelVariables if v.causality == "input" and v.type == "Real")
    return unknowns, inputs + (ROLLER_STATES if me else ())


def roller_jacobians(fmu, vr, unknowns, knowns, step=STEP):
    u_refs = [vr[n] for n in unknowns]
    states = ROLLER_STATES
    analytic, fd, noise = {}, {}, {}
    for k in knowns:
        column = fmu.getDirectionalDerivative(u_refs, [vr[k]], [1.0])
        x = fmu.getReal([vr[s] for s in states])
        value = x[states.index(k)] if k in states else fmu.getReal([vr[k]])[0]
        h = step * max(abs(value), 1e-3 if k.endswith(".eps") or k == "r" else 1.0)

        def put(v):
            if k in states:
                x2 = list(x)
                x2[states.index(k)] = v
                fmu.setContinuousStates((fmi2Real * len(x2))(*x2), len(x2))
            else:
                fmu.setReal([vr[k]], [v])

        put(value + h)
        up = fmu.getReal(u_refs)
        put(value - h)
        down = fmu.getReal(u_refs)
        put(value)
        for i, n in enumerate(unknowns):
            analytic[n, k] = column[i]
            fd[n, k] = (up[i] - down[i]) / (2 * h)
            noise[n, k] = ROUNDING * max(abs(up[i]), abs(down[i]), 1.0) / h
    return analytic, fd, noise


def roller_case(roller, tmp_path, kind, profile, values, me_states, knowns, unknowns, step=STEP, cs_time=0.25, read=()):
    """The Roller with `profile` and `values`, away from its start (Model Exchange: its states set to
    `me_states` at 0.25 s, where the states join `knowns`; Co-Simulation: after a step to `cs_time`):
    (analytic, differences, noise) of `unknowns` along `knowns`, and the values `read` then."""
    import json

    md, unzipdir, vr = roller
    path = tmp_path / "profile.json"
    path.write_text(json.dumps(profile))
    me = kind == "ModelExchange"
    fmu = instantiate(unzipdir, md, kind)
    try:
        start(fmu, vr, {**values, "profile": str(path)}, me=me)
        if me:
            fmu.setTime(0.25)
            # The states a case leaves out (added after it was written) at 0: they do not move there.
            me_states = tuple(me_states) + (0.0,) * (len(ROLLER_STATES) - len(me_states))
            fmu.setContinuousStates((fmi2Real * len(me_states))(*me_states), len(me_states))
        else:
            fmu.doStep(0.0, cs_time)
        found = roller_jacobians(fmu, vr, unknowns, knowns, step)
        return found, fmu.getReal([vr[k] for k in read])
    finally:
        fmu.terminate()
        fmu.freeInstance()


@pytest.mark.parametrize("kind", ["ModelExchange", "CoSimulation"])
@pytest.mark.parametrize("case", ROLLER_CASES, ids=roller_label)
def test_roller_matches_finite_differences(roller, tmp_path, kind, case):
    drive, roll, carriage, (inlets, outlets) = case
    profile = dict(DRIVES[drive])
    if carriage:
        profile["load"] = [[0, 50.0], [10, 80.0]]
    me = kind == "ModelExchange"
    values = {**ROLLER_PARAMS, **ROLLER_POINT, "roll": roll, "carriage": carriage, "inlets": inlets, "outlets": outlets}
    # Away from the start values: the carriage moving, the roll grown.
    states = (33.0, 0.16, 0.52, -0.03, 33.0 * 0.16 + 2e-3, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    # Without traction the fifth state is the surface's speed r*omega, not a known of its own: v_web
    # reads r*omega back (its derivatives by r and omega are omega and r, by itself 0).
    unknowns, knowns = every_pair(roller, me)
    assert set(ROLLER_UNKNOWNS) <= set(unknowns) and set(ROLLER_INPUTS) <= set(knowns)
    (a, f, n), _ = roller_case(roller, tmp_path, kind, profile, values, states, knowns, unknowns)
    if me and drive != "speed":
        assert a["v_web", "r"] == pytest.approx(33.0) and a["v_web", "omega"] == pytest.approx(0.16)
    what = f"Roller {kind} {roller_label(case)}"
    worst = compare(what, a, f, n)
    print(f"{what}: max relative error {worst:.1e}")


# With traction [R6]-[R8] the web's speed is a state of its own, moved by the capstan friction
# and a nip; the slip sits where tanh is curved (2 v_slip) and the air film's friction rule
# is on its sloping part (h between roughness and three times it), so every gradient is exercised.
TRACTION_CASES = {"wrap": {"traction.wrap": 1.2}, "wrap-nip-air": {"traction.wrap": 0.8, "nip.mu": 0.4,
                                                                   "air.roughness": 1e-5}}


@pytest.mark.parametrize("kind", ["ModelExchange", "CoSimulation"])
@pytest.mark.parametrize("label", TRACTION_CASES)
def test_roller_with_traction_matches_finite_differences(roller, tmp_path, kind, label):
    profile = {"torque": [[0, 1.0], [10, 3.0]]}
    if "nip.mu" in TRACTION_CASES[label]:
        profile["nip"] = [[0, 300.0], [10, 360.0]]
    me = kind == "ModelExchange"
    params = {k: v for k, v in ROLLER_PARAMS.items() if not k.startswith(("wound.", "carriage."))}
    values = {**params, **ROLLER_POINT, "includeTraction": True, "traction.mu": 0.3, "traction.v_slip": 1e-3,
              "traction.width": 0.5, "traction.slip_start": 2e-3, **TRACTION_CASES[label]}
    unknowns, knowns = every_pair(roller, me)
    # The grip curves over v_slip = 1 mm/s: a step of 1e-6 of a speed of 5 m/s would leave a
    # truncation error of (5e-6/1e-3)^2 ~ 2.5e-5; 1e-8 leaves 2.5e-9, rounding stays in the noise term.
    (a, f, n), (slip, mu_eff, h_air) = roller_case(
        roller, tmp_path, kind, profile, values, (33.0, 0.15, 0.0, 0.0, 33.0 * 0.15 + 2e-3, 0.0, 0.0, 0.0, 0.9, 0.0, 0.0),
        knowns, unknowns, step=1e-8, read=("slip", "mu_eff", "h_air"))
    what = f"Roller {kind} traction {label}"
    worst = compare(what, a, f, n)
    print(f"{what}: slip {slip:.2e} m/s, mu_eff {mu_eff:.4f}, h_air {h_air:.2e} m, max relative error {worst:.1e}")
    if "air.roughness" in TRACTION_CASES[label]:
        assert 0 < mu_eff < 0.3, "the air film must be on its sloping part"
    if me:  # sliding forward with its grip near the kinetic limit: more grip pulls the web back, and the grip grows to it
        assert a["der(v_web)", "grip"] < 0, "the grip's friction must pull the web's speed toward the surface's"
        assert a["der(grip)", "grip"] < 0 < a["der(grip)", "v_web"], "the grip must relax to its sliding value"


# A drive's loop [R10]-[R11]: its integrator and its lagging motor are states, what it measures an
# input. On a roll being wound (J and the feed-forward move with r), the command u about -5.5 N.m is
# inside the limit's exponential bend (|u| > 0.95 * 5.3 N.m), so the limit's slope and the
# back-calculation count; a speed loop measures the surface's own speed; a dancer loop [R13] trims its
# reference by a PI on the input dancer.y, its integrator dancer.I an eighth state.
LOOP_CASES = {
    "force-ff-limit-lag": {"loop.kind": 1, "loop.sign": -1.0, "loop.set": 200.0, "loop.measured": 190.0,
                           "loop.feedforward": True, "motor.limit": 5.3, "motor.lag": 0.02},
    "force-no-lag": {"loop.kind": 1, "loop.sign": 1.0, "loop.set": 200.0, "loop.measured": 190.0, "loop.feedforward": True},
    "speed-ff": {"loop.kind": 2, "loop.feedforward": True, "motor.limit": 50.0},
    "dancer-ff-lag": {"loop.kind": 3, "loop.sign": -1.0, "loop.feedforward": True, "motor.limit": 50.0, "motor.lag": 0.02,
                      "dancer.set": 0.3, "dancer.y": 0.28, "dancer.kp": 2.0, "dancer.ki": 3.0},
    "dancer-no-lag": {"loop.kind": 3, "loop.sign": 1.0, "dancer.set": 0.3, "dancer.y": 0.28, "dancer.kp": 2.0, "dancer.ki": 3.0},
}


@pytest.mark.parametrize("kind", ["ModelExchange", "CoSimulation"])
@pytest.mark.parametrize("label", LOOP_CASES)
def test_roller_with_a_loop_matches_finite_differences(roller, tmp_path, kind, label):
    me = kind == "ModelExchange"
    params = {k: v for k, v in ROLLER_PARAMS.items() if not k.startswith("carriage.")}
    values = {**params, **ROLLER_POINT, "roll": 1, "loop.kp": 0.2, "loop.ki": 2.0, **LOOP_CASES[label]}
    unknowns, knowns = every_pair(roller, me)
    (a, f, n), _ = roller_case(roller, tmp_path, kind, {"reference": [[0, 5.0], [10, 6.0]]}, values,
                               (33.0, 0.16, 0.0, 0.0, 33.0 * 0.16, -3.5, -4.0, 0.02, 0.0, 0.0, 0.0), knowns, unknowns)
    what = f"Roller {kind} loop {label}"
    worst = compare(what, a, f, n)
    print(f"{what}: max relative error {worst:.1e}")
    if me and label == "force-ff-limit-lag":
        slope = a["der(motor.torque)", "loop.I"] * 0.02
        assert 0.0 < slope < 0.9, f"the command must sit in the limit's bend (its slope {slope})"


@pytest.mark.parametrize("kind", ["ModelExchange", "CoSimulation"])
def test_roller_with_a_brake_matches_finite_differences(roller, tmp_path, kind):
    """A powder brake [R12] near rest (v = 4 mm/s, where the grip's damping fades over v_slip) on a roll
    being wound, its grip at half its rating."""
    me = kind == "ModelExchange"
    params = {k: v for k, v in ROLLER_PARAMS.items() if not k.startswith("carriage.")}
    values = {**params, **ROLLER_POINT, "web_b.F": 180.0, "roll": 1, "v_start": 0.004}
    (a, f, n), _ = roller_case(roller, tmp_path, kind, {"brake": [[0, 2.0], [10, 3.0]]}, values,
                               (0.025, 0.16, 0.0, 0.0, 0.004, 0.0, 0.0, 0.0, 0.0, 0.5, 0.0), *every_pair(roller, me)[::-1], cs_time=0.01)
    what = f"Roller {kind} brake"
    print(f"{what}: max relative error {compare(what, a, f, n):.1e}")
