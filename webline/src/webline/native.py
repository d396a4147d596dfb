"""A point of a study through the Line FMU without a Python call per step.

`simulate` takes what `linestudy` hands FMPy's `simulate_fmu` for a point (an instance reset, its
model description, the stop time, the step, the outputs, the start values) and returns the same
structured array, bit for bit. It makes the same FMI calls in the same order, as FMPy 0.3.32's
Co-Simulation loop (`fmpy.simulation.simulateCS`) makes them for an FMU without inputs:
fmi2SetupExperiment (the default experiment's tolerance and start time, the stop time), the start
values in the model description's order (those settable when instantiated, then, in initialization
mode, the others), fmi2ExitInitializationMode, fmi2GetReal of the outputs, a fmi2DoStep and a
fmi2GetReal per communication point, fmi2Terminate. Only the loop moves into the library: the Line
library's one addition to FMI, `convertingSpanDoSteps` (fmi/abi), takes every communication point
FMPy would take (`communication_points`, the same floating-point operations) and runs its steps and
reads in one call. Why this way and not a driver of our own: docs/studies.md.

A step the FMU refuses ends the point as it ends in FMPy: the calls FMPy makes next are made
through FMPy, so that the exception and the FMU's messages are the same.
"""

from __future__ import annotations

import ctypes
from math import isclose

import numpy as np

ENTRY = "convertingSpanDoSteps"
OK, DISCARD = 0, 2  # fmi2Status
LAST_SUCCESSFUL_TIME, TERMINATED = 2, 3  # fmi2StatusKind
RELATIVE = 1e-9  # math.isclose's default relative tolerance, which FMPy's loop uses


class NativeError(RuntimeError):
    """The FMU cannot run natively (its library lacks the entry, an output is not Real); the message says so."""


def _close(a: np.ndarray, b: float) -> np.ndarray:
    """math.isclose(a, b) for each element of `a` (relative 1e-9, no absolute tolerance), as FMPy tests times."""
    diff = np.abs(b - a)
    return (a == b) | (diff <= abs(RELATIVE * b)) | (diff <= np.abs(RELATIVE * a))


def communication_points(start: float, stop: float, interval: float, variable_steps: bool) -> np.ndarray:
    """The times FMPy's simulateCS stops at without inputs: start + k*interval while they stay below
    the stop time (not within 1e-9 of it); the last is the stop time itself when it falls between
    two, for an FMU that handles a variable step (else the run ends before it)."""
    if start > stop or isclose(start, stop):
        return np.array([start])
    count = int((stop - start) / interval) + 2  # past the stop time: the loop ends within these
    regular = start + np.arange(1, count + 1, dtype=np.float64) * interval
    last = int(np.argmax((regular > stop) | _close(regular, stop)))  # the first at or past the stop time
    times = [np.array([start]), regular[:last]]
    if not regular[last] > stop or isclose(regular[last], stop):
        times.append(regular[last:last + 1])
    elif variable_steps:
        times.append(np.array([stop]))
    return np.concatenate(times)


def _apply_start_values(fmu, description, values: dict, settable) -> dict:
    """FMPy's apply_start_values for scalars without units: each value its own call, in the model
    description's order; returns those not set."""
    values = dict(values)
    for v in description.modelVariables:
        if v.name in values and settable(v):
            kind = "Integer" if v.type == "Enumeration" else v.type
            getattr(fmu, "set" + kind)([v.valueReference], [v._python_type(values.pop(v.name))])
    return values


def entry(fmu):
    """The library's `convertingSpanDoSteps` of an FMPy FMU2Slave, typed."""
    try:
        f = getattr(fmu.dll, ENTRY)
    except AttributeError:
        raise NativeError(f"the FMU's library has no {ENTRY} (a Line FMU exported before it, or another FMU): "
                          "run it with --engine fmpy-line") from None
    if f.argtypes is None:
        double_p, size = ctypes.POINTER(ctypes.c_double), ctypes.c_size_t
        f.argtypes = [ctypes.c_void_p, double_p, size, ctypes.POINTER(ctypes.c_uint32), size, double_p,
                      ctypes.POINTER(size), ctypes.POINTER(size)]
        f.restype = ctypes.c_int
    return f


