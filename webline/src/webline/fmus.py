"""The two FMUs of a line, loaded with FMPy: one `Instance` per component.

`FmuFile` extracts an FMU once and reads its model description (the
enumerations a scene names, such as the span's solvers, come from there:
`enumeration`; so do the span's effects: `span_effects`); `Instance`
is one FMPy `FMU2Slave` with preallocated ctypes buffers for the calls made
every communication step, an FMU state slot for rollbacks, and the FMU's log
messages kept so that a failed call can say why.
"""

from __future__ import annotations

import atexit
import os
import shutil
import tempfile
import zipfile
from ctypes import byref
from functools import lru_cache
from pathlib import Path

from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import (
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
    fmi2FMUstate,
    fmi2Integer,
    fmi2Real,
    fmi2ValueReference,
)
from fmpy import calloc, free
from lxml import etree

from .installation import CHECKOUT, FMU_DIR

# The repository's out/ in a checkout, the wheel's data when installed (installation.py).
DEFAULT_FMU_DIR = FMU_DIR
SPAN_FMU = "ConvertingSpan.fmu"
ROLLER_FMU = "Roller.fmu"

OK, WARNING, DISCARD = 0, 1, 2
# The span's model-level annotation that names its effects: the Boolean parameters
# that switch a physical effect on (not every Boolean parameter is one).
EFFECTS_TOOL = "ConvertingSpan.effects"


class FmuError(RuntimeError):
    """An FMU call failed with fmi2Error or fmi2Fatal; the message carries the FMU's log."""


def enumeration(md, variable: str) -> dict:
    """The items of an Enumeration variable's type in a model description: name -> value."""
    v = next((v for v in md.modelVariables if v.name == variable), None)
    if v is None or v.declaredType is None or not v.declaredType.items:
        raise FmuError(f"{md.modelName} has no Enumeration variable {variable!r}")
    return {item.name: int(item.value) for item in v.declaredType.items}


@lru_cache(maxsize=8)
def _read(path: str, mtime: float):
    return read_model_description(path)


def _span_path(fmu_dir=None) -> Path:
    """The FMU in `fmu_dir` (DEFAULT_FMU_DIR by default); in a checkout, without a `fmu_dir` and
    before the FMUs are built, the repository's modelDescription.xml, which the FMU is packaged from."""
    path = Path(fmu_dir or DEFAULT_FMU_DIR) / SPAN_FMU
    if not path.exists() and fmu_dir is None and CHECKOUT and (CHECKOUT / "modelDescription.xml").exists():
        path = CHECKOUT / "modelDescription.xml"
    if not path.exists():
        raise FileNotFoundError(f"{path} is missing: build the FMUs first with `python3 fmu/package.py`")
    return path


def span_description(fmu_dir=None):
    """ConvertingSpan's model description (see `_span_path` for which one)."""
    path = _span_path(fmu_dir)
    return _read(str(path), os.path.getmtime(path))


def span_effects(fmu_dir=None) -> tuple:
    """ConvertingSpan's effects, from the same model description as `span_description`."""
    path = _span_path(fmu_dir)
    return _effects(str(path), os.path.getmtime(path))


def effects(path) -> tuple:
    """The effects a span's model description (a .fmu or a modelDescription.xml) names in
    its `EFFECTS_TOOL` annotation, in its order; each must be a Boolean parameter."""
    return _effects(str(path), os.path.getmtime(path))


@lru_cache(maxsize=8)
def _effects(path: str, mtime: float) -> tuple:
    if path.endswith(".fmu"):
        with zipfile.ZipFile(path) as z:
            text = z.read("modelDescription.xml")
    else:
        text = Path(path).read_bytes()
    root = etree.fromstring(text, etree.XMLParser(resolve_entities=False, no_network=True))
    names = tuple(e.get("variable") for e in root.iterfind(f"VendorAnnotations/Tool[@name='{EFFECTS_TOOL}']/Effects/Effect"))
    if not names:
        raise FmuError(f"{path} names no effects (annotation {EFFECTS_TOOL}): an FMU built before it? "
                       "Rebuild the FMUs with `python3 fmu/package.py`")
    booleans = {v.get("name") for v in root.iterfind("ModelVariables/ScalarVariable[@causality='parameter']")
                if v.find("Boolean") is not None}
    for name in names:
        if name not in booleans:
            raise FmuError(f"{path}: {EFFECTS_TOOL} names {name!r}, which is not a Boolean parameter")
    return names


# What an FMU carries to say which it is, as its modelDescription.xml names them (FMI 2.0's guid is
# FMI 3.0's instantiationToken).
IDENTITY = ("modelName", "fmiVersion", "version", "guid", "instantiationToken", "generationTool", "generationDateAndTime")


def identity(path) -> dict:
    """An FMU's identity (a .fmu file): its file name and the attributes of IDENTITY that it gives."""
    with zipfile.ZipFile(path) as z:
        root = etree.fromstring(z.read("modelDescription.xml"), etree.XMLParser(resolve_entities=False, no_network=True))
    return {"file": Path(path).name, **{k: root.get(k) for k in IDENTITY if root.get(k) is not None}}


