#!/usr/bin/env python3
"""What accuracy costs: every way to integrate ConvertingSpan, error against cost.

    .venv/bin/python bench/study.py [--rounds R] [--quick] [--no-fmpy]
                                    [--dahlquist LIB.so ...] [--publish]

One command: builds and packages the FMU (fmu/package.py), compiles the native
drivers (bench/study_driver.c, native_cost.c) with gcc against FMPy's
FMI 2.0 headers and Debian's SUNDIALS (libsundials-dev, installed with apt-get
when it is missing), runs the grid and writes into target/study/:

  results.json   every run: scene, method, communication step, error, cost
  study.md       the summary tables
  pareto.png     error against native cost per communication step, one line per method
  comm_step.png  error against communication step
  fmpy.png       error against whole-run wall time through FMPy

--publish copies study.md, pareto.png and comm_step.png to bench/results/
(the files docs/accuracy.md shows).

Scenes (inputs given as functions of time; the FMU sees them at its
communication points t_k = k*h):
  step     held-input step response, exact solution known (closed form, mpmath)
  short    a 5 mm span at 30 m/s (time constant 0.17 ms), held inputs, closed form
  ramp     speed ramp 5 -> 10 m/s with the draw growing, without and with input derivatives
  dancer   roller b oscillating (variableLength), without and with input derivatives
  mass     web mass on: S-curve speed ramp, error of web_b.F (includes the momentum terms)
For the scenes with moving inputs the reference is computed once by an
independent method: Dormand-Prince 8(5,3) (scipy DOP853) at its tightest
tolerance on the strain equation, inputs evaluated in extended precision; it
is checked against mpmath's Taylor-series ODE solver (30 digits) at a few
points, and the check is reported.

Methods: the FMU's solvers (auto, exact, rosenbrock and dopri5 at tolerances
1e-3 ... 1e-12, rk4 and euler at 1 ... 65536 sub-steps), every communication step
1e-1 ... 1e-5 s, and Model Exchange integrated by CVode (natively: the C driver
with Debian's SUNDIALS, rtol 1e-4 ... 1e-14; through FMPy's simulate_fmu, rtol
1e-4 ... 1e-10).

Measured: the largest relative error of the tension (web_b.F for the mass
scene) over all communication points, and the cost: native ns per
communication step (inputs set, step, outputs read, as an importer does;
the thread's CPU time, so that time while other processes have the core does
not count; interleaved rounds, median), and FMPy's whole-run wall time (median
of interleaved rounds; the FMU is unzipped and its model description read and
validated once, outside the timing). Timing is for people to read: the
numbers are not asserted, and other processes on the machine move them; the
medians of interleaved rounds keep ratios measured side by side meaningful.
"""

import argparse
import contextlib
import hashlib
import io
import json
import math
import os
import platform
import re
import shutil
import subprocess
import sys
import time
import xml.etree.ElementTree as ET
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
BENCH = ROOT / "bench"
OUT = ROOT / "target" / "study"
PUBLISH = BENCH / "results"

STEPS = [1e-1, 1e-2, 1e-3, 1e-4, 1e-5]
PARETO_STEP = 1e-3
TOLERANCES = [10.0 ** -k for k in range(3, 13)]
RK4_SUBSTEPS = [1, 2, 4, 8, 16, 32, 64, 128, 256]
EULER_SUBSTEPS = [1, 4, 16, 64, 256, 1024, 4096, 16384, 65536]
CVODE_NATIVE = [10.0 ** -k for k in range(4, 15)]
CVODE_FMPY = [10.0 ** -k for k in range(4, 11)]
FMPY_TOLERANCES = [1e-4, 1e-6, 1e-8, 1e-10]
# fixed-step runs beyond this many sub-steps in all are skipped (time budget): more at the Pareto step
MAX_SUBSTEPS_PARETO, MAX_SUBSTEPS_OTHER = 2e7, 2e6
SOLVERS = {"auto": 1, "exact": 2, "rosenbrock": 3, "dopri5": 4, "rk4": 5, "euler": 6}


# --------------------------------------------------------------------------
# Input signals: one definition for the C driver, the FMPy input table and the reference


class Signal:
    def breaks(self):
        return []


@dataclass
class Const(Signal):
    v: float

    def spec(self):
        return f"const {self.v!r}"

    def value(self, t, dtype=np.float64):
        return np.full(np.shape(t), dtype(self.v), dtype=dtype)

    def rate(self, t):
        return np.zeros(np.shape(t))

    def mp(self, t, seg):
        import mpmath
        return mpmath.mpf(self.v)


@dataclass
class Pwl(Signal):
    """Linear between the points, constant outside."""
    pts: list

    def spec(self):
        return "pwl " + " ".join(f"{t!r} {v!r}" for t, v in self.pts)

    def breaks(self):
        return [t for t, _ in self.pts if t > 0]

    def value(self, t, dtype=np.float64):
        t = np.asarray(t, dtype=dtype)
        out = np.full(t.shape, dtype(self.pts[0][1]), dtype=dtype)
        for (t0, v0), (t1, v1) in zip(self.pts[:-1], self.pts[1:]):
            t0, v0, t1, v1 = dtype(t0), dtype(v0), dtype(t1), dtype(v1)
            m = (t >= t0) & (t <= t1)
            out[m] = v0 + (t[m] - t0) / (t1 - t0) * (v1 - v0)
        out[t > dtype(self.pts[-1][0])] = dtype(self.pts[-1][1])
        return out

    def rate(self, t):
        t = np.asarray(t, dtype=float)
        out = np.zeros(t.shape)
        for (t0, v0), (t1, v1) in zip(self.pts[:-1], self.pts[1:]):
            out[(t >= t0) & (t < t1)] = (v1 - v0) / (t1 - t0)
        return out

    def mp(self, t, seg):
        """The analytic continuation of the piece containing `seg` (a time inside it)."""
        import mpmath
        pts = self.pts
        if seg <= pts[0][0]:
            return mpmath.mpf(pts[0][1])
        for (t0, v0), (t1, v1) in zip(pts[:-1], pts[1:]):
            if t0 <= seg <= t1:
                t0, v0, t1, v1 = map(mpmath.mpf, (t0, v0, t1, v1))
                return v0 + (t - t0) / (t1 - t0) * (v1 - v0)
        return mpmath.mpf(pts[-1][1])


@dataclass
class Sin(Signal):
    offset: float
    amplitude: float
    frequency: float

    def spec(self):
        return f"sin {self.offset!r} {self.amplitude!r} {self.frequency!r}"

    def value(self, t, dtype=np.float64):
        t = np.asarray(t, dtype=dtype)
        return dtype(self.offset) + dtype(self.amplitude) * np.sin(2 * dtype(np.pi) * dtype(self.frequency) * t)

    def rate(self, t):
        w = 2 * np.pi * self.frequency
        return self.amplitude * w * np.cos(w * np.asarray(t, dtype=float))

    def mp(self, t, seg):
        import mpmath
        return mpmath.mpf(self.offset) + mpmath.mpf(self.amplitude) * mpmath.sin(2 * mpmath.pi * mpmath.mpf(self.frequency) * t)

    def mp_rate(self, t, seg):
        import mpmath
        w = 2 * mpmath.pi * mpmath.mpf(self.frequency)
        return mpmath.mpf(self.amplitude) * w * mpmath.cos(w * t)


@dataclass
class SCurve(Signal):
    """v0 + (v1 - v0) (1 - cos(pi s))/2, s = (t - t0)/(t1 - t0) in [0, 1]: a jerk-limited speed ramp."""
    t0: float
    t1: float
    v0: float
    v1: float

    def spec(self):
        return f"scurve {self.t0!r} {self.t1!r} {self.v0!r} {self.v1!r}"

    def breaks(self):
        return [self.t0, self.t1]

    def value(self, t, dtype=np.float64):
        t = np.asarray(t, dtype=dtype)
        s = np.clip((t - dtype(self.t0)) / (dtype(self.t1) - dtype(self.t0)), 0, 1)
        return dtype(self.v0) + (dtype(self.v1) - dtype(self.v0)) * dtype(0.5) * (1 - np.cos(dtype(np.pi) * s))

    def rate(self, t):
        t = np.asarray(t, dtype=float)
        d = self.t1 - self.t0
        s = (t - self.t0) / d
        return np.where((s > 0) & (s < 1), (self.v1 - self.v0) * 0.5 * np.pi / d * np.sin(np.pi * np.clip(s, 0, 1)), 0.0)

    def mp(self, t, seg):
        import mpmath
        if seg <= self.t0:
            return mpmath.mpf(self.v0)
        if seg >= self.t1:
            return mpmath.mpf(self.v1)
        s = (t - mpmath.mpf(self.t0)) / (mpmath.mpf(self.t1) - mpmath.mpf(self.t0))
        return mpmath.mpf(self.v0) + (mpmath.mpf(self.v1) - mpmath.mpf(self.v0)) * (1 - mpmath.cos(mpmath.pi * s)) / 2


