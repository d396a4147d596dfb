"""Studies through the Line FMU: one export per structure, one instance per worker, a reset per point.

Planning, on the client: each point's scene is read with its overrides and compiled to the line it
would export (`linefmu.line_spec`, without settling the connected inputs, which the FMU settles
itself when it initializes). Two points share an FMU when their lines differ only in Real
parameters the FMU offers (`<part>.<parameter>`, and `tolerance`, the study key of the FMU's own
tolerance); each point then sets those of its values that differ from the FMU's start values. Any
other difference (a profile table, an event, a web by record, an effect switched on, the stop time,
the record) is a structure of its own, exported once for all its points (docs/studies.md).

On a worker: each FMU (its bytes reach every worker through the study's plugin, `delivery`) is
extracted once, its model description read once and one instance made; every point resets that
instance (fmi2Reset), sets its parameters and runs as FMPy's `simulate_fmu` runs it in `linefmu.run`
(FMPy's efficient-loops pattern): with the steps in one call into the library (`native`, --engine
line), or through `simulate_fmu` itself (--engine fmpy-line), the same numbers bit for bit. The
instance is freed and its folder removed when the study ends or the worker closes.
"""

from __future__ import annotations

import io
import json
import shutil
import struct
import tempfile
import threading
import time as clock
import zipfile
from dataclasses import dataclass
from pathlib import Path

from distributed import WorkerPlugin

from . import delivery, fmpy_log, linefmu, native, units
from .points import Outcome, failed, layout, metric_record, metrics
from .scene import load_scene

TOLERANCE = "tolerance"  # the Line FMU's own parameter: a study key, not a scene key
PLUGIN = "webline-line-fmus"
WARNING = 1  # fmi2Warning: a status at or above it is worth a row's word
LINE_FMU = "Line.fmu"  # its name among a study's files


@dataclass
class Structure:
    """One exported Line FMU and what its points share."""

    index: int
    fmu: bytes | None  # None: the export failed, `error` says why
    error: str | None
    offered: frozenset  # the FMU's Real parameters
    base: dict  # their start values in the FMU: what fmi2Reset restores
    fixed: dict  # the line's other Real start values: equal in every point of the structure
    outputs: list  # FMU variables: the scene's record first, then what the metrics read
    recorded: int  # how many of `outputs` are the scene's record
    columns: list  # the record's columns ("first.T [N]")
    parts: list  # points.layout
    stop_time: float
    step: float
    name: str = ""  # the study's plugin that carries the FMU to the workers, and its instance's key there


@dataclass
class LineTask:
    """What a worker needs for one point besides the FMU (which travels apart, once)."""

    fmu: str  # Structure.name
    parameters: dict
    stop_time: float
    step: float
    outputs: list
    recorded: int
    parts: list
    series: bool
    user: tuple = ()  # the user's metrics (usermetric.Metric)
    native: bool = True  # the steps in one call into the library (`native`), or FMPy's loop (--engine fmpy-line)


def _same(a: float, b: float) -> bool:
    return struct.pack("<d", a) == struct.pack("<d", b)


def _reals(spec: dict) -> dict:
    return {f"{p['name']}.{k}": v for p in spec["parts"] for k, v in p["start"].items() if isinstance(v, float)}


def _skeleton(spec: dict, scene, step: float) -> str:
    """The line without its Real start values: points with equal skeletons may share an FMU."""
    parts = [{**p, "start": {k: v for k, v in p["start"].items() if not isinstance(v, float)}} for p in spec["parts"]]
    return json.dumps({**spec, "parts": parts, "record": scene.record, "step": step}, sort_keys=True)


class Planner:
    """Points to Line FMU tasks: exports a structure the first time a point needs it."""

    def __init__(self, scene_path, fmu_dir, step=None, series=False, user=(), native=True):
        self.scene_path = Path(scene_path)
        self.fmu_dir = fmu_dir
        self.step = step
        self.series = series
        self.user = tuple(user)
        self.native = native
        self.structures: list[Structure] = []
        self._by_skeleton: dict[str, list[Structure]] = {}

    def plan(self, overrides: dict):
        """(Structure, LineTask) of a point; raises with the reason if its scene cannot be read."""
        overrides = dict(overrides)
        tolerance = overrides.pop(TOLERANCE, None)
        scene = load_scene(self.scene_path, overrides, self.fmu_dir)
        spec = linefmu.line_spec(scene, self.fmu_dir, start=linefmu.run_start(scene), settle=False)
        reals = _reals(spec)
        if tolerance is not None:
            reals[TOLERANCE] = units.parse_quantity(tolerance, units.DIMENSIONLESS)
        step = self.step or scene.step
        candidates = self._by_skeleton.setdefault(_skeleton(spec, scene, step), [])
        for s in candidates:
            if set(reals) - s.offered == set(s.fixed) and all(_same(reals[n], v) for n, v in s.fixed.items()):
                break
        else:
            s = self._export(scene, reals, step)
            candidates.append(s)
        if s.fmu is None:
            raise linefmu.LineFmuError(s.error)
        parameters = {n: v for n, v in reals.items() if n in s.offered and not _same(v, s.base[n])}
        return s, LineTask(s.name, parameters, s.stop_time, s.step, s.outputs, s.recorded, s.parts, self.series,
                           self.user, self.native)

    def _export(self, scene, reals: dict, step: float) -> Structure:
        from fmpy import read_model_description

        index = len(self.structures)
        record = metric_record(scene, self.user)
        outputs = [linefmu.output(c, q) for c, q in record]
        common = dict(index=index, outputs=outputs, recorded=len(scene.record), columns=scene.columns(),
                      parts=layout(scene), stop_time=float(scene.stop_time), step=float(step))
        try:
            with tempfile.TemporaryDirectory(prefix="webline-study-") as tmp:
                path = linefmu.export(scene, Path(tmp) / "Line.fmu", self.fmu_dir, start=linefmu.run_start(scene))
                data = path.read_bytes()
                description = read_model_description(str(path))
        except Exception as e:  # the points with these very values fail, saying why; the study goes on
            s = Structure(fmu=None, error=f"exporting the Line FMU: {e}", offered=frozenset(), base={}, fixed=reals, **common)
        else:
            offered = {v.name: float(v.start) for v in description.modelVariables
                       if v.causality == "parameter" and v.type == "Real"}
            fixed = {n: v for n, v in reals.items() if n not in offered}
            s = Structure(fmu=data, error=None, offered=frozenset(offered), base=offered, fixed=fixed,
                          name=delivery.study_name(f"line{index}"), **common)
        self.structures.append(s)
        return s