class FmuFile:
    """An extracted FMU and its variables."""

    _cache: dict = {}

    def __init__(self, path: Path):
        self.path = Path(path)
        if not self.path.exists():
            raise FileNotFoundError(
                f"{self.path} is missing: build the FMUs first with `python3 fmu/package.py`"
            )
        self.md = read_model_description(str(self.path))
        self.unzipdir = extract(str(self.path), unzipdir=tempfile.mkdtemp(prefix=f"webline-{self.path.stem}-"))
        atexit.register(shutil.rmtree, self.unzipdir, True)
        self.variables = {v.name: v for v in self.md.modelVariables}

    @classmethod
    def load(cls, path) -> "FmuFile":
        key = (str(Path(path).resolve()), os.path.getmtime(path) if os.path.exists(path) else 0)
        if key not in cls._cache:
            cls._cache[key] = cls(Path(path))
        return cls._cache[key]

    def vr(self, name: str) -> int:
        return self.variables[name].valueReference

    def enumeration(self, variable: str) -> dict:
        return enumeration(self.md, variable)

    def can_interpolate_inputs(self) -> bool:
        return bool(self.md.coSimulation.canInterpolateInputs)


class Instance:
    """One FMU instance, initialized in `begin`/`end_initialization`."""

    def __init__(self, fmu: FmuFile, name: str, inputs, outputs):
        self.file = fmu
        self.name = name
        self.messages: list[str] = []
        self.slave = FMU2Slave(
            guid=fmu.md.guid,
            unzipDirectory=fmu.unzipdir,
            modelIdentifier=fmu.md.coSimulation.modelIdentifier,
            instanceName=name,
        )
        self._callbacks = fmi2CallbackFunctions()
        self._callbacks.logger = fmi2CallbackLoggerTYPE(self._log)
        self._callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        self._callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        self.slave.instantiate(callbacks=self._callbacks)
        self.component = self.slave.component
        self.n_in = len(inputs)
        self.n_out = len(outputs)
        self.in_vr = (fmi2ValueReference * self.n_in)(*[fmu.vr(n) for n in inputs])
        self.out_vr = (fmi2ValueReference * self.n_out)(*[fmu.vr(n) for n in outputs])
        self.in_val = (fmi2Real * self.n_in)()
        self.in_der = (fmi2Real * self.n_in)()
        self.orders = (fmi2Integer * self.n_in)(*([1] * self.n_in))
        self.out_val = (fmi2Real * self.n_out)()
        self.state = None
        self.freed = False

    def _log(self, env, instance, status, category, message):
        self.messages.append(message.decode("utf-8", "replace"))

    def _check(self, what, call):
        try:
            return call()
        except FMICallException as e:
            if e.status == DISCARD:
                return DISCARD
            last = self.messages[-1] if self.messages else "(no message)"
            raise FmuError(f"{self.name}: {what} failed: {last}") from None

    def begin(self, start_values: dict, tolerance, start_time, stop_time):
        """fmi2SetupExperiment, start values, fmi2EnterInitializationMode."""
        s = self.slave
        self._check("fmi2SetupExperiment", lambda: s.setupExperiment(tolerance=tolerance, startTime=start_time, stopTime=stop_time))
        reals, ints, bools, texts = [], [], [], []
        for name, value in start_values.items():
            if name not in self.file.variables:
                raise FmuError(f"{self.name}: the FMU has no variable {name!r}")
            v = self.file.variables[name]
            if v.type == "Real":
                reals.append((v.valueReference, float(value)))
            elif v.type == "Boolean":
                bools.append((v.valueReference, bool(value)))
            elif v.type == "String":
                texts.append((v.valueReference, str(value)))
            else:
                ints.append((v.valueReference, int(value)))
        if reals:
            self._check("setting parameters", lambda: s.setReal([r[0] for r in reals], [r[1] for r in reals]))
        if ints:
            self._check("setting parameters", lambda: s.setInteger([r[0] for r in ints], [r[1] for r in ints]))
        if bools:
            self._check("setting parameters", lambda: s.setBoolean([r[0] for r in bools], [r[1] for r in bools]))
        if texts:
            self._check("setting parameters", lambda: s.setString([r[0] for r in texts], [r[1] for r in texts]))
        self._check("fmi2EnterInitializationMode", s.enterInitializationMode)

    def end_initialization(self):
        self._check("fmi2ExitInitializationMode", self.slave.exitInitializationMode)

    def set_inputs(self, values):
        for i, x in enumerate(values):
            self.in_val[i] = x
        self._check("fmi2SetReal", lambda: self.slave.fmi2SetReal(self.component, self.in_vr, self.n_in, self.in_val))

    def set_input_derivatives(self, values):
        for i, x in enumerate(values):
            self.in_der[i] = x
        self._check(
            "fmi2SetRealInputDerivatives",
            lambda: self.slave.fmi2SetRealInputDerivatives(self.component, self.in_vr, self.n_in, self.orders, self.in_der),
        )

    def outputs(self):
        self._check("fmi2GetReal", lambda: self.slave.fmi2GetReal(self.component, self.out_vr, self.n_out, self.out_val))
        return list(self.out_val)

    def get(self, name) -> float:
        return self.slave.getReal([self.file.vr(name)])[0]

    def do_step(self, t, h) -> bool:
        """True when the step succeeded, False when the FMU discarded it."""
        status = self._check("fmi2DoStep", lambda: self.slave.fmi2DoStep(self.component, t, h, 0))
        return status != DISCARD

    def save(self):
        if self.state is None:
            self.state = fmi2FMUstate()
        self._check("fmi2GetFMUstate", lambda: self.slave.fmi2GetFMUstate(self.component, byref(self.state)))

    def restore(self):
        self._check("fmi2SetFMUstate", lambda: self.slave.fmi2SetFMUstate(self.component, self.state))

    def free(self):
        if self.freed:
            return
        self.freed = True
        try:
            if self.state is not None:
                self.slave.fmi2FreeFMUstate(self.component, byref(self.state))
            self.slave.terminate()
        except FMICallException:
            pass
        self.slave.freeInstance()