# --------------------------------------------------------------------------
# Scenes


@dataclass
class Scene:
    name: str
    title: str
    stop: float
    params: dict
    inputs: dict
    metric: str = "T"
    derivs: tuple = (False,)
    me: bool = True
    closed_form: bool = False

    def value(self, name, t, dtype=np.float64):
        return self.inputs[name].value(t, dtype) if name in self.inputs else np.full(np.shape(t), dtype(DEFAULTS[name]), dtype=dtype)

    def breaks(self):
        return sorted({b for s in self.inputs.values() for b in s.breaks() if 0 < b < self.stop})


DEFAULTS = {}  # start values from the model description, filled in main()

SCENES = [
    Scene("step", "held-input step response: 1 m span at 5 m/s, strain 0.1 % at t = 0, draw 0.1 % (tension 844 -> 1690 N, time constant 0.2 s)",
          1.0, {"startAtEquilibrium": False, "eps_start": 1e-3},
          {"web_a.v": Const(5.0), "web_a.eps": Const(1e-3), "web_b.v": Const(5.005)}, closed_form=True),
    Scene("short", "very short, fast span: 5 mm at 30 m/s (time constant 0.17 ms), strain 0.1 % at t = 0, draw 0.1 %",
          0.1, {"L": 5e-3, "startAtEquilibrium": False, "eps_start": 1e-3},
          {"web_a.v": Const(30.0), "web_a.eps": Const(1e-3), "web_b.v": Const(30.03)}, closed_form=True),
    Scene("ramp", "speed ramp: 5 -> 10 m/s from 0.1 s to 0.6 s (10 m/s2) while the draw grows from 0.1 % to 0.2 %",
          1.0, {},
          {"web_a.v": Pwl([(0.0, 5.0), (0.1, 5.0), (0.6, 10.0)]), "web_a.eps": Const(1e-3),
           "web_b.v": Pwl([(0.0, 5.005), (0.1, 5.005), (0.6, 10.02)])}, derivs=(False, True)),
    Scene("dancer", "dancer: roller b moves +-0.3 mm at 2 Hz (variableLength, 1 m span at 5 m/s, strain 0.1 %)",
          1.0, {"variableLength": True},
          {"web_a.v": Const(5.0), "web_a.eps": Const(1e-3), "web_b.v": Const(5.0), "frame_b.x": Sin(1.0, 3e-4, 2.0)},
          derivs=(False, True)),
    Scene("mass", "web mass on: S-curve speed ramp 5 -> 10 m/s from 0.1 s to 0.6 s (draw 0.1 %); error of web_b.F (tension plus momentum terms)",
          1.0, {"includeMass": True},
          {"web_a.v": SCurve(0.1, 0.6, 5.0, 10.0), "web_a.eps": Const(1e-3), "web_b.v": SCurve(0.1, 0.6, 5.005, 10.01)},
          metric="web_b.F", derivs=(False, True), me=False),
]


def variant_name(scene, derivs):
    return scene.name + ("+derivs" if derivs else "")


# --------------------------------------------------------------------------
# Environment and build


def sh(cmd, **kw):
    return subprocess.run(cmd, check=True, **kw)


def ensure_tools():
    if not shutil.which("gcc"):
        sh(["apt-get", "update", "-qq"])
        sh(["apt-get", "install", "-y", "-qq", "gcc"])
    if not Path("/usr/include/cvode/cvode.h").exists():
        print("installing SUNDIALS (Debian package libsundials-dev) for the native CVode driver ...", flush=True)
        env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
        sh(["apt-get", "update", "-qq"], env=env)
        sh(["apt-get", "install", "-y", "-qq", "--no-install-recommends", "libsundials-dev"], env=env,
           stdout=subprocess.DEVNULL)


def fmpy_headers():
    import fmpy
    return os.path.join(os.path.dirname(fmpy.__file__), "c-code")


def build():
    """Packages the FMU and snapshots it into target/study/fmu (others may
    rebuild target/release meanwhile); compiles the C drivers."""
    sh([sys.executable, "fmu/package.py", "--out", str(OUT / "ConvertingSpan.fmu")], cwd=ROOT, stdout=subprocess.DEVNULL)
    unzipdir = OUT / "fmu"
    shutil.rmtree(unzipdir, ignore_errors=True)
    with zipfile.ZipFile(OUT / "ConvertingSpan.fmu") as z:
        z.extractall(unzipdir)
    lib = unzipdir / "binaries" / "linux64" / "ConvertingSpan.so"
    bindir = OUT / "bin"
    bindir.mkdir(exist_ok=True)
    inc = f"-I{fmpy_headers()}"
    loader = f"-I{ROOT / 'tests' / 'integration' / 'c_importer'}"
    sh(["gcc", "-O2", "-Wall", "-Wextra", "-Werror", inc, loader, str(BENCH / "study_driver.c"), "-o", str(bindir / "study_driver"),
        "-ldl", "-lm", "-lsundials_cvode", "-lsundials_nvecserial", "-lsundials_sunmatrixdense", "-lsundials_sunlinsoldense"])
    sh(["gcc", "-O2", "-Wall", "-Wextra", "-Werror", inc, loader, str(BENCH / "native_cost.c"), "-o", str(bindir / "native_cost"), "-ldl"])
    return unzipdir, lib, bindir


def interface(md_path):
    root = ET.parse(md_path).getroot()
    vrs, starts, types = {}, {}, {}
    for v in root.iter("ScalarVariable"):
        name = v.get("name")
        vrs[name] = int(v.get("valueReference"))
        t = next(iter(v))
        types[name] = t.tag
        if t.get("start") is not None:
            s = t.get("start")
            starts[name] = (s == "true") if t.tag == "Boolean" else (int(s) if t.tag in ("Integer", "Enumeration") else float(s))
    return root.get("guid"), vrs, starts, types


def param_arg(vrs, types, name, value):
    kind = {"Real": "r", "Boolean": "b"}.get(types[name], "i")
    if kind == "b":
        value = int(bool(value))
    return f"{kind}:{vrs[name]}={value!r}" if kind == "r" else f"{kind}:{vrs[name]}={value}"


def machine():
    cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), platform.processor())
    mem = next((l.split()[1] for l in open("/proc/meminfo") if l.startswith("MemTotal")), "?")

    def version(cmd):
        try:
            return subprocess.run(cmd, capture_output=True, text=True).stdout.splitlines()[0]
        except Exception:
            return "?"

    import fmpy
    sundials = "?"
    try:
        sundials = re.search(r'SUNDIALS_VERSION "([^"]+)"', Path("/usr/include/sundials/sundials_config.h").read_text()).group(1)
    except Exception:
        pass
    git = subprocess.run(["git", "describe", "--always", "--dirty"], cwd=ROOT, capture_output=True, text=True).stdout.strip()
    return {
        "cpu": cpu, "cores": os.cpu_count(), "memory_gb": round(int(mem) / 1048576, 1), "os": platform.platform(),
        "python": platform.python_version(), "gcc": version(["gcc", "--version"]), "rustc": version(["rustc", "--version"]),
        "fmpy": fmpy.__version__, "sundials_native": sundials, "git": git, "load_average_start": os.getloadavg(),
    }


# --------------------------------------------------------------------------
# References


def closed_form(scene, times):
    """Exact solution for held inputs: x(t) = x_inf + (x0 - x_inf) exp(-lambda t), the
    differences to L formed in 40-digit arithmetic so that the strain (L - x)/x keeps
    full relative precision."""
    import mpmath
    with mpmath.workdps(40):
        p = {**DEFAULTS, **scene.params}
        L = mpmath.mpf(p["L"])
        va, ea, vb = (mpmath.mpf(scene.inputs[n].v) for n in ("web_a.v", "web_a.eps", "web_b.v"))
        eps0 = (vb / va) * (1 + ea) - 1 if p["startAtEquilibrium"] else mpmath.mpf(p["eps_start"])
        x0 = L / (1 + eps0)
        lam = vb / L
        x_inf = va / (1 + ea) / lam
        a, b = float(L - x_inf), float(x0 - x_inf)
        decay = np.exp(-float(lam) * times)
        strain = (a - b * decay) / (float(x_inf) + b * decay)
    return strain


