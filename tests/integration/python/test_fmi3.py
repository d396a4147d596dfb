"""The FMI 3.0 FMUs (out/fmi3/): schema and FMPy validation, the terminals,
the archive, FMU states and refused calls through FMPy's FMU3 classes. That
every co-simulation and Model Exchange scene of the FMI 2.0 tests gives
bit-identical outputs through FMI 3.0 is checked by those tests themselves
(conftest.simulate_fmu runs each scene on both FMUs)."""

import xml.etree.ElementTree as ET
from ctypes import c_double
import zipfile
from pathlib import Path

import fmpy
import pytest
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi3 import FMU3Model, FMU3Slave
from fmpy.validation import validate_fmu
from lxml import etree

from conftest import FMU, ROOT, packaged, fmi3_twin

FMU3 = ROOT / "out" / "fmi3" / "ConvertingSpan.fmu"
SCHEMA = Path(fmpy.__file__).parent / "schema" / "fmi3"
# FMI 3.0's platform folder for each FMI 2.0 one (fmu/package.py).
FOLDERS = {"linux64": "x86_64-linux", "win64": "x86_64-windows", "aarch64-linux": "aarch64-linux"}


@pytest.fixture(scope="module")
def fmu3():
    packaged(FMU)
    return packaged(FMU3)


@pytest.fixture(scope="module")
def md3(fmu3):
    return read_model_description(str(fmu3))


def test_fmpy_validation_finds_no_problem(fmu3):
    assert validate_fmu(str(fmu3)) == []


def test_terminals_follow_the_fmi3_schema_and_name_existing_variables(fmu3, md3):
    with zipfile.ZipFile(fmu3) as zf:
        text = zf.read("terminalsAndIcons/terminalsAndIcons.xml")
    schema = etree.XMLSchema(etree.parse(str(SCHEMA / "fmi3TerminalsAndIcons.xsd")))
    document = etree.fromstring(text)
    assert schema.validate(document), schema.error_log
    names = {v.name for v in md3.modelVariables}
    terminals = {t.get("name"): t for t in document.iter("Terminal")}
    assert set(terminals) == {"web_a", "web_b"}
    for name, t in terminals.items():
        assert t.get("terminalKind") == "org.convertingspan.WebPort"
        members = {m.get("memberName"): m.get("variableName") for m in t.iter("TerminalMemberVariable")}
        assert members == {"v": f"{name}.v", "F": f"{name}.F", "eps": f"{name}.eps"}
        assert set(members.values()) <= names


def test_names_units_and_value_references_are_the_fmi2_ones(fmu3, md3):
    md2 = read_model_description(str(FMU))
    three = {v.name: v for v in md3.modelVariables}
    for v in md2.modelVariables:
        w = three[v.name]
        assert (w.valueReference, w.causality, w.variability, w.unit, w.start) == (
            v.valueReference, v.causality, v.variability, v.unit, v.start), v.name
    added = set(three) - {v.name for v in md2.modelVariables}
    assert added == {"time", "eventIndicator1"}
    assert md3.instantiationToken == md2.guid


def test_the_archive_carries_every_platform_of_the_fmi2_fmu(fmu3):
    with zipfile.ZipFile(FMU) as zf:
        fmi2 = {n.split("/")[1]: zf.read(n) for n in zf.namelist() if n.startswith("binaries/")}
    with zipfile.ZipFile(fmu3) as zf:
        fmi3 = {n.split("/")[1]: zf.read(n) for n in zf.namelist() if n.startswith("binaries/")}
        assert "resources/webs.json" in zf.namelist() and "documentation/index.html" in zf.namelist()
    # One library for both APIs: the same bytes under FMI 3.0's folder names.
    assert fmi3 == {FOLDERS[folder]: data for folder, data in fmi2.items()}


def test_the_twin_of_the_scene_tests_is_the_fmi3_fmu():
    root = ET.parse(Path(fmi3_twin(FMU)) / "modelDescription.xml").getroot()
    assert root.get("fmiVersion") == "3.0"


