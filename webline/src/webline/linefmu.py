"""A whole line as one FMU: Line.fmu, its line in resources/line.json.

The scene is compiled as for a co-simulation of parts (`compiler`): the
same parts, start values, profiles and connections, in line order. They go
into resources/line.json (and each part's profile into
resources/profiles/<part>.json); the model descriptions come from
`line-description`, the Rust tool that builds the interface exactly as the
FMU's binary does when it reads that file; the binaries are the generic
Line library, built once for every platform (`fmu/package.py`).
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import tempfile
import zipfile
from pathlib import Path

from . import fmpy_log
from .compiler import compile_scene, layer_parts
from .fmus import DEFAULT_FMU_DIR
from .installation import CHECKOUT, LINE, host_platform
from .scene import Scene, Span
from .system import profile_text

FORMAT = "converting-span-line 1"
# Where fmu/package.py leaves the Line library of each platform (FMI 2.0 and 3.0 names), the
# description tool of each (tools/PLATFORM/) and the documentation page (documentation/index.html).
TEMPLATE = LINE
# Zip entries' time: the same line gives the same FMU bytes (as fmu/package.py's FMUs).
ZIP_TIME = (2026, 1, 1, 0, 0, 0)


# A scene's recorded quantity -> the Line FMU's output of that part (a laminate's T_<label>: as it is).
OUTPUTS = {"T": "T", "eps": "eps", "L": "length", "F_a": "F_a", "F_b": "F_b",
           "v": "v", "omega": "omega", "tau": "tau", "y": "y", "y_dot": "y_dot",
           "v_web": "v_web", "slip": "slip", "traction": "traction", "mu_eff": "mu_eff", "h_air": "h_air"}


def output(component: str, quantity: str) -> str:
    """The Line FMU's output of a scene's recorded quantity."""
    return f"{component}.{OUTPUTS.get(quantity, quantity)}"


class LineFmuError(RuntimeError):
    """The Line FMU cannot be written or run; the message says why. `cannot_export`: it could not be
    written (no Line binaries, a line the description tool refuses), so that another engine may run it."""

    def __init__(self, message, cannot_export=False):
        super().__init__(message)
        self.cannot_export = cannot_export


def line_spec(scene: Scene, fmu_dir=None, start: str | None = None, settle=True) -> dict:
    """The line.json of a scene: its parts in line order with their start
    values and profiles, the connections, the experiment, how it starts.
    `settle=False` leaves out the connected inputs' start values (which the
    FMU settles itself when it initializes), without running the parts' FMUs."""
    system = compile_scene(scene, fmu_dir, settle=settle, carriages_at_equilibrium=False)
    components = {c.name: c for c in system.components}
    parts = []
    laminates = []
    for c in scene.parts:
        names = layer_parts(c) if isinstance(c, Span) else [c.name]
        if isinstance(c, Span) and c.layered:  # its layers' spans, and the outputs of the laminate they make ([M6])
            laminates.append({"name": c.name, "layers": [{"part": n, "label": x} for n, x in zip(names, c.labels)]})
        for name in names:
            comp = components[name]
            part = {"name": name, "start": comp.start}
            if isinstance(c, Span):
                part.update(model="ConvertingSpan", role="span")
            else:
                part.update(model="Roller", role=c.type, torque_input=scene.speed_profile(c) is None)
                loop = getattr(getattr(c, "drive", None), "loop", None)
                if loop is not None and loop.set_input:
                    part["speed_input" if loop.speed else "set_input"] = True
                if getattr(getattr(c, "drive", None), "input", False):  # an ideal speed drive on v_ref
                    part["speed_input"] = True
                if loop is not None and loop.feedforward and not loop.speed and scene.input_reference() is not None:
                    part["feedforward_from"] = scene.input_reference().name
                wrap = getattr(c, "wrap", None)
                if wrap is not None:
                    part["wrap"] = float(wrap)
            if comp.profile:
                part["profile"] = comp.profile
            parts.append(part)
    spec = {
        "format": FORMAT,
        "name": scene.name,
        "description": scene.description,
        "experiment": {"start_time": 0.0, "stop_time": float(scene.stop_time), "step": float(scene.step)},
        "start": start or getattr(scene, "start", None) or "equilibrium",
        "parts": parts,
        "connections": [{"from": list(k.source), "to": list(k.target)} for k in system.connections],
    }
    if laminates:
        spec["laminates"] = laminates
    return spec