def strain_rhs_factory(scene, p):
    """d(eps)/dt = (1+eps)/L * (dL/dt + ((v_b - v_a) + v_b*eps_a - eps*v_a)/(1+eps_a)) for
    forward flow (v_a >= 0), from x = L/(1+eps) and dx/dt = v_a/(1+eps_a) - v_b x/L.
    Inputs in extended precision, so that v_b - v_a does not lose digits."""
    ld = np.longdouble
    variable = p["variableLength"]

    def geometry(t):
        if not variable:
            return ld(p["L"]), ld(0)
        dx = scene.value("frame_b.x", t, ld) - scene.value("frame_a.x", t, ld)
        dy = scene.value("frame_b.y", t, ld) - scene.value("frame_a.y", t, ld)
        L = np.sqrt(dx * dx + dy * dy)
        rx = scene.inputs["frame_b.x"].rate(t) if "frame_b.x" in scene.inputs else 0.0
        return L, (dx * ld(rx)) / L

    def f(t, y):
        e = ld(y[0])
        va, ea, vb = (scene.value(n, t, ld) for n in ("web_a.v", "web_a.eps", "web_b.v"))
        L, Ldot = geometry(t)
        return [float((1 + e) / L * (Ldot + ((vb - va) + vb * ea - e * va) / (1 + ea)))]

    return f, geometry


def ode_reference(scene, times):
    """DOP853 at scipy's tightest tolerance and steps of at most 1 ms, restarted at every kink of the inputs."""
    from scipy.integrate import solve_ivp
    import mpmath
    p = {**DEFAULTS, **scene.params}
    f, geometry = strain_rhs_factory(scene, p)
    with mpmath.workdps(40):
        va, ea, vb = (mpmath.mpf(float(scene.value(n, 0.0))) for n in ("web_a.v", "web_a.eps", "web_b.v"))
        eps0 = float((vb / va) * (1 + ea) - 1) if p["startAtEquilibrium"] else p["eps_start"]
    edges = [0.0, *scene.breaks(), scene.stop]
    strain = np.empty_like(times)
    y = eps0
    for a, b in zip(edges[:-1], edges[1:]):
        # the step is bounded so that the dense output (7th-order interpolant) stays as accurate as the steps
        sol = solve_ivp(f, (a, b), [y], method="DOP853", rtol=2.3e-14, atol=1e-20, max_step=1e-3, dense_output=True)
        m = (times >= a) & (times <= b)
        strain[m] = sol.sol(times[m])[0]
        y = float(sol.y[0, -1])
    return strain, eps0


def mp_check(scene, times, strain, eps0, points=8):
    """mpmath's Taylor-series ODE solver (30 digits) at a few points: the largest
    relative difference to the reference strain there."""
    import mpmath
    p = {**DEFAULTS, **scene.params}
    with mpmath.workdps(30):
        edges = [0.0, *scene.breaks(), scene.stop]
        picks = np.linspace(0, len(times) - 1, points + 1).astype(int)[1:]
        worst = 0.0
        y = mpmath.mpf(eps0)
        for a, b in zip(edges[:-1], edges[1:]):
            seg = (a + b) / 2
            va, ea, vb = (lambda t, n=n: (scene.inputs[n].mp(t, seg) if n in scene.inputs else mpmath.mpf(DEFAULTS[n]))
                          for n in ("web_a.v", "web_a.eps", "web_b.v"))
            if p["variableLength"]:
                fb = scene.inputs["frame_b.x"]

                def LL(t):
                    return fb.mp(t, seg) - mpmath.mpf(DEFAULTS["frame_a.x"])

                def Ld(t):
                    return fb.mp_rate(t, seg)
            else:
                LL = lambda t: mpmath.mpf(p["L"])
                Ld = lambda t: mpmath.mpf(0)

            def F(t, e):
                return (1 + e) / LL(t) * (Ld(t) + ((vb(t) - va(t)) + vb(t) * ea(t) - e * va(t)) / (1 + ea(t)))

            sol = mpmath.odefun(F, mpmath.mpf(a), y)
            for k in picks:
                if a < times[k] <= b:
                    exact = sol(mpmath.mpf(float(times[k])))
                    worst = max(worst, float(abs((strain[k] - exact) / exact)))
            y = sol(mpmath.mpf(b))
    return worst


def reference(scene):
    """Tension (and web_b.F) at every point of the finest grid, k*1e-5."""
    n = int(round(scene.stop / STEPS[-1]))
    times = np.arange(n + 1) * STEPS[-1]
    p = {**DEFAULTS, **scene.params}
    info = {}
    if scene.closed_form:
        strain = closed_form(scene, times)
        ode, _ = ode_reference(scene, times)  # the ODE reference's own accuracy, where the exact answer is known
        info = {"method": "closed form (mpmath)", "ode_reference_error_here": float(np.max(np.abs(ode - strain) / np.abs(strain)))}
    else:
        strain, eps0 = ode_reference(scene, times)
        info = {"method": "DOP853 at rtol 2.3e-14 with steps of at most 1 ms on the strain, inputs in extended precision",
                "check_against_mpmath_odefun": mp_check(scene, times, strain, eps0)}
    EA = p["wp2.E"] * p["wp2.width"] * p["wp2.thickness"]
    tension = EA * strain
    out = {"T": tension}
    if scene.metric == "web_b.F":
        rho1 = p["wp1.density"] * p["wp1.width"] * p["wp1.thickness"]
        rho2 = p["wp2.density"] * p["wp2.width"] * p["wp2.thickness"]
        va, ea, vb = (scene.value(nm, times) for nm in ("web_a.v", "web_a.eps", "web_b.v"))
        dvb = scene.inputs["web_b.v"].rate(times)
        x = p["L"] / (1 + strain)
        out["web_b.F"] = tension + va / (1 + ea) * (rho2 * vb - rho1 * va) + rho2 * x * dvb
    return times, out, info


# --------------------------------------------------------------------------
# Native grid


@dataclass
class Job:
    id: str
    variant: str
    kind: str          # "cs" or "me"
    method: str        # auto, exact, rosenbrock, dopri5, rk4, euler, cvode
    h: float
    setting: float     # tolerance, substeps or rtol (None for auto/exact)
    derivs: bool
    params: list = field(default_factory=list)


def grid(scene, derivs, vrs, types, quick):
    v = variant_name(scene, derivs)
    n_for = lambda h: int(round(scene.stop / h))
    jobs = []
    steps = [1e-2, 1e-3] if quick else STEPS
    tols = TOLERANCES[::3] if quick else TOLERANCES

    def cs(method, h, setting=None):
        params = [param_arg(vrs, types, "solver", SOLVERS[method])]
        if method in ("rosenbrock", "dopri5"):
            params.append(param_arg(vrs, types, "tolerance", setting))
        if method in ("rk4", "euler"):
            params.append(param_arg(vrs, types, "substeps", int(setting)))
        tag = "" if setting is None else f"{setting:g}"
        jobs.append(Job(f"{v}_{method}{tag}_h{h:g}".replace("+", "P"), v, "cs", method, h, setting, derivs, params))

    for h in steps:
        cs("auto", h)
        if not derivs:
            cs("exact", h)
        for tol in tols:
            cs("rosenbrock", h, tol)
            cs("dopri5", h, tol)
        cap = MAX_SUBSTEPS_PARETO if h == PARETO_STEP else MAX_SUBSTEPS_OTHER
        for n in (RK4_SUBSTEPS[::3] if quick else RK4_SUBSTEPS):
            if n_for(h) * n <= cap:
                cs("rk4", h, n)
        for n in (EULER_SUBSTEPS[::3] if quick else EULER_SUBSTEPS):
            if n_for(h) * n <= cap:
                cs("euler", h, n)
        if scene.me and not derivs:
            for rtol in (CVODE_NATIVE[::3] if quick else CVODE_NATIVE):
                jobs.append(Job(f"{v}_cvode{rtol:g}_h{h:g}", v, "me", "cvode", h, rtol, False, []))
    return jobs