def start(fmu, description, stop: float, start_values: dict) -> float:
    """FMPy's initialization of a reset instance (simulateCS): fmi2SetupExperiment with the default
    experiment's tolerance and start time and the stop time, the start values, initialization mode
    and its end. Returns the start time."""
    from fmpy.simulation import settable_in_initialization_mode, settable_in_instantiated

    experiment = description.defaultExperiment
    begin = float(experiment.startTime) if experiment is not None and experiment.startTime is not None else 0.0
    tolerance = float(experiment.tolerance) if experiment is not None and experiment.tolerance is not None else None
    fmu.setupExperiment(tolerance=tolerance, startTime=begin, stopTime=stop)
    left = _apply_start_values(fmu, description, start_values, settable_in_instantiated)
    fmu.enterInitializationMode()
    left = _apply_start_values(fmu, description, left, settable_in_initialization_mode)
    fmu.exitInitializationMode()
    if left:  # simulate_fmu validates by default
        raise Exception("The start values for the following variables could not be set: " + ", ".join(left))
    return begin


def steps(run, fmu, times: np.ndarray, vrs: np.ndarray, values: np.ndarray):
    """One call of the entry `run`: the steps between `times`, the outputs `vrs` read into `values`
    (a row per time); (status, steps taken, rows written)."""
    taken, rows = ctypes.c_size_t(0), ctypes.c_size_t(0)
    status = run(fmu.component, times.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), len(times) - 1,
                 vrs.ctypes.data_as(ctypes.POINTER(ctypes.c_uint32)), len(vrs),
                 values.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), ctypes.byref(taken), ctypes.byref(rows))
    return status, taken.value, rows.value


def simulate(filename, model_description, fmu_instance, fmi_type="CoSimulation", stop_time=None, step_size=None,
             output_interval=None, output=None, start_values=None):
    """What `fmpy.simulate_fmu` returns for these arguments (an FMI 2.0 Co-Simulation instance, reset,
    without inputs), with the steps in one call into the library. `filename` and `step_size` are
    FMPy's, unused in Co-Simulation."""
    from fmpy.fmi1 import FMICallException

    description, fmu = model_description, fmu_instance
    if fmi_type != "CoSimulation" or description.fmiVersion != "2.0":
        raise NativeError(f"the native loop runs FMI 2.0 Co-Simulation, not {description.fmiVersion} {fmi_type}")
    names = set(output)
    recorded = [v for v in description.modelVariables if v.name in names and v.name != "time"]  # FMPy's Recorder
    if any(v.type != "Real" for v in recorded):
        raise NativeError(f"the native loop records Real outputs: {', '.join(v.name for v in recorded if v.type != 'Real')} are not")
    run = entry(fmu)
    stop = float(stop_time)
    begin = start(fmu, description, stop, start_values or {})
    times = communication_points(begin, stop, float(output_interval),
                                 bool(description.coSimulation.canHandleVariableCommunicationStepSize))
    vrs = np.array([v.valueReference for v in recorded], dtype=np.uint32)
    values = np.empty((len(times), len(vrs)))
    status, taken, rows = steps(run, fmu, times, vrs, values)
    if status == OK:
        pass
    elif rows == taken:  # a read failed
        raise FMICallException(function="fmi2GetReal", status=status)
    elif status != DISCARD:
        raise FMICallException(function="fmi2DoStep", status=status)
    elif fmu.getBooleanStatus(TERMINATED):  # FMPy keeps what ran and the outputs at the last good time
        times = np.append(times[:rows], fmu.getRealStatus(LAST_SUCCESSFUL_TIME))
        values = np.vstack([values[:rows], fmu.getReal(vrs.tolist())])
    else:  # FMPy reads the outputs, then steps again from the same time, which the FMU refuses
        fmu.getReal(vrs.tolist())
        fmu.doStep(currentCommunicationPoint=float(times[taken]), communicationStepSize=float(times[taken + 1] - times[taken]))
        raise NativeError(f"fmi2DoStep at t = {times[taken]} was taken again after the FMU discarded it")
    fmu.terminate()
    result = np.empty(len(times), dtype=[("time", np.float64)] + [(v.name, np.float64) for v in recorded])
    result["time"] = times
    for j, v in enumerate(recorded):
        result[v.name] = values[:, j]
    return result