def spec_text(spec: dict) -> str:
    """The canonical text of a spec: its hash is the FMU's GUID."""
    return json.dumps(spec, indent=1, sort_keys=True) + "\n"


def description_tool(fmu_dir) -> Path:
    """The host's line-description: in a checkout built on first use (cargo), so that it follows the
    Rust sources; installed, the one fmu/package.py built for this platform (in the wheel)."""
    if CHECKOUT is None:
        return shipped_tool(fmu_dir)
    manifest = CHECKOUT / "models" / "line" / "Cargo.toml"
    # Its own target folder: a build of the line links the span's crate without its C API,
    # which must not replace the span's own library in target/ (fmu/package.py does the same).
    target = CHECKOUT / "target" / "line"
    exe = target / "release" / "line-description"
    run = subprocess.run(
        ["cargo", "build", "--quiet", "--release", "--manifest-path", str(manifest), "--features", "cli", "--bin", "line-description"],
        capture_output=True,
        text=True,
        env={**os.environ, "CARGO_TARGET_DIR": str(target)},
    )
    if run.returncode != 0:
        raise LineFmuError(f"cannot build line-description: {run.stderr.strip().splitlines()[-1] if run.stderr.strip() else run.returncode}",
                           cannot_export=True)
    return exe


def shipped_tool(fmu_dir) -> Path:
    """This platform's line-description in the FMU folder (fmu/package.py's tools/PLATFORM/)."""
    tools = Path(fmu_dir) / TEMPLATE / "tools"
    platform = host_platform()
    exe = tools / platform / ("line-description.exe" if platform == "win64" else "line-description")
    if not exe.is_file():
        carried = sorted(p.name for p in tools.iterdir()) if tools.is_dir() else []
        raise LineFmuError(f"no line-description for {platform} in {tools} (it holds {', '.join(carried) or 'none'}): "
                           "build it on this platform from the repository (`bash fmu/main.sh`)", cannot_export=True)
    return exe


def descriptions(text: str, out: Path, fmu_dir):
    """modelDescription.xml (FMI 2.0) and fmi3/ files for the spec text, into out."""
    with tempfile.TemporaryDirectory() as tmp:
        spec_file = Path(tmp) / "line.json"
        spec_file.write_text(text)
        run = subprocess.run([str(description_tool(fmu_dir)), str(spec_file), str(out)], capture_output=True, text=True)
        if run.returncode != 0:
            raise LineFmuError(run.stderr.strip() or f"line-description failed ({run.returncode})", cannot_export=True)


def export(scene: Scene, out, fmu_dir=None, fmi3=False, start: str | None = None) -> Path:
    """Writes Line.fmu for the scene (FMI 3.0 with fmi3=True); returns its path."""
    fmu_dir = Path(fmu_dir or DEFAULT_FMU_DIR)
    template = fmu_dir / TEMPLATE / ("fmi3" if fmi3 else "fmi2")
    binaries = template / "binaries"
    if not binaries.is_dir() or not any(binaries.iterdir()):
        raise LineFmuError(f"no Line binaries in {binaries}: build them with `bash fmu/main.sh` (fmu/package.py)",
                           cannot_export=True)
    spec = line_spec(scene, fmu_dir, start)
    text = spec_text(spec)
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        descriptions(text, tmp, fmu_dir)
        entries = {"modelDescription.xml": (tmp / ("fmi3" if fmi3 else "") / "modelDescription.xml").read_bytes()}
        if fmi3:
            entries["terminalsAndIcons/terminalsAndIcons.xml"] = (tmp / "fmi3" / "terminalsAndIcons.xml").read_bytes()
        entries["resources/line.json"] = text.encode()
        for part in spec["parts"]:
            if part.get("profile"):
                entries[f"resources/profiles/{part['name']}.json"] = profile_text(part["profile"]).encode()
        for path in sorted(binaries.rglob("*")):
            if path.is_file():
                entries[f"binaries/{path.relative_to(binaries).as_posix()}"] = path.read_bytes()
        page = (fmu_dir / TEMPLATE / "documentation" / "index.html").read_text(encoding="utf-8")
        entries["documentation/index.html"] = documentation(page, spec, entries["modelDescription.xml"], fmi3).encode()
        part_file = out.with_suffix(".part")
        with zipfile.ZipFile(part_file, "w", zipfile.ZIP_DEFLATED) as z:
            for name, data in entries.items():
                info = zipfile.ZipInfo(name, ZIP_TIME)
                info.compress_type = zipfile.ZIP_DEFLATED
                info.external_attr = 0o644 << 16
                z.writestr(info, data)
        part_file.replace(out)
    return out