def scene_file(scene, vrs, types, path):
    lines = [f"stop {scene.stop!r}"]
    for name, value in scene.params.items():
        kind, rest = param_arg(vrs, types, name, value).split(":", 1)
        vr, val = rest.split("=")
        lines.append(f"param {kind} {vr} {val}")
    for name, sig in scene.inputs.items():
        lines.append(f"input {vrs[name]} {sig.spec()}")
    lines.append(f"output {vrs['T']}")
    lines.append(f"output {vrs[scene.metric] if scene.metric != 'T' else vrs['web_b.F']}")
    path.write_text("\n".join(lines) + "\n")


def run_native(scene, jobs, lib, guid, bindir, vrs, types, rounds, ref):
    """Runs every job of one scene in one process (interleaved rounds); errors against the reference."""
    work = OUT / "runs" / scene.name
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    scene_file(scene, vrs, types, work / "scene.txt")
    with open(work / "jobs.txt", "w") as f:
        for j in jobs:
            if j.kind == "cs":
                f.write(f"cs {j.id} {j.h!r} {int(j.derivs)} {len(j.params)} {' '.join(j.params)}\n")
            else:
                f.write(f"me {j.id} {j.h!r} {j.setting!r} 0\n")
    proc = subprocess.run([str(bindir / "study_driver"), str(lib), guid, str(work / "scene.txt"), str(work / "jobs.txt"),
                           str(work), str(rounds), "2e6"], capture_output=True, text=True)
    if proc.returncode:
        raise RuntimeError(f"study_driver failed on {scene.name}: {proc.stderr[-2000:]}")
    lines = {l.split()[0]: l.split() for l in (work / "results.txt").read_text().splitlines()}
    col = 0 if scene.metric == "T" else 1
    results = []
    for j in jobs:
        parts = lines[j.id]
        status, steps = int(parts[1]), int(parts[2])
        rec = {"variant": j.variant, "interface": "CS" if j.kind == "cs" else "ME", "method": j.method, "h": j.h,
               "setting": j.setting, "derivs": j.derivs, "status": status}
        if status == 0:
            ns = [float(x) for x in parts[3:3 + rounds]]
            y = np.fromfile(work / f"{j.id}.bin").reshape(steps + 1, 2)[:, col]
            stride = int(round(j.h / STEPS[-1]))
            r = ref[scene.metric][::stride][: steps + 1]
            rec.update(error=float(np.max(np.abs(y - r) / np.abs(r))), ns_per_step=float(np.median(ns)),
                       ns_min=float(min(ns)), ns_max=float(max(ns)), steps=steps)
            if j.kind == "me":
                nst, nfe, nsetups, netf = map(int, parts[3 + rounds + 1: 3 + rounds + 5])
                rec.update(cvode_steps=nst, rhs_evals=nfe, jacobian_setups=nsetups, error_test_fails=netf)
        results.append(rec)
    return results


# --------------------------------------------------------------------------
# Native per-step cost, per-call cost, instances, instruction counts


def span_target(lib, guid, vrs):
    return [str(lib), guid, ",".join(str(vrs[n]) for n in ("web_a.v", "web_a.eps", "web_b.v")),
            f"{vrs['v']},{vrs['T']}", "5,1e-3,5,0.005"]


def dahlquist_target(path):
    """A Reference FMU's Dahlquist library, its GUID from the modelDescription.xml of
    the FMU it was built into (found next to it or given as LIB.so:GUID).  Its
    "inputs" are the parameter k set three times (it has no inputs); k stays small
    so that x never becomes subnormal."""
    lib, _, guid = path.partition(":")
    if not guid:
        for md in [Path(lib).parents[2] / "modelDescription.xml", Path(lib).parent / "modelDescription.xml"]:
            if md.exists():
                guid = ET.parse(md).getroot().get("guid")
                break
    return [lib, guid, "3,3,3", "1,0", "1e-4,1e-4,1e-4,1e-5"]


def per_step(bindir, targets, rounds, steps):
    out = subprocess.run([str(bindir / "native_cost"), "step", str(rounds), str(steps), *sum(targets, [])],
                         check=True, capture_output=True, text=True).stdout.splitlines()
    res = []
    for line in out:
        parts = line.split()
        ns = [float(x) for x in parts[1:1 + rounds]]
        res.append({"ns_median": float(np.median(ns)), "ns_min": min(ns), "ns_max": max(ns), "rounds": ns})
    return res


def instructions_per_step(bindir, target):
    """callgrind: instructions of 120,000 steps minus those of 20,000 steps, per step
    (load-independent), and the inclusive instructions per step of fmi2SetReal,
    fmi2DoStep and fmi2GetReal (callgrind_annotate)."""
    if not shutil.which("valgrind"):
        return None, {}
    counts, per_call = [], {}
    for n in (20000, 120000):
        f = OUT / f"callgrind.{n}.out"
        subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={f}", str(bindir / "native_cost"), "step", "1",
                        str(n), *target], check=True, capture_output=True)
        text = f.read_text()
        m = re.search(r"^summary:\s+(\d+)", text, re.M) or re.search(r"^totals:\s+(\d+)", text, re.M)
        counts.append(int(m.group(1)))
        if n == 120000 and shutil.which("callgrind_annotate"):
            ann = subprocess.run(["callgrind_annotate", "--inclusive=yes", str(f)], capture_output=True, text=True).stdout
            for fn in ("fmi2SetReal", "fmi2DoStep", "fmi2GetReal"):
                m = re.search(r"^\s*([\d,]+)\s.*:" + fn + r"\b", ann, re.M)
                if m:
                    per_call[fn] = int(m.group(1).replace(",", "")) / n
        f.unlink()
    return (counts[1] - counts[0]) / 100000, per_call


def call_costs(bindir, target, which="all"):
    out = subprocess.run([str(bindir / "native_cost"), "calls", "7", "300000", which, *target], check=True, capture_output=True,
                         text=True).stdout.split()
    return {out[i]: float(out[i + 1]) for i in range(0, len(out), 2)}


def instances(bindir, target, n=10000):
    out = subprocess.run([str(bindir / "native_cost"), "instances", str(n), *target], check=True, capture_output=True,
                         text=True).stdout.split()
    return {out[i]: float(out[i + 1]) for i in range(0, len(out), 2)}


# --------------------------------------------------------------------------
# FMPy


def fmpy_table(scene, h):
    names = list(scene.inputs)
    if all(isinstance(s, (Const, Pwl)) for s in scene.inputs.values()):
        times = sorted({0.0, scene.stop, *scene.breaks()})
    else:
        times = np.arange(int(round(scene.stop / h)) + 1) * h
    rows = [(t, *[float(scene.value(n, t)) for n in names]) for t in times]
    return np.array(rows, dtype=[("time", float)] + [(n, float) for n in names])


