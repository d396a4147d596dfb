"""An SSP archive run by other engines: DNV's libcosim (libcosimpy) and FMPy's SSP simulation.

Both couple Jacobi-style with held inputs at a fixed step. Each returns a Result on the communication
points start + k*h, k = 1..n (the values after each step), columns "component.variable" as recorded.
"""

from __future__ import annotations

import time as clock
from pathlib import Path

import numpy as np

from .result import Result
from .ssp import SSD, SspError
from .system import System

ENGINES = ("webline", "libcosim", "fmpy")


def steps_of(system: System, step: float | None) -> tuple[float, int]:
    h = step or system.step
    n = int(round((system.stop_time - system.start_time) / h))
    return h, n


def run_libcosim(ssd_dir: Path, system: System, step: float | None = None) -> Result:
    """libcosim on an extracted archive (read_ssp's target folder: libcosim never unpacks an untrusted zip)."""
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver

    h, n = steps_of(system, step)
    ns = int(round(h * 1e9))  # libcosim counts time in nanoseconds
    if abs(ns - h * 1e9) > 1e-6 * h * 1e9:
        raise SspError(f"{system.name}: step {h} s is not a whole number of nanoseconds (libcosim's time unit)")
    log_output_level(CosimLogLevel.ERROR)
    t0 = clock.perf_counter()
    try:
        execution = CosimExecution.from_ssp_file(str(Path(ssd_dir)), step_size=ns)
    except AssertionError:
        raise SspError(f"{ssd_dir}: libcosim could not load {SSD} (see its log above)") from None
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    reads, order = [], []  # (slave index, value references) per component; the record's order of the values read
    for comp in dict.fromkeys(c for c, _ in system.record):
        index = execution.slave_index_from_instance_name(comp)
        vr = {v.name.decode(): v.reference for v in execution.slave_variables(index)}
        picked = [i for i, (c, _) in enumerate(system.record) if c == comp]
        reads.append((index, [vr[system.record[i][1]] for i in picked]))
        order += picked
    columns = [f"{c}.{v}" for c, v in system.record]
    rows = np.empty((n, len(columns)))
    for k in range(n):
        if not execution.step():
            raise SspError(f"{system.name}: libcosim failed at step {k} (t = {system.start_time + k * h} s)")
        rows[k, order] = [x for index, vrs in reads for x in observer.last_real_values(index, vrs)]
    wall = clock.perf_counter() - t0
    times = system.start_time + h * np.arange(1, n + 1)
    return Result(scene=system.name, columns=columns, time=times, data=rows,
                  info={"method": f"libcosim, fixed step {h * 1e3:g} ms", "step": h, "steps": n, "wall_time": wall})


def fmpy_parameter_set(archive: Path, system_root=None):
    """The archive's own parameter sets as one FMPy ParameterSet: names prefixed with the component,
    Boolean literals converted (FMPy sets a Boolean as `value != 0.0`, so the text 'false' would be True)."""
    from fmpy.ssp.ssd import ParameterSet, read_ssd, read_ssv

    ssd = read_ssd(str(archive))
    merged = ParameterSet(name="start values")
    for comp in ssd.system.elements:
        for binding in comp.parameterBindings:
            sets = [read_ssv(str(archive), resource=binding.source)] if binding.source else binding.parameterValues
            for ps in sets:
                for p in ps.parameters:
                    if p.type in ("String", "Enumeration", "Binary"):
                        raise SspError(f"{archive}: {comp.name}.{p.name}: FMPy's SSP simulation cannot set a {p.type}")
                    if p.type == "Boolean":
                        p.value = {"true": 1.0, "false": 0.0, "1": 1.0, "0": 0.0}[p.value.strip()]
                    p.name = f"{comp.name}.{p.name}"
                    merged.parameters.append(p)
    return merged


def run_fmpy(archive: Path, system: System, step: float | None = None) -> Result:
    """FMPy's simulate_ssp on a (checked) archive. FMPy labels its rows t but they hold the values at t + h,
    and its first step uses 0.0 for every connected input; the times here are the true ones."""
    from fmpy.ssp.simulation import simulate_ssp

    h, n = steps_of(system, step)
    t0 = clock.perf_counter()
    # FMPy loops while its summed time < stop: half a step short gives exactly n steps.
    out = simulate_ssp(str(archive), start_time=system.start_time, stop_time=system.start_time + (n - 0.5) * h,
                       step_size=h, parameter_set=fmpy_parameter_set(archive))
    wall = clock.perf_counter() - t0
    if len(out) != n:
        raise SspError(f"{archive}: FMPy took {len(out)} steps, not {n}")
    columns = [f"{c}.{v}" for c, v in system.record]
    missing = [c for c in columns if c not in out.dtype.names]
    if missing:
        raise SspError(f"{archive}: FMPy recorded no {', '.join(missing)} (record only connectors)")
    data = np.column_stack([out[c].astype(float) for c in columns])
    return Result(scene=system.name, columns=columns, time=out["time"] + h, data=data,
                  info={"method": f"FMPy simulate_ssp, fixed step {h * 1e3:g} ms", "step": h, "steps": n, "wall_time": wall})


def ssd_dir_of(target_dir: Path) -> Path:
    """The folder read_ssp extracted to, checked to hold the SSD (what libcosim is given)."""
    p = Path(target_dir)
    if not (p / SSD).is_file():
        raise SspError(f"{p}: no {SSD}")
    return p