def run_start(scene: Scene) -> str:
    """How a run of the scene as one Line FMU starts (`run`, and the sweeps through it): as every
    engine starts the scene, from its "start" (equilibrium unless it says given)."""
    return scene.start or "equilibrium"


def run(scene: Scene, fmu_dir=None, step: float | None = None, model_exchange=False, workdir=None):
    """The scene as one Line FMU in FMPy (Co-Simulation at the step, or Model Exchange with FMPy's CVode
    and output at the step): a Result with the scene's recorded columns at the communication points.
    The line starts as every engine starts the scene (its "start": equilibrium unless it says given)."""
    with tempfile.TemporaryDirectory(prefix="webline-line-") as tmp:
        path = export(scene, Path(workdir or tmp) / f"{scene.name}.fmu", fmu_dir, start=run_start(scene))
        return simulate(scene, path, step, model_exchange)


def model_exchange_refusal(scene: Scene) -> str | None:
    """Why the scene's Line FMU cannot run in Model Exchange (None: it can): a loop feeds forward the
    slope of a reference the importer gives as an input, which only Co-Simulation's steps give."""
    ref = scene.input_reference()
    fed = [c.name for c in scene.nodes if getattr(getattr(getattr(c, "drive", None), "loop", None), "feedforward", False)
           and not c.drive.loop.speed]
    if ref is None or not fed:
        return None
    return (f"{fed[0]}'s feed-forward takes the slope of its reference, the input {ref.name}.v_ref: Model Exchange gives "
            "no input derivatives and has no steps to take a difference over, so it would feed forward nothing; run the "
            "line in Co-Simulation, or give the reference as a profile")


def simulate(scene: Scene, path: Path, step: float | None = None, model_exchange=False):
    """A scene's Line FMU at `path` in FMPy (see `run`); info["messages"] holds what the FMU logged."""
    import time as clock

    import numpy as np
    from fmpy import simulate_fmu

    from .result import Result

    h = step or scene.step
    why = model_exchange and model_exchange_refusal(scene)
    if why:
        raise LineFmuError(f"{scene.name}: {why}")
    outputs = [output(c, q) for c, q in scene.record]
    watch = watcher(scene, path)
    t0 = clock.perf_counter()
    with fmpy_log.collecting() as (messages, logger):
        try:
            out = simulate_fmu(str(path), stop_time=scene.stop_time, step_size=h, output_interval=h, output=outputs,
                               fmi_type="ModelExchange" if model_exchange else "CoSimulation", logger=logger,
                               step_finished=watch)
        except Exception as e:  # FMPy's FMICallException names the call; the FMU's log says why
            raise LineFmuError(f"{scene.name}: {e}" + "".join(f"\n  {m}" for m in messages[-3:])) from e
    if watch.stopped is not None:
        raise watch.stopped
    wall = clock.perf_counter() - t0
    n = int(round(scene.stop_time / h))
    time = out["time"].astype(float)
    # Model Exchange records an event's time twice (before and after it): keep the
    # values before, as Co-Simulation gives them at a communication point where an
    # event falls (it happens at the start of the next step); the grid points only.
    on_grid = np.abs(time / h - np.round(time / h)) < 1e-6
    first = np.insert(time[1:] != time[:-1], 0, True)
    out, time = out[on_grid & first], time[on_grid & first]
    data = np.column_stack([out[k].astype(float) for k in outputs])
    how = "Model Exchange (FMPy CVode)" if model_exchange else "Co-Simulation"
    return Result(scene=scene.name, columns=scene.columns(), time=time, data=data,
                  info={"method": f"Line FMU in FMPy, {how}", "step": h, "steps": n, "wall_time": wall,
                        "messages": messages})