def run_fmpy(scenes, unzipdir, native, calls, rounds, quick):
    from fmpy import read_model_description, simulate_fmu
    md = read_model_description(str(unzipdir), validate=True)   # parsed and validated once, outside the timing
    jobs = []
    for scene in scenes:
        base = {**scene.params}
        grid_h = [PARETO_STEP] if quick else [1e-2, PARETO_STEP, 1e-4]
        for h in grid_h:
            jobs.append((scene, "CS", "auto", h, None, {**base, "solver": 1}))
        for tol in ([1e-6] if quick else FMPY_TOLERANCES):
            jobs.append((scene, "CS", "rosenbrock", PARETO_STEP, tol, {**base, "solver": 3, "tolerance": tol}))
            jobs.append((scene, "CS", "dopri5", PARETO_STEP, tol, {**base, "solver": 4, "tolerance": tol}))
        if scene.me:
            for rtol in (CVODE_FMPY[::3] if quick else CVODE_FMPY):
                jobs.append((scene, "ME", "cvode", PARETO_STEP, rtol, base))
    def call(job, stop=None, logger=None):
        scene, iface, method, h, setting, values = job
        kw = dict(fmi_type="CoSimulation") if iface == "CS" else dict(fmi_type="ModelExchange", solver="CVode", relative_tolerance=setting)
        with contextlib.redirect_stdout(io.StringIO()):   # FMPy prints a warning for each input not in the table
            return simulate_fmu(str(unzipdir), validate=False, model_description=md, stop_time=stop or scene.stop,
                                output_interval=h, start_values=values, input=fmpy_table(scene, h), output=["T", "web_b.F"],
                                fmi_call_logger=logger, **kw)

    results = []
    times = {i: [] for i in range(len(jobs))}
    cpu = {i: [] for i in range(len(jobs))}
    fixed = {i: [] for i in range(len(jobs))}
    errors = {}
    for r in range(rounds):
        for i, job in enumerate(jobs):
            t0, c0 = time.perf_counter(), time.thread_time()
            res = call(job)
            times[i].append(time.perf_counter() - t0)
            cpu[i].append(time.thread_time() - c0)   # FMPy, CVode and the FMU all run in this thread
            t0 = time.perf_counter()
            call(job, stop=job[3])   # one output interval: what a run costs besides its steps
            fixed[i].append(time.perf_counter() - t0)
            if r == 0:
                scene = job[0]
                t = res["time"]
                res = res[np.append(t[1:] != t[:-1], True)]   # FMPy records an event point twice
                ref = native["refs"][scene.name][scene.metric][np.rint(res["time"] / STEPS[-1]).astype(int)]
                errors[i] = float(np.max(np.abs(res[scene.metric] - ref) / np.abs(ref)))
    for i, job in enumerate(jobs):
        scene, iface, method, h, setting, values = job
        counts = {}

        def count(msg):
            name = msg.split("(", 1)[0].strip()
            counts[name] = counts.get(name, 0) + 1

        call(job, logger=count)
        n = int(round(scene.stop / h))
        whole = float(np.median(times[i]))
        fixed_part = float(np.median(fixed[i]))
        if iface == "CS":
            nat = next((x for x in native["grid"] if x["variant"] == scene.name and x["interface"] == "CS"
                        and x["method"] == method and x["h"] == h and x["setting"] == setting and x["status"] == 0), None)
            fmu_s = nat["ns_per_step"] * n * 1e-9 if nat else None
        else:
            fmu_s = sum(c * calls.get("me." + name, calls.get("cs." + name, 10.0)) for name, c in counts.items()) * 1e-9
        results.append({"variant": scene.name, "interface": iface, "method": method, "h": h, "setting": setting,
                        "error": errors[i], "wall_s": whole, "cpu_s": float(np.median(cpu[i])), "fixed_s": fixed_part,
                        "per_step_us": (whole - fixed_part) / max(n - 1, 1) * 1e6, "steps": n,
                        "fmu_calls": sum(counts.values()), "fmu_s_estimate": fmu_s,
                        "fmu_share": (fmu_s / whole) if fmu_s else None,
                        "rhs_evals": counts.get("fmi2GetDerivatives", 0)})
    return results


# --------------------------------------------------------------------------
# Analysis


def cheapest(points, error):
    ok = [p for p in points if p.get("status", 0) == 0 and p["error"] <= error]
    return min(ok, key=lambda p: p["ns_per_step"]) if ok else None


def label(p):
    if p["method"] in ("auto", "exact"):
        return p["method"] + (" + derivatives" if p.get("derivs") else "")
    if p["method"] == "cvode":
        return f"CVode rtol {p['setting']:.0e}"
    if p["method"] in ("rk4", "euler"):
        return f"{p['method']} {int(p['setting'])} sub-steps" + (" + derivatives" if p.get("derivs") else "")
    return f"{p['method']} tol {p['setting']:.0e}" + (" + derivatives" if p.get("derivs") else "")


def analyse(native, fmpy_results, scenes):
    grid = [p for p in native["grid"] if p["status"] == 0]
    out = {"per_scene": {}}
    levels = [10.0 ** -k for k in range(2, 14)]
    for scene in scenes:
        cs_all = [p for p in grid if p["variant"].split("+")[0] == scene.name and p["interface"] == "CS" and p["h"] == PARETO_STEP]
        me = [p for p in grid if p["variant"] == scene.name and p["interface"] == "ME" and p["h"] == PARETO_STEP]
        s = {"title": scene.title}
        # cheapest CS method (any solver, with or without derivatives) for each error level
        s["cheapest"] = {f"{e:.0e}": ({"method": label(c), "ns": c["ns_per_step"], "error": c["error"]} if (c := cheapest(cs_all, e)) else None)
                         for e in levels}
        # per method family: cheapest cost for each error level
        fams = {}
        for p in cs_all + me:
            fam = p["method"] if p["method"] not in ("auto", "exact") else p["method"]
            fam += " + derivatives" if p.get("derivs") else ""
            fams.setdefault(fam, []).append(p)
        s["families"] = {f: {f"{e:.0e}": (round(c["ns_per_step"], 1) if (c := cheapest(ps, e)) else None) for e in levels} for f, ps in fams.items()}
        s["best_error"] = {f: min(p["error"] for p in ps) for f, ps in fams.items()}
        # co-simulation vs CVode at equal error (native)
        ratios = []
        for p in sorted(me, key=lambda p: -p["setting"]):
            c = cheapest(cs_all, p["error"])
            if c:
                ratios.append({"rtol": p["setting"], "cvode_error": p["error"], "cvode_ns": p["ns_per_step"],
                               "cs_method": label(c), "cs_error": c["error"], "cs_ns": c["ns_per_step"],
                               "ratio": p["ns_per_step"] / c["ns_per_step"]})
        s["cs_vs_cvode"] = ratios
        # the same at every communication step, for CVode's most accurate run there
        by_h = []
        for h in STEPS:
            me_h = [p for p in grid if p["variant"] == scene.name and p["interface"] == "ME" and p["h"] == h]
            cs_h = [p for p in grid if p["variant"].split("+")[0] == scene.name and p["interface"] == "CS" and p["h"] == h]
            if not me_h:
                continue
            best = min(me_h, key=lambda p: (p["error"], p["ns_per_step"]))
            c = cheapest(cs_h, best["error"])
            if c:
                by_h.append({"h": h, "rtol": best["setting"], "cvode_error": best["error"], "cvode_ns": best["ns_per_step"],
                             "cs_method": label(c), "cs_error": c["error"], "cs_ns": c["ns_per_step"],
                             "ratio": best["ns_per_step"] / c["ns_per_step"]})
        s["cs_vs_best_cvode_by_step"] = by_h
        out["per_scene"][scene.name] = s
    # what one more digit costs: geometric mean over levels of the cost ratio between successive levels
    digit = {}
    for scene in scenes:
        for fam, costs in out["per_scene"][scene.name]["families"].items():
            vals = [costs[f"{e:.0e}"] for e in levels]
            r = [b / a for a, b in zip(vals[:-1], vals[1:]) if a and b]
            if r:
                digit.setdefault(scene.name, {})[fam] = float(np.exp(np.mean(np.log(r))))
    out["cost_per_digit"] = digit
    if fmpy_results:
        fr = {}
        for scene in scenes:
            rows = [p for p in fmpy_results if p["variant"] == scene.name and p["h"] == PARETO_STEP]
            cs = next((p for p in rows if p["interface"] == "CS" and p["method"] == "auto"), None)
            me = [p for p in rows if p["interface"] == "ME"]
            if cs and me:
                fr[scene.name] = [{"rtol": p["setting"], "cvode_error": p["error"], "cs_error": cs["error"],
                                   "cvode_wall_s": p["wall_s"], "cs_wall_s": cs["wall_s"], "ratio": p["wall_s"] / cs["wall_s"],
                                   "ratio_cpu": p["cpu_s"] / cs["cpu_s"],
                                   "ratio_without_fixed": (p["wall_s"] - p["fixed_s"]) / max(cs["wall_s"] - cs["fixed_s"], 1e-9)}
                                  for p in me]
        out["fmpy_cs_vs_me"] = fr
    return out


# --------------------------------------------------------------------------
# Plots


COLORS = {"auto": "k", "exact": "k", "rosenbrock": "tab:blue", "dopri5": "tab:orange", "rk4": "tab:green",
          "euler": "tab:red", "cvode": "tab:purple"}


def save(fig, path):
    """PNG with a 256-colour palette (octree, which keeps the thin lines' colours): a quarter of the size."""
    import matplotlib.pyplot as plt
    fig.savefig(path, dpi=72)
    plt.close(fig)
    try:
        from PIL import Image
        Image.open(path).convert("RGB").quantize(colors=256, method=Image.Quantize.FASTOCTREE).save(path, optimize=True)
    except ImportError:
        pass