class Log:
    def __init__(self):
        self.messages = []

    def __call__(self, environment, status, category, message):
        self.messages.append(message.decode())


def slave(md3, unzipdir, log):
    fmu = FMU3Slave(guid=md3.instantiationToken, unzipDirectory=unzipdir,
                    modelIdentifier=md3.coSimulation.modelIdentifier, instanceName="span3")
    fmu.instantiate(logMessage=log)
    return fmu


@pytest.fixture(scope="module")
def unzipdir3(fmu3):
    return fmpy.extract(str(fmu3))


def test_fmu_state_save_restore_serialize_deserialize(md3, unzipdir3):
    """A state saved at t = 0.5, restored (directly and through bytes),
    continues bit-identically to the uninterrupted run."""
    vr = {v.name: v.valueReference for v in md3.modelVariables}
    outputs = [vr[n] for n in ("T", "web_b.eps", "unstretchedLength", "time")]
    fmu = slave(md3, unzipdir3, Log())
    fmu.enterInitializationMode(startTime=0.0)
    fmu.setFloat64([vr["web_b.v"]], [5.01])
    fmu.exitInitializationMode()
    t, h = 0.0, 0.01
    for _ in range(50):
        fmu.doStep(t, h)
        t += h
    state = fmu.getFMUState()
    serialized = fmu.serializeFMUState(state)
    reference = []
    for k in range(50):
        fmu.doStep(t + k * h, h)
        reference.append(fmu.getFloat64(outputs))
    for restore in ("direct", "bytes"):
        if restore == "direct":
            fmu.setFMUState(state)
        else:
            copy = fmu.deserializeFMUState(serialized)
            fmu.setFMUState(copy)
            fmu.freeFMUState(copy)
        again = []
        for k in range(50):
            fmu.doStep(t + k * h, h)
            again.append(fmu.getFloat64(outputs))
        assert again == reference, restore
    fmu.freeFMUState(state)
    fmu.terminate()
    fmu.freeInstance()


def before_initialization(call):
    call.before = True
    return call


@pytest.mark.parametrize("call, needle", [
    (lambda f, vr: f.setFloat64([vr["L"]], [-1.0]), "fmi3SetFloat64: cannot set L: it is a fixed parameter and cannot be set in Step Mode"),
    (before_initialization(lambda f, vr: f.setInt64([vr["toUnitV"]], [99])), "toUnitV = 99"),
    (before_initialization(lambda f, vr: f.exitInitializationMode()), "fmi3ExitInitializationMode: illegal call sequence"),
    (lambda f, vr: f.setFloat64([vr["web_a.v"]], [float("nan")]), "web_a.v = NaN"),
    (lambda f, vr: f.setInt32([vr["toUnitV"]], [1]), "is of type Int64 (an enumeration), not Int32"),
    (lambda f, vr: f.getFloat64([999]), "fmi3GetFloat64: unknown value reference 999"),
    (lambda f, vr: f.setFloat64([0], [1.0]), "time (the independent variable): it can only be read"),
    (lambda f, vr: f.doStep(5.0, 0.1), "fmi3DoStep: currentCommunicationPoint = 5"),
    (lambda f, vr: f.doStep(0.0, -0.1), "communicationStepSize = -0.1"),
    (lambda f, vr: f.enterEventMode(), "hasEventMode is false"),
    (lambda f, vr: f.getDirectionalDerivative([vr["T"]], [vr["L"]], [1.0]), "fmi3GetDirectionalDerivative: "),
    (lambda f, vr: f.enterConfigurationMode(), "no structural parameters"),
])
def test_bad_calls_are_refused_with_a_message_and_reset_recovers(md3, unzipdir3, call, needle):
    vr = {v.name: v.valueReference for v in md3.modelVariables}
    log = Log()
    fmu = slave(md3, unzipdir3, log)
    if not getattr(call, "before", False):
        fmu.enterInitializationMode(startTime=0.0)
        fmu.exitInitializationMode()
    with pytest.raises(FMICallException):
        call(fmu, vr)
    assert any(needle in m for m in log.messages), log.messages
    assert not any("fmi2" in m for m in log.messages), log.messages
    fmu.reset()
    fmu.enterInitializationMode(startTime=0.0)
    fmu.exitInitializationMode()
    fmu.doStep(0.0, 0.1)
    assert fmu.getFloat64([0]) == [0.1]
    fmu.freeInstance()