class _Ready:
    """One FMU on a worker: extracted, described, instantiated; reset before every point."""

    def __init__(self, fmu: bytes):
        from fmpy import read_model_description
        from fmpy.simulation import instantiate_fmu

        self.folder = tempfile.mkdtemp(prefix="webline-line-")
        try:
            with zipfile.ZipFile(io.BytesIO(fmu)) as z:
                z.extractall(self.folder)
            self.description = read_model_description(self.folder)
            # FMPy's default callbacks: the messages go through its proxy, which each run points at its own collector.
            with fmpy_log.collecting_proxied() as messages:
                try:
                    self.instance = instantiate_fmu(self.folder, self.description, "CoSimulation")
                except Exception as e:
                    raise RuntimeError(f"{e}" + "".join(f"\n  {m}" for _, m in messages[-3:])) from e
        except BaseException:
            shutil.rmtree(self.folder, ignore_errors=True)
            raise

    def run(self, task: LineTask):
        """The point's outputs (FMPy's structured array), the FMU's messages, the seconds they took."""
        from fmpy import simulate_fmu

        simulate = native.simulate if task.native else simulate_fmu
        with fmpy_log.collecting_proxied() as messages:
            t0 = clock.perf_counter()
            self.instance.reset()
            try:
                out = simulate(self.folder, model_description=self.description, fmu_instance=self.instance,
                               fmi_type="CoSimulation", stop_time=task.stop_time, step_size=task.step,
                               output_interval=task.step, output=task.outputs, start_values=task.parameters)
            except Exception as e:  # FMPy names the call; the FMU's log says why
                raise RuntimeError(f"{e}" + "".join(f"\n  {m}" for _, m in messages[-3:])) from e
            seconds = clock.perf_counter() - t0
        return out, messages, seconds

    def close(self):
        try:
            self.instance.freeInstance()
        finally:
            shutil.rmtree(self.folder, ignore_errors=True)


class LineFmus:
    """The Line FMUs of one worker process, by their study's plugin name. One point runs at a time: every instance
    logs through FMPy's one proxy per process (fmpy_log)."""

    def __init__(self):
        self._ready: dict[str, _Ready] = {}
        self._lock = threading.Lock()

    def run(self, key: str, fmu: bytes, task: LineTask):
        with self._lock:
            ready = self._ready.get(key)
            if ready is None:
                ready = self._ready[key] = _Ready(fmu)
            return ready.run(task)

    def has(self, key: str) -> bool:
        return key in self._ready

    def drop(self, key: str):
        """Frees one FMU's instance and removes its folder (its study ended); waits for a running point."""
        with self._lock:
            ready = self._ready.pop(key, None)
            if ready is not None:
                ready.close()

    def close(self):
        with self._lock:
            for ready in self._ready.values():
                ready.close()
            self._ready.clear()


class LineFmusPlugin(WorkerPlugin):
    """Gives each worker its LineFmus, closed (instances freed, folders removed) when the worker closes.
    Registered again by a later study, it stays (no running point loses its instance); each study's
    own plugin (`delivery`) drops that study's FMUs when it ends."""

    name = PLUGIN
    idempotent = True

    def setup(self, worker):
        self.fmus = LineFmus()

    def teardown(self, worker):
        self.fmus.close()


def worker_fmus() -> LineFmus:
    from distributed import get_worker

    return get_worker().plugins[PLUGIN].fmus


def run_points(tasks: list) -> list:
    """Several points of one structure, one after the other (a Dask task): the FMU from its study's
    plugin, whose end on this worker frees the instance."""
    files, fmus = delivery.study_files(tasks[0].fmu), worker_fmus()
    if not fmus.has(tasks[0].fmu):
        files.on_teardown(lambda: fmus.drop(tasks[0].fmu))
    return [run_point(files.files[LINE_FMU], task, fmus) for task in tasks]


def run_point(fmu: bytes, task: LineTask, fmus: LineFmus | None = None) -> Outcome:
    """One point through the Line FMU (a Dask task; `fmus`: the worker's, by default)."""
    started = clock.time()
    try:
        fmus = fmus or worker_fmus()
        out, messages, simulation = fmus.run(task.fmu, fmu, task)
        row = metrics(task.parts, lambda name: out[name], out["time"], task.user)
        warned = [m for status, m in messages if status >= WARNING]
        row["status"] = f"warning: {warned[-1]}" if warned else "ok"
        outcome = Outcome(row=row, simulation=simulation)
        if task.series:
            import numpy as np

            outcome.time = out["time"].astype(float)
            outcome.data = np.column_stack([out[name].astype(float) for name in task.outputs[: task.recorded]])
    except Exception as e:  # a point that fails is a row that says why
        outcome = failed(str(e))
    outcome.started, outcome.ended = started, clock.time()
    return outcome