def variant_panels(scenes, height):
    """A figure with one panel per scene variant, four to a row."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    variants = [variant_name(s, d) for s in scenes for d in s.derivs]
    cols = 4
    rows = math.ceil(len(variants) / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, height * rows), squeeze=False)
    return fig, axes, variants


def variant_points(native, v, h=None):
    """The successful runs of a variant (at step h, if given); a "+derivs"
    variant also shows Model Exchange's runs of its scene."""
    ok = [p for p in native["grid"] if p["status"] == 0 and (h is None or p["h"] == h)]
    pts = [p for p in ok if p["variant"] == v]
    if v.endswith("+derivs"):
        pts += [p for p in ok if p["variant"] == v.split("+")[0] and p["interface"] == "ME"]
    return pts


def finish_panel(ax, v, scenes, xlabel):
    ax.set_title(v + ("" if any(s.me for s in scenes if s.name == v.split("+")[0]) else " (Model Exchange refuses includeMass)"),
                 fontsize=10)
    ax.set_ylim(1e-16, 1)
    ax.grid(True, which="major", alpha=0.3)
    ax.set_xlabel(xlabel, fontsize=8)
    ax.set_ylabel("max relative error", fontsize=8)
    ax.tick_params(labelsize=7)


def finish_figure(fig, axes, n_panels, ncol, title, bottom, path):
    """Blanks the unused panels, gives one legend for all panels and the title, and saves."""
    for ax in list(axes.flat)[n_panels:]:
        ax.axis("off")
    labels = {}
    for ax in axes.flat:
        for hd, lb in zip(*ax.get_legend_handles_labels()):
            labels.setdefault(lb, hd)
    fig.legend(list(labels.values()), list(labels.keys()), loc="lower center", ncol=min(ncol, len(labels)), fontsize=8)
    fig.suptitle(title, fontsize=11)
    fig.tight_layout(rect=(0, bottom, 1, 0.96))
    save(fig, path)


def plot_pareto(native, scenes, path):
    fig, axes, variants = variant_panels(scenes, 3.5)
    for ax, v in zip(axes.flat, variants):
        pts = variant_points(native, v, PARETO_STEP)
        front, best = [], float("inf")
        for p in sorted(pts, key=lambda p: (p["ns_per_step"], p["error"])):
            if p["error"] < best:
                front.append(p)
                best = p["error"]
        if front:
            xs = [p["ns_per_step"] for p in front] + [1e7]
            ys = [max(p["error"], 1e-16) for p in front] + [max(front[-1]["error"], 1e-16)]
            ax.step(xs, ys, where="post", color="0.85", lw=7, zorder=0, label="Pareto front (cheapest for each error)")
        for m in ["rosenbrock", "dopri5", "rk4", "euler", "cvode"]:
            ps = sorted([p for p in pts if p["method"] == m], key=lambda p: p["setting"] if m not in ("rk4", "euler") else -p["setting"])
            if ps:
                ax.loglog([p["ns_per_step"] for p in ps], [max(p["error"], 1e-16) for p in ps], "o-", ms=3, lw=1,
                          color=COLORS[m], label="CVode on Model Exchange (native)" if m == "cvode" else m)
        for m, marker in [("exact", "*"), ("auto", "s")]:
            ps = [p for p in pts if p["method"] == m]
            for p in ps:
                ax.loglog([p["ns_per_step"]], [max(p["error"], 1e-16)], marker, color="k", ms=9 if marker == "*" else 5,
                          label=m + (" (= rosenbrock 1e-8)" if v.endswith("+derivs") and m == "auto" else ""))
        finish_panel(ax, v, scenes, "ns per communication step (native, h = 1 ms)")
        ax.set_xlim(40, 3e6)
    finish_figure(fig, axes, len(variants), 7,
                  "Error against cost: every solver at tolerances 1e-3..1e-12 (fixed-step: sub-steps), CVode rtol 1e-4..1e-14",
                  0.05, path)


def plot_comm_step(native, scenes, path):
    fig, axes, variants = variant_panels(scenes, 3.3)
    picks = [("auto", None, "k", "s-"), ("exact", None, "k", "*--"), ("rosenbrock", 1e-6, "tab:blue", "o-"),
             ("rosenbrock", 1e-10, "tab:blue", "o--"), ("dopri5", 1e-8, "tab:orange", "o-"), ("rk4", 1, "tab:green", "o-"),
             ("euler", 1, "tab:red", "o-"), ("euler", 256, "tab:red", "o--"), ("cvode", 1e-6, "tab:purple", "o-"),
             ("cvode", 1e-10, "tab:purple", "o--")]
    for ax, v in zip(axes.flat, variants):
        pts = variant_points(native, v)
        for m, setting, color, style in picks:
            ps = sorted([p for p in pts if p["method"] == m and (setting is None or p["setting"] == setting)], key=lambda p: p["h"])
            if ps:
                name = {"cvode": "CVode rtol"}.get(m, m) + ("" if setting is None else f" {setting:g}")
                if m in ("rk4", "euler"):
                    name = f"{m} {setting} sub-step" + ("s" if setting > 1 else "")
                ax.loglog([p["h"] for p in ps], [max(p["error"], 1e-16) for p in ps], style, color=color, ms=4, lw=1, label=name)
        finish_panel(ax, v, scenes, "communication step h (s)")
    finish_figure(fig, axes, len(variants), 6,
                  "Error against communication step (a missing point: the method refused the step as unstable)", 0.07, path)