def test_directional_derivatives_equal_the_fmi2_ones(md3, unzipdir3, unzipdir):
    """The same partial derivatives through both APIs, bit for bit, after the same steps."""
    from fmpy.fmi2 import FMU2Slave

    md2 = read_model_description(unzipdir)
    vr = {v.name: v.valueReference for v in md3.modelVariables}
    unknowns, knowns = [vr["T"], vr["web_b.F"]], [vr["web_a.v"], vr["web_b.v"], vr["web_a.eps"]]
    two = FMU2Slave(guid=md2.guid, unzipDirectory=unzipdir, modelIdentifier="ConvertingSpan", instanceName="d2")
    two.instantiate()
    two.setupExperiment(startTime=0.0)
    # Damping makes the tension depend on the speeds at once: non-zero derivatives.
    two.setBoolean([vr["includeDamping"]], [True])
    two.enterInitializationMode()
    two.exitInitializationMode()
    three = slave(md3, unzipdir3, Log())
    three.setBoolean([vr["includeDamping"]], [True])
    three.enterInitializationMode(startTime=0.0)
    three.exitInitializationMode()
    for k in range(10):
        two.doStep(k * 0.01, 0.01)
        three.doStep(k * 0.01, 0.01)
    for seed in ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.3, -2.0, 5.0]):
        d2 = two.getDirectionalDerivative(unknowns, knowns, seed)
        d3 = three.getDirectionalDerivative(unknowns, knowns, seed)
        assert list(d2) == list(d3) and any(x != 0 for x in d3), seed
    two.freeInstance()
    three.freeInstance()


@pytest.mark.parametrize("name", ["ConvertingSpan", "Roller"])
def test_both_models_validate_and_have_the_web_ports(name):
    fmu = packaged(ROOT / "out" / "fmi3" / f"{name}.fmu")
    assert validate_fmu(str(fmu)) == []
    with zipfile.ZipFile(fmu) as zf:
        document = etree.fromstring(zf.read("terminalsAndIcons/terminalsAndIcons.xml"))
    schema = etree.XMLSchema(etree.parse(str(SCHEMA / "fmi3TerminalsAndIcons.xsd")))
    assert schema.validate(document), schema.error_log
    # The Roller's extra inlets and outlets are web ports too.
    ports = ["web_a", "web_b"] + ([f"web_{end}{k}" for end in "ab" for k in (2, 3, 4)] if name == "Roller" else [])
    assert {(t.get("name"), t.get("terminalKind")) for t in document.iter("Terminal")} == {
        (port, "org.convertingspan.WebPort") for port in ports}


def test_model_exchange_reports_its_sizes_and_refuses_co_simulation_calls(md3, unzipdir3):
    log = Log()
    fmu = FMU3Model(guid=md3.instantiationToken, unzipDirectory=unzipdir3,
                    modelIdentifier=md3.modelExchange.modelIdentifier, instanceName="span3me")
    fmu.instantiate(logMessage=log)
    assert fmu.getNumberOfContinuousStates() == 1 and fmu.getNumberOfEventIndicators() == 1
    fmu.enterInitializationMode(startTime=0.0)
    fmu.exitInitializationMode()
    fmu.updateDiscreteStates()
    fmu.enterContinuousTimeMode()
    z = (c_double * 1)()
    fmu.getEventIndicators(z, 1)
    indicator = md3.eventIndicators[0].variable.valueReference
    assert fmu.getFloat64([indicator]) == [z[0]]
    with pytest.raises(FMICallException):
        fmu.fmi3DoStep(fmu.component, 0.0, 0.1, False, None, None, None, None)
    assert any("a Co-Simulation function, and this is a Model Exchange instance" in m for m in log.messages)
    fmu.freeInstance()