def watcher(scene: Scene, path: Path):
    """FMPy's step_finished for a Line FMU's run: False, and the Runaway in `.stopped`, once a span's
    tension passes its bound (bound.py)."""
    from fmpy import read_model_description

    from .bound import runaway, tension_bounds

    bounds = tension_bounds(scene)
    vrs = {v.name: v.valueReference for v in read_model_description(str(path)).modelVariables}
    names = list(bounds)
    refs = [vrs[f"{n}.T"] for n in names]
    limits = [bounds[n] for n in names]

    def step_finished(time, recorder):
        fmu = recorder.fmu
        values = fmu.getFloat64(refs) if hasattr(fmu, "getFloat64") else fmu.getReal(refs)  # FMI 3.0, 2.0
        for name, T, limit in zip(names, values, limits):
            if abs(T) > limit:
                step_finished.stopped = runaway(scene.name, name, T, limit, time)
                return False
        return True

    step_finished.stopped = None
    return step_finished


def run_libcosim(fmu: Path, outputs: list[str], step: float, stop: float):
    """A Line FMU in libcosim at a fixed step: the communication times, a row of
    the outputs at each, and the wall time."""
    import time as clock

    import numpy as np
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    log_output_level(CosimLogLevel.ERROR)
    t0 = clock.perf_counter()
    execution = CosimExecution.from_step_size(step_size=int(round(step * 1e9)))  # libcosim counts nanoseconds
    slave = execution.add_local_slave(CosimLocalSlave(fmu_path=str(fmu), instance_name="line"))
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    vr = {v.name.decode(): v.reference for v in execution.slave_variables(slave)}
    refs = [vr[name] for name in outputs]
    n = int(round(stop / step))
    rows = np.empty((n, len(outputs)))
    for k in range(n):
        if not execution.step():
            raise LineFmuError(f"{fmu}: libcosim failed at step {k} (t = {k * step} s)")
        rows[k] = observer.last_real_values(slave, refs)
    return step * np.arange(1, n + 1), rows, clock.perf_counter() - t0


def documentation(page: str, spec: dict, description: bytes, fmi3: bool) -> str:
    """The FMU's documentation/index.html from the page fmu/package.py wrote (its stylesheet inlined):
    which line, its parts, its variables."""
    import html
    import xml.etree.ElementTree as ET

    esc = html.escape
    root = ET.fromstring(description)
    token = root.get("instantiationToken") if fmi3 else root.get("guid")
    variables = root.find("ModelVariables")
    rows = []
    offered = {}
    for v in variables:
        if fmi3:
            kind, attrs = v.tag, v
        else:
            kind = next(iter(v)).tag
            attrs = next(iter(v))
        name = v.get("name")
        part = name.split(".")[0].removeprefix("der(")
        if v.get("causality") in ("output", "input"):
            offered.setdefault(part, []).append(name.split(".", 1)[1])
        rows.append(f"<tr><td><code>{esc(name)}</code></td><td>{esc(v.get('causality', 'local'))}</td>"
                    f"<td>{esc(attrs.get('unit', ''))}</td><td>{esc(attrs.get('start', ''))}</td>"
                    f"<td>{esc(v.get('description', ''))}</td></tr>")
    parts = [f"<tr><td><code>{esc(p['name'])}</code></td><td>{esc(p['role'])}</td><td>{esc(p['model'])}</td>"
             f"<td>{esc(', '.join(offered.get(p['name'], [])))}</td></tr>" for p in spec["parts"]]
    values = {
        "<!-- NAME -->": esc(spec["name"]),
        "<!-- DESCRIPTION -->": esc(spec.get("description", "")),
        "<!-- GUID -->": esc(token or ""),
        "<!-- STANDARD -->": "FMI 3.0" if fmi3 else "FMI 2.0",
        "<!-- PARTS -->": "\n".join(parts),
        "<!-- VARIABLES -->": "\n".join(rows),
    }
    for key, value in values.items():
        page = page.replace(key, value)
    return page