def plot_fmpy(fmpy_results, scenes, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    names = [s.name for s in scenes]
    fig, axes = plt.subplots(1, len(names), figsize=(3.8 * len(names), 3.4), squeeze=False)
    for ax, n in zip(axes.flat, names):
        rows = [p for p in fmpy_results if p["variant"] == n and p["h"] == PARETO_STEP]
        for m in ["auto", "rosenbrock", "dopri5", "cvode"]:
            ps = sorted([p for p in rows if p["method"] == m], key=lambda p: p["setting"] or 0)
            if ps:
                ax.loglog([p["wall_s"] * 1e3 for p in ps], [max(p["error"], 1e-16) for p in ps], "s" if m == "auto" else "o-",
                          color=COLORS[m], ms=4, lw=1, label={"cvode": "ME + CVode", "auto": "CS auto"}.get(m, "CS " + m))
        ax.set_title(n, fontsize=10)
        ax.set_xlabel("FMPy whole-run wall time (ms)", fontsize=8)
        ax.set_ylabel("max relative error", fontsize=8)
        ax.grid(True, alpha=0.3)
        ax.tick_params(labelsize=7)
        ax.legend(fontsize=7)
    fig.tight_layout()
    save(fig, path)


# --------------------------------------------------------------------------
# Report


def fmt_ns(x):
    return "–" if x is None else (f"{x:.0f}" if x >= 10 else f"{x:.1f}")


def cvode_row(scene, r, with_step=False):
    """A row of the CVode / co-simulation tables."""
    step = f"{r['h']:g} | " if with_step else ""
    return (f"| {scene} | {step}{r['rtol']:.0e} | {r['cvode_error']:.1e} | {fmt_ns(r['cvode_ns'])} | {r['cs_method']} | "
            f"{r['cs_error']:.1e} | {fmt_ns(r['cs_ns'])} | {r['ratio']:.1f}× |")


def report(res, path, full=True):
    """The tables; full=False leaves out the per-run tables (the published summary)."""
    m = res["machine"]
    a = res["analysis"]
    L = []
    L.append("# What accuracy costs — study results\n")
    L.append(f"Generated by `.venv/bin/python bench/study.py` in {res['run_seconds']:.0f} s on: {m['cpu']}, {m['cores']} cores, "
             f"{m['memory_gb']} GB, {m['os']}; {m['gcc']}; {m['rustc']}; FMPy {m['fmpy']}; SUNDIALS {m['sundials_native']} (native CVode); "
             f"commit {m['git']}. Load average at start {m['load_average_start'][0]:.1f}, at end {m['load_average_end'][0]:.1f} "
             f"(other processes share the machine: medians of {res['rounds']} interleaved rounds).\n")
    h = res["headline"]
    L.append("## Headline\n")
    span = h["per_step"][0]
    L.append(f"- Native cost of a co-simulation step (elastic scene, set 3 inputs + `fmi2DoStep` + get 2 outputs): "
             f"**{span['ns_median']:.0f} ns** median (min {span['ns_min']:.0f}), {span['instructions']:.0f} instructions"
             if span.get("instructions") else f"- Native cost of a co-simulation step: **{span['ns_median']:.0f} ns**")
    if h.get("dahlquist_ratio"):
        L.append(f"- Against the Reference FMUs' Dahlquist in the same harness ({h['per_step'][-1]['name']}): "
                 f"**{h['dahlquist_ratio']:.2f}×** the time, {h.get('dahlquist_instruction_ratio', float('nan')):.2f}× the instructions.")
    i = h["instances"]["ConvertingSpan"]
    L.append(f"- {int(i['instances']):,} instances: **{i['rss_bytes']:.0f} bytes** each ({i['rss_total_mb']:.1f} MB in all), "
             f"**{i['init_ns'] / 1e3:.2f} µs** each to instantiate and initialize.")
    for n in ("step", "short"):
        sc = a["per_scene"].get(n)
        if not sc:
            continue
        at = {r["h"]: r for r in sc["cs_vs_best_cvode_by_step"]}
        rng = [r["ratio"] for r in sc["cs_vs_cvode"]]
        if PARETO_STEP in at and rng:
            r = at[PARETO_STEP]
            L.append(f"- {n}, natively at h = 1 ms: CVode on Model Exchange costs **{min(rng):.1f}× to {max(rng):.1f}×** "
                     f"the cheapest co-simulation of equal or smaller error (rtol 1e-4 to 1e-14); at CVode's most accurate "
                     f"(rtol {r['rtol']:.0e}, error {r['cvode_error']:.1e}) {r['ratio']:.1f}×, where co-simulation's "
                     f"{r['cs_method']} has error {r['cs_error']:.1e}. By communication step: "
                     + ", ".join(f"{x['h']:g} s: {x['ratio']:.1f}×" for x in sc["cs_vs_best_cvode_by_step"]) + ".")
    for n, rows in a.get("fmpy_cs_vs_me", {}).items():
        if n in ("step", "short") and rows:
            lo, hi = min(r["ratio"] for r in rows), max(r["ratio"] for r in rows)
            shares = [p["fmu_share"] for p in res["fmpy"] if p["variant"] == n and p["fmu_share"] is not None and p["h"] == PARETO_STEP]
            L.append(f"- {n}, through FMPy (`simulate_fmu`, h = 1 ms): Model Exchange with CVode takes **{lo:.1f}× to {hi:.1f}×** "
                     f"the wall time of co-simulation (auto); the FMU's own share of a run is {100 * min(shares):.1f} % to "
                     f"{100 * max(shares):.1f} %, the rest is FMPy (and, for Model Exchange, CVode).")
    L.append("")
    L.append("## Native cost per communication step (elastic scene)\n")
    L.append("Set the three inputs, `fmi2DoStep` (h = 1 ms), get `v` and `T`, called from C through `dlopen` "
             f"(`bench/native_cost.c`, the loop of `step_cost.c`); median of {h['step_rounds']} interleaved rounds of "
             f"{h['step_steps']:,} steps.\n")
    L.append("| FMU | ns/step median | min | max | instructions/step (callgrind) |")
    L.append("|---|---|---|---|---|")
    for t in h["per_step"]:
        L.append(f"| {t['name']} | {t['ns_median']:.1f} | {t['ns_min']:.1f} | {t['ns_max']:.1f} | "
                 f"{'–' if t.get('instructions') is None else round(t['instructions'])} |")
    L.append("")
    if h.get("dahlquist_ratio"):
        L.append(f"ConvertingSpan / Dahlquist (one Euler step per `fmi2DoStep`): {h['dahlquist_ratio']:.2f}× in time, "
                 f"{h.get('dahlquist_instruction_ratio', float('nan')):.2f}× in instructions.\n")
    if any(t.get("instructions_per_call") for t in h["per_step"]):
        L.append("Instructions per step inside each call (callgrind, inclusive):\n")
        L.append("| FMU | fmi2SetReal (3 values) | fmi2DoStep | fmi2GetReal (2 values) |")
        L.append("|---|---|---|---|")
        for t in h["per_step"]:
            c = t.get("instructions_per_call") or {}
            L.append(f"| {t['name']} | " + " | ".join(f"{c[f]:.0f}" if f in c else "–" for f in ("fmi2SetReal", "fmi2DoStep", "fmi2GetReal")) + " |")
        L.append("")
    calls = h.get("call_ns_by_fmu", {})
    if calls:
        names = sorted({k for c in calls.values() for k in c})
        L.append("Where a step's time goes: each call timed on its own in a loop (ns per call, median of 7 rounds):\n")
        L.append("| FMU | " + " | ".join(n.split(".", 1)[1] + (" (3 values)" if "SetReal" in n else " (2 values)" if "GetReal" in n else "")
                                       for n in names) + " |")
        L.append("|---|" + "---|" * len(names))
        for fmu, c in calls.items():
            L.append(f"| {fmu} | " + " | ".join(f"{c[n]:.1f}" if n in c else "–" for n in names) + " |")
        L.append("")
    inst = h["instances"]
    L.append("## Instances\n")
    L.append(f"{int(inst['ConvertingSpan']['instances']):,} Co-Simulation instances in one process, each instantiated, set up and "
             "initialized:\n")
    L.append("| FMU | µs per instance (instantiate + initialize) | bytes per instance (RSS) | heap bytes per instance | all instances (MB RSS) | µs per fmi2FreeInstance |")
    L.append("|---|---|---|---|---|---|")
    for name, i in inst.items():
        L.append(f"| {name} | {i['init_ns'] / 1e3:.2f} | {i['rss_bytes']:.0f} | {i['heap_bytes']:.0f} | {i['rss_total_mb']:.2f} | {i['free_ns'] / 1e3:.3f} |")
    L.append("")
    L.append("## Scenes\n")
    for n, s in a["per_scene"].items():
        L.append(f"- **{n}**: {s['title']}; reference: {res['references'][n]['method']}"
                 + (f" (checked against mpmath's odefun: {res['references'][n]['check_against_mpmath_odefun']:.1e})"
                    if 'check_against_mpmath_odefun' in res['references'][n] else "") + ".")
    L.append("")
    L.append("## Cheapest way to each error (co-simulation, h = 1 ms, native ns per communication step)\n")
    levels = ["1e-02", "1e-04", "1e-06", "1e-08", "1e-10", "1e-12"]
    L.append("| scene | " + " | ".join(f"error ≤ {e}" for e in levels) + " |")
    L.append("|---|" + "---|" * len(levels))
    for n, s in a["per_scene"].items():
        cells = []
        for e in levels:
            c = s["cheapest"][e]
            cells.append("–" if c is None else f"{c['method']}: {fmt_ns(c['ns'])} ns")
        L.append(f"| {n} | " + " | ".join(cells) + " |")
    L.append("")
    L.append("## Cost of each method to reach an error (ns per communication step, h = 1 ms; – : not reached)\n")
    for n, s in a["per_scene"].items():
        L.append(f"**{n}**\n")
        L.append("| method | best error | " + " | ".join(f"≤ {e}" for e in levels) + " | × per digit |")
        L.append("|---|---|" + "---|" * len(levels) + "---|")
        for fam, costs in s["families"].items():
            d = a["cost_per_digit"].get(n, {}).get(fam)
            L.append(f"| {fam} | {s['best_error'][fam]:.1e} | " + " | ".join(fmt_ns(costs[e]) for e in levels)
                     + f" | {'–' if d is None else f'{d:.2f}'} |")
        L.append("")
    L.append("## Co-simulation against CVode on Model Exchange at equal error (native, same harness)\n")
    if full:
        L.append("At h = 1 ms, for each CVode tolerance: its error and cost, and the cheapest co-simulation run (any solver, "
                 "with or without input derivatives) whose error is at most CVode's.\n")
        L.append("| scene | CVode rtol | CVode error | CVode ns/step | co-simulation | its error | its ns/step | CVode / co-simulation |")
        L.append("|---|---|---|---|---|---|---|---|")
        for n, s in a["per_scene"].items():
            L += [cvode_row(n, r) for r in s["cs_vs_cvode"]]
        L.append("")
    else:
        L.append("At h = 1 ms, CVode / the cheapest co-simulation of equal or smaller error, over CVode's tolerances 1e-4 ... 1e-14: "
                 + "; ".join(f"{n} {min(r['ratio'] for r in s['cs_vs_cvode']):.1f}× to {max(r['ratio'] for r in s['cs_vs_cvode']):.1f}×"
                             for n, s in a["per_scene"].items() if s["cs_vs_cvode"])
                 + " (every tolerance: target/study/study.md).\n")
    L.append("The same comparison at every communication step, for CVode's most accurate run at that step:\n")
    L.append("| scene | h (s) | CVode rtol | CVode error | CVode ns/step | co-simulation | its error | its ns/step | CVode / co-simulation |")
    L.append("|---|---|---|---|---|---|---|---|---|")
    for n, s in a["per_scene"].items():
        L += [cvode_row(n, r, with_step=True) for r in s["cs_vs_best_cvode_by_step"]]
    L.append("")
    if res.get("fmpy"):
        L.append("## Through FMPy: simulate_fmu, whole-run wall time (h = 1 ms output grid)\n")
        L.append("The FMU extracted and its model description read and validated once, outside the timing; `validate=False`. "
                 "`fixed` is the time of a run of one output interval (instantiation, initialization, FMPy's set-up); "
                 "`FMU` is the time spent inside the FMU, estimated from the native cost of the same calls "
                 "(co-simulation: the native run of the same scene and method; Model Exchange: FMI calls counted with "
                 "FMPy's call logger times their native cost).\n")
        L.append("| scene | run | error | wall ms | CPU ms | fixed ms | µs per output step | FMI calls | FMU share |")
        L.append("|---|---|---|---|---|---|---|---|---|")
        for p in (res["fmpy"] if full else [p for p in res["fmpy"] if p["method"] in ("auto", "cvode") and p["h"] == PARETO_STEP
                                               and (p["method"] == "auto" or p["setting"] in (1e-4, 1e-7, 1e-10))]):
            run = f"CS {p['method']}" + (f" tol {p['setting']:.0e}" if p["setting"] and p["interface"] == "CS" else "")
            if p["interface"] == "ME":
                run = f"ME CVode rtol {p['setting']:.0e}"
            if p["h"] != PARETO_STEP:
                run += f" (h = {p['h']:g})"
            share = "–" if p["fmu_share"] is None else f"{100 * p['fmu_share']:.1f} %"
            L.append(f"| {p['variant']} | {run} | {p['error']:.1e} | {1e3 * p['wall_s']:.1f} | {1e3 * p['cpu_s']:.1f} | {1e3 * p['fixed_s']:.1f} | "
                     f"{p['per_step_us']:.1f} | {p['fmu_calls']} | {share} |")
        L.append("")
        L.append("FMPy 0.3.32's Model Exchange loop sets continuous inputs only at output points and when CVode evaluates the "
                 "event indicators, not in the right-hand side: with moving inputs (ramp, dancer) they are held over CVode's "
                 "internal steps, hence the large errors there (the native driver sets them in the right-hand side).\n")
        L.append("CVode (Model Exchange) / co-simulation (auto) whole-run wall time through FMPy:\n")
        L.append("| scene | rtol | CVode error | CS auto error | ratio (wall) | ratio (CPU) | ratio without the fixed part (wall) |")
        L.append("|---|---|---|---|---|---|---|")
        for n, rows in a.get("fmpy_cs_vs_me", {}).items():
            for r in rows:
                L.append(f"| {n} | {r['rtol']:.0e} | {r['cvode_error']:.1e} | {r['cs_error']:.1e} | {r['ratio']:.2f}× | "
                         f"{r['ratio_cpu']:.2f}× | {r['ratio_without_fixed']:.2f}× |")
        L.append("")
    L.append("Per-call native costs used for the FMPy split (ns): " +
             ", ".join(f"{k} {v:.1f}" for k, v in res["headline"]["call_ns"].items()) + ".\n")
    path.write_text("\n".join(L))


# --------------------------------------------------------------------------


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rounds", type=int, default=7, help="interleaved timing rounds (median reported)")
    ap.add_argument("--quick", action="store_true", help="a small grid (a smoke run of a few seconds per scene)")
    ap.add_argument("--no-fmpy", action="store_true", help="skip the FMPy runs")
    ap.add_argument("--dahlquist", action="append", default=[], metavar="[LABEL=]LIB.so[:GUID]",
                    help="a build of the Modelica Reference FMUs' Dahlquist, measured beside the span (repeatable; "
                         "the ratio is taken to the last one)")
    ap.add_argument("--publish", action="store_true", help="copy study.md and the PNGs docs/accuracy.md shows to bench/results/")
    args = ap.parse_args()
    start = time.time()
    OUT.mkdir(parents=True, exist_ok=True)
    ensure_tools()
    print("building and packaging the FMU ...", flush=True)
    unzipdir, lib, bindir = build()
    guid, vrs, starts, types = interface(unzipdir / "modelDescription.xml")
    DEFAULTS.update(starts)
    res = {"machine": machine(), "rounds": args.rounds, "library": str(lib),
           "library_sha256": hashlib.sha256(lib.read_bytes()).hexdigest()}
    scenes = SCENES

    # native per-step cost first (the headline), with the Dahlquist FMUs side by side
    print("native cost per step, instances ...", flush=True)
    dahlquist = [d.partition("=")[::2] if "=" in d else (f"Dahlquist {i + 1}", d) for i, d in enumerate(args.dahlquist)]
    targets = [span_target(lib, guid, vrs)] + [dahlquist_target(path) for _, path in dahlquist]
    names = ["ConvertingSpan (elastic scene)"] + [label for label, _ in dahlquist]
    step_rounds, step_steps = (3, 200000) if args.quick else (11, 1000000)
    per = per_step(bindir, targets, step_rounds, step_steps)
    for p, n, t in zip(per, names, targets):
        p["name"] = n
        p["instructions"], p["instructions_per_call"] = instructions_per_step(bindir, t)
    headline = {"per_step": per, "step_rounds": step_rounds, "step_steps": step_steps,
                "call_ns": call_costs(bindir, targets[0]),
                "instances": {"ConvertingSpan": instances(bindir, targets[0])}}
    headline["call_ns_by_fmu"] = {"ConvertingSpan": {k: v for k, v in headline["call_ns"].items() if k.startswith("cs.")}}
    for n, t in zip(names[1:], targets[1:]):
        headline["instances"][n] = instances(bindir, t)
        headline["call_ns_by_fmu"][n] = call_costs(bindir, t, "cs")
    headline["instances"] = {("ConvertingSpan" if k == "ConvertingSpan" else k): v for k, v in headline["instances"].items()}
    if len(per) > 1:
        headline["dahlquist_ratio"] = per[0]["ns_median"] / per[-1]["ns_median"]
        if per[0]["instructions"] and per[-1]["instructions"]:
            headline["dahlquist_instruction_ratio"] = per[0]["instructions"] / per[-1]["instructions"]
    res["headline"] = headline

    native = {"grid": [], "refs": {}}
    res["references"] = {}
    for scene in scenes:
        t0 = time.time()
        times, ref, info = reference(scene)
        native["refs"][scene.name] = ref
        res["references"][scene.name] = info
        jobs = [j for d in scene.derivs for j in grid(scene, d, vrs, types, args.quick)]
        t1 = time.time()
        native["grid"] += run_native(scene, jobs, lib, guid, bindir, vrs, types, args.rounds, ref)
        print(f"{scene.name}: reference {t1 - t0:.1f} s, {len(jobs)} native runs {time.time() - t1:.1f} s", flush=True)
    res["grid"] = native["grid"]

    res["fmpy"] = None
    if not args.no_fmpy:
        t0 = time.time()
        res["fmpy"] = run_fmpy(scenes, unzipdir, native, headline["call_ns"], max(3, args.rounds // 2 + 1), args.quick)
        print(f"FMPy: {len(res['fmpy'])} runs x rounds, {time.time() - t0:.1f} s", flush=True)

    res["analysis"] = analyse(native, res["fmpy"], scenes)
    res["machine"]["load_average_end"] = os.getloadavg()
    plot_pareto(native, scenes, OUT / "pareto.png")
    plot_comm_step(native, scenes, OUT / "comm_step.png")
    if res["fmpy"]:
        plot_fmpy(res["fmpy"], scenes, OUT / "fmpy.png")
    res["run_seconds"] = time.time() - start
    (OUT / "results.json").write_text(json.dumps(res, indent=1, default=float))
    report(res, OUT / "study.md")
    if args.publish:
        PUBLISH.mkdir(parents=True, exist_ok=True)
        report(res, PUBLISH / "study.md", full=False)
        for f in ["pareto.png", "comm_step.png"]:
            shutil.copy(OUT / f, PUBLISH / f)
    print(f"done in {res['run_seconds']:.0f} s: {OUT / 'study.md'}, results.json, pareto.png, comm_step.png")


if __name__ == "__main__":
    sys.exit(main())
