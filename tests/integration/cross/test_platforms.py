"""Every platform's binary in the FMUs, run here: Windows x64 under Wine,
ARM64 Linux under QEMU, x86-64 Linux natively, each driven by the same C
importer (tests/integration/c_importer/importer.c, compiled for the platform).

The Linux x86-64 binary is the reference (test_c_importer.py and the other
tests check it against exact solutions); every other platform must give the
same bits for every output of every step, the same status for every call
and the same log messages. A difference, if a platform's math library ever
rounds otherwise, may be at most 1e-14 relative: the test names the variable
and the size. (None does today: the solvers take expm1 and pow from the
libm crate, not from the platform's C library; docs/platforms.md.) The scenes
cover every solver and effect of the span, every sensor unit, bad inputs,
the panic boundary (a test-hooks build per platform) and FMU states
serialized on one platform and deserialized on every other.

    bash tests/integration/cross.sh      (runs this after the Rust tests under Wine and QEMU)

Needs the tools of fmu/env.sh (tests/integration/cross.sh sources it): mingw-w64 and
aarch64 gcc, Wine (WINEPREFIX with the test-only ProcessPrng shim) and QEMU.
"""

import math
import os
import re
import struct
import subprocess
import sys
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import fmpy
import pytest

ROOT = Path(__file__).resolve().parents[3]
SOURCE = ROOT / "tests" / "integration" / "c_importer" / "importer.c"
SOURCE3 = ROOT / "tests" / "integration" / "c_importer" / "importer3.c"
HEADERS = Path(fmpy.__file__).resolve().parent / "c-code"
OUT = ROOT / "out"
SUMMARY = ROOT / "target" / "platforms" / "summary.txt"
REFERENCE = "linux64"
# At most this far from the reference where a platform's libm rounds otherwise (none does today).
REL_TOL = 1e-14


class Platform:
    def __init__(self, folder, compiler, runner, suffix, target=None):
        self.folder = folder
        self.compiler = compiler  # the C compiler and its platform flags
        self.runner = runner  # the emulator, if any
        self.suffix = suffix
        self.target = target  # cargo target of the cross builds


PLATFORMS = [
    Platform("linux64", ["gcc"], [], ".so"),
    # ANSI stdio: printf formats doubles as glibc does (%.17g round-trips on both).
    Platform("win64", ["x86_64-w64-mingw32-gcc", "-D__USE_MINGW_ANSI_STDIO=1"], ["/usr/lib/wine/wine64"], ".dll",
             "x86_64-pc-windows-gnu"),
    Platform("aarch64-linux", ["aarch64-linux-gnu-gcc"], ["qemu-aarch64-static"], ".so", "aarch64-unknown-linux-gnu"),
]
BY_FOLDER = {p.folder: p for p in PLATFORMS}
OTHERS = [p.folder for p in PLATFORMS if p.folder != REFERENCE]
MODELS = ["ConvertingSpan", "Roller"]


def bits(value):
    """The 16 hex digits of a double's bits, as importer.c --script reads values."""
    return format(struct.unpack("<Q", struct.pack("<d", value))[0], "016x")


def from_bits(text):
    return struct.unpack("<d", struct.pack("<Q", int(text, 16)))[0]


# --------------------------------------------------------------------------
# Fixtures: the importers, the FMUs' binaries, running a scene


@pytest.fixture(scope="session", autouse=True)
def cross_tools():
    if "WINEPREFIX" not in os.environ or "CROSS_CARGO" not in os.environ:
        pytest.fail("the cross tools are not set up: run through tests/run.sh, or `source fmu/env.sh` first")


def build_importers(source, folder):
    """{platform folder: the C importer `source` compiled for it}."""
    built = {}
    for p in PLATFORMS:
        exe = folder / f"{source.stem}-{p.folder}{'.exe' if p.suffix == '.dll' else ''}"
        libs = [] if p.suffix == ".dll" else ["-ldl"]
        build = subprocess.run([*p.compiler, "-Wall", "-Werror", "-O1", "-I", str(HEADERS), str(source), "-o", str(exe), *libs],
                               capture_output=True, text=True)
        assert build.returncode == 0 and build.stderr == "", f"{p.folder}: {source.name} does not compile cleanly:\n{build.stderr}"
        built[p.folder] = exe
    return built


@pytest.fixture(scope="session")
def importers(tmp_path_factory):
    return build_importers(SOURCE, tmp_path_factory.mktemp("importers"))


@pytest.fixture(scope="session")
def importers3(tmp_path_factory):
    return build_importers(SOURCE3, tmp_path_factory.mktemp("importers3"))


@pytest.fixture(scope="session")
def binaries(tmp_path_factory):
    """{(model, platform folder): path of the packaged library}; every FMU carries every platform."""
    folder = tmp_path_factory.mktemp("binaries")
    found = {}
    for model in MODELS:
        fmu = OUT / f"{model}.fmu"
        assert fmu.exists(), f"{fmu} is missing: run python3 fmu/package.py"
        with zipfile.ZipFile(fmu) as zf:
            for p in PLATFORMS:
                name = f"binaries/{p.folder}/{model}{p.suffix}"
                assert name in zf.namelist(), f"{fmu.name} lacks {name}"
                path = folder / p.folder / f"{model}{p.suffix}"
                path.parent.mkdir(exist_ok=True)
                path.write_bytes(zf.read(name))
                found[model, p.folder] = path
    return found


@pytest.fixture(scope="session")
def descriptions():
    """{model: (guid, {name: (vr, type element)})}."""
    out = {}
    for model, path in (("ConvertingSpan", ROOT / "modelDescription.xml"), ("Roller", ROOT / "models/roller/modelDescription.xml")):
        root = ET.parse(path).getroot()
        variables = {v.get("name"): v for v in root.iter("ScalarVariable")}
        out[model] = (root.get("guid"), variables)
    return out


def run(importers, platform, library, guid, args, tmp_path, timeout=300):
    p = BY_FOLDER[platform]
    proc = subprocess.run([*p.runner, str(importers[platform]), str(library), guid, *args],
                          capture_output=True, text=True, timeout=timeout, cwd=tmp_path)
    # Windows' C runtime writes \r\n; text=True already reads it as \n.
    return proc


def run_script(importers, platform, library, guid, script, tmp_path):
    path = tmp_path / f"scene-{platform}.txt"
    path.write_text(script)
    proc = run(importers, platform, library, guid, ["--script", str(path)], tmp_path)
    assert proc.returncode == 0, f"{platform}: importer exit {proc.returncode}\n{proc.stderr[-3000:]}"
    return proc


def log_lines(stderr):
    return [line for line in stderr.splitlines() if line.startswith("log,")]


def largest_difference(reference, other):
    """(largest relative difference, where) between two runs' out lines; 0.0 if bit-identical."""
    worst, where = 0.0, None
    ref_lines = [l for l in reference.splitlines() if l.startswith("out,")]
    other_lines = [l for l in other.splitlines() if l.startswith("out,")]
    assert len(ref_lines) == len(other_lines)
    for a, b in zip(ref_lines, other_lines):
        fa, fb = a.split(","), b.split(",")
        assert fa[:3] == fb[:3]
        for i, (x, y) in enumerate(zip(fa[3:], fb[3:])):
            if x != y:
                u, v = from_bits(x), from_bits(y)
                rel = abs(u - v) / max(abs(u), abs(v)) if not (math.isnan(u) or math.isnan(v)) else math.inf
                if rel > worst:
                    worst, where = rel, (a.split(",")[1], a.split(",")[2], i)
    return worst, where


def record(line):
    SUMMARY.parent.mkdir(parents=True, exist_ok=True)
    with SUMMARY.open("a") as f:
        f.write(line + "\n")


# --------------------------------------------------------------------------
# The scenes, written from the model descriptions


class Scene:
    """A script for importer.c --script, value references looked up by name."""

    def __init__(self, variables):
        self.vars = variables
        self.lines = []

    def vr(self, name):
        return self.vars[name].get("valueReference")

    def add(self, *words):
        self.lines.append(" ".join(str(w) for w in words))

    def set(self, name, value):
        kind = self.vars[name][0].tag
        if kind == "Real":
            self.add("real", self.vr(name), bits(float(value)))
        elif kind == "Boolean":
            self.add("boolean", self.vr(name), int(bool(value)))
        else:
            self.add("integer", self.vr(name), int(value))

    def outputs(self):
        names = [n for n, v in self.vars.items() if v.get("causality") == "output" and v[0].tag == "Real"]
        self.add("outputs", *(self.vr(n) for n in names))

    def start(self, name, parameters=(), stop=10.0):
        self.add("instance", name)
        self.add("setup", bits(stop))
        for key, value in parameters:
            self.set(key, value)
        self.add("enter")
        self.add("exit")
        self.outputs()

    def steps(self, n, h=1e-3):
        self.add("steps", n, bits(h))

    def text(self):
        return "\n".join(self.lines) + "\n"


SOLVERS = range(1, 7)  # auto, exact, rosenbrock, dopri5, rk4, euler
SPAN_EFFECTS = {
    "damping": [("includeDamping", True), ("wp2.d_r", 0.01)],
    "mass and variable length": [("includeMass", True), ("variableLength", True)],
    "no negative tension": [("preventNegativeTension", True)],
    "off equilibrium, raw strain": [("startAtEquilibrium", False), ("eps_start", 2e-3), ("useSensor", False)],
}


def span_scene(variables):
    s = Scene(variables)
    for solver in SOLVERS:
        for effect, parameters in SPAN_EFFECTS.items():
            s.start(f"solver{solver}-{effect.replace(' ', '_').replace(',', '')}", [("solver", solver), *parameters])
            s.steps(200)
            # an input step and, for the variable length, a moving roller
            s.set("web_b.v", 4.9 if effect == "no negative tension" else 5.005)
            if effect == "mass and variable length":
                # off the axis: the length goes through hypot, the platform's libm
                s.set("frame_b.x", 1.02)
                s.set("frame_b.y", 0.013)
            s.steps(200)
            s.add("free")
    for unit in range(1, 7):
        s.start(f"units{unit}", [("toUnitV", unit), ("toUnitF", unit), ("includeDamping", True)])
        s.steps(20)
        s.set("web_b.v", 5.01)
        s.steps(20)
        s.add("free")
    return s.text()


def roller_scene(variables):
    s = Scene(variables)
    for b in (0.0, 0.02):
        s.start(f"roller-b{b}", [("b", b), ("J", 0.07)])
        s.set("web_a.F", 120.0)
        s.set("web_b.F", 80.0)
        s.steps(300)
        s.set("tau_m", -1.5)
        s.steps(300)
        s.add("free")
    return s.text()


SCENES = {"ConvertingSpan": span_scene, "Roller": roller_scene}


def bad_scene(variables):
    """Every settable Real gets NaN and +inf, every bounded one a value past its
    bound, every enumeration one past its last item: all refused, one log line each."""
    s = Scene(variables)
    s.add("instance", "bad")
    count = 0
    for name, v in variables.items():
        if v.get("causality") not in ("parameter", "input"):
            continue
        t = v[0]
        if t.tag == "Real":
            values = [math.nan, math.inf]
            if t.get("min") is not None:
                values.append(float(t.get("min")) - 1.0)
            if t.get("max") is not None:
                values.append(float(t.get("max")) + 1.0)
        elif t.tag in ("Enumeration", "Integer") and t.get("max") is not None:
            values = [int(t.get("max")) + 1]
        elif t.tag == "Enumeration":
            values = [0]
        elif t.tag == "Integer":
            values = [-1]
        else:
            continue
        for value in values:
            s.set(name, value)
            count += 1
    s.add("free")
    return s.text(), count


# --------------------------------------------------------------------------
# Tests


@pytest.mark.parametrize("platform", OTHERS)
def test_the_c_importers_scene_is_bit_identical(importers, binaries, descriptions, platform, tmp_path):
    """importer.c's own scene (state save/restore, serialization, illegal
    calls): the same output text, statuses and log messages as Linux x86-64."""
    sys.path.insert(0, str(ROOT / "tests" / "integration" / "python"))
    from test_c_importer import NAMES

    guid, variables = descriptions["ConvertingSpan"]
    args = [f"{n}={variables[n].get('valueReference')}" for n in NAMES]
    results = {}
    for folder in (REFERENCE, platform):
        proc = run(importers, folder, binaries["ConvertingSpan", folder], guid, args, tmp_path)
        assert proc.returncode == 0, f"{folder}: exit {proc.returncode}\n{proc.stderr[-3000:]}"
        results[folder] = proc
    assert results[platform].stdout == results[REFERENCE].stdout
    assert log_lines(results[platform].stderr) == log_lines(results[REFERENCE].stderr)


# FMI 3.0's names of the platform folders.
FMI3_FOLDERS = {"linux64": "x86_64-linux", "win64": "x86_64-windows", "aarch64-linux": "aarch64-linux"}


@pytest.mark.parametrize("platform", OTHERS)
def test_the_fmi3_importers_scene_is_bit_identical(importers3, platform, tmp_path):
    """importer3.c's scene through the FMI 3.0 FMU (importer.c's scene, FMU
    states, refused calls): the same output text and log lines as Linux x86-64."""
    sys.path.insert(0, str(ROOT / "tests" / "integration" / "python"))
    from test_c_importer import NAMES

    fmu = OUT / "fmi3" / "ConvertingSpan.fmu"
    assert fmu.exists(), f"{fmu} is missing: run python3 fmu/package.py"
    with zipfile.ZipFile(fmu) as zf:
        root = ET.fromstring(zf.read("modelDescription.xml"))
        vrs = {v.get("name"): v.get("valueReference") for v in root.find("ModelVariables")}
        results = {}
        for folder in (REFERENCE, platform):
            p = BY_FOLDER[folder]
            library = tmp_path / f"{folder}{p.suffix}"
            library.write_bytes(zf.read(f"binaries/{FMI3_FOLDERS[folder]}/ConvertingSpan{p.suffix}"))
            proc = run({folder: importers3[folder]}, folder, library, root.get("instantiationToken"),
                       [f"{n}={vrs[n]}" for n in NAMES], tmp_path)
            assert proc.returncode == 0, f"{folder}: exit {proc.returncode}\n{proc.stderr[-3000:]}"
            results[folder] = proc
    assert "row," in results[platform].stdout
    assert results[platform].stdout == results[REFERENCE].stdout
    # (Messages naming a foreign FMU state print its address, which differs.)
    logs = {f: [re.sub(r"0x[0-9a-fA-F]+", "0x...", l) for l in log_lines(r.stderr)] for f, r in results.items()}
    assert logs[platform] == logs[REFERENCE]


@pytest.mark.parametrize("model", MODELS)
def test_every_solver_effect_and_unit_gives_the_same_bits(importers, binaries, descriptions, model, tmp_path):
    guid, variables = descriptions[model]
    script = SCENES[model](variables)
    results = {p.folder: run_script(importers, p.folder, binaries[model, p.folder], guid, script, tmp_path) for p in PLATFORMS}
    reference = results[REFERENCE]
    calls = [l for l in reference.stdout.splitlines() if l.startswith("call,")]
    failed = [l for l in calls if not l.endswith(",0")]
    assert not failed, f"{model}: calls of the scene failed on Linux x86-64: {failed}\n{reference.stderr[-2000:]}"
    steps = sum(1 for l in reference.stdout.splitlines() if l.startswith("out,"))
    for folder in OTHERS:
        other = results[folder]
        assert [l for l in other.stdout.splitlines() if l.startswith("call,")] == calls
        assert log_lines(other.stderr) == log_lines(reference.stderr)
        worst, where = largest_difference(reference.stdout, other.stdout)
        record(f"{model} on {folder}: {steps} steps, largest relative difference to linux64 {worst:.3g}"
               + (f" (script line, step, output index: {where})" if where else " (bit-identical)"))
        assert worst <= REL_TOL, f"{model} on {folder}: {worst:.3g} relative at {where}"


@pytest.mark.parametrize("model", MODELS)
def test_bad_inputs_are_refused_with_the_same_messages(importers, binaries, descriptions, model, tmp_path):
    guid, variables = descriptions[model]
    script, count = bad_scene(variables)
    results = {p.folder: run_script(importers, p.folder, binaries[model, p.folder], guid, script, tmp_path) for p in PLATFORMS}
    reference = results[REFERENCE]
    sets = [l for l in reference.stdout.splitlines() if l.startswith("call,") and l.split(",")[2] in ("real", "integer", "boolean")]
    assert len(sets) == count
    accepted = [script.splitlines()[int(l.split(",")[1]) - 1] for l in sets if not l.endswith(",3")]
    assert not accepted, f"{model}: bad values not refused with fmi2Error: {accepted}"
    errors = [l for l in log_lines(reference.stderr) if ",3,logStatusError," in l]
    assert len(errors) >= count, "a refusal without its log line"
    for folder in OTHERS:
        assert results[folder].stdout == reference.stdout
        assert log_lines(results[folder].stderr) == log_lines(reference.stderr)


@pytest.mark.parametrize("model", MODELS)
def test_an_fmu_state_saved_on_one_platform_continues_on_every_other(importers, binaries, descriptions, model, tmp_path):
    """The serialized state is little-endian on every platform: the bytes
    saved on each platform are the same, and each platform continues from
    each platform's state with the same bits as Linux x86-64 continuing its own."""
    guid, variables = descriptions[model]
    first = Scene(variables)
    if model == "ConvertingSpan":
        first.start("save", [("solver", 3), ("includeDamping", True), ("includeMass", True)])
    else:
        first.start("save", [("b", 0.02)])
        first.set("web_a.F", 100.0)
    first.steps(150)
    saved = {}
    for p in PLATFORMS:
        state = tmp_path / f"state-{p.folder}.bin"
        run_script(importers, p.folder, binaries[model, p.folder], guid, first.text() + f"save {state}\n", tmp_path)
        saved[p.folder] = state
    for folder in OTHERS:
        assert saved[folder].read_bytes() == saved[REFERENCE].read_bytes(), f"{model}: {folder} saved another state"
    continuations = {}
    for p in PLATFORMS:
        for origin, state in saved.items():
            second = Scene(variables)
            second.start("load")
            second.add("load", state, bits(150 * 1e-3))  # the saved instance's time
            second.steps(150)
            proc = run_script(importers, p.folder, binaries[model, p.folder], guid, second.text(), tmp_path)
            continuations[p.folder, origin] = proc.stdout
    reference = continuations[REFERENCE, REFERENCE]
    calls = [l for l in reference.splitlines() if l.startswith("call,")]
    assert all(l.endswith(",0") for l in calls), reference[-2000:]
    worst_of_all = 0.0
    for (platform, origin), text in continuations.items():
        assert [l for l in text.splitlines() if l.startswith("call,")] == calls, (platform, origin)
        worst, where = largest_difference(reference, text)
        worst_of_all = max(worst_of_all, worst)
        assert worst <= REL_TOL, f"{model}: state saved on {origin}, continued on {platform}: {worst:.3g} at {where}"
    record(f"{model} FMU state across platforms (3 x 3 save/continue pairs): largest relative difference {worst_of_all:.3g}")


def panic_libraries():
    """The span's library with the test-only panic hook, per platform (not shipped);
    the cross builds share tests/integration/cross.sh's target directory and profile."""
    libraries = {}
    for p in PLATFORMS:
        if p.target is None:
            command = ["cargo", "build", "--profile", "cross-test", "--lib", "--quiet", "--features", "test-hooks", "-p", "converting-span",
                       "--target-dir", str(ROOT / "target" / "test-hooks")]
            libraries[p.folder] = ROOT / "target" / "test-hooks" / "cross-test" / "libconverting_span.so"
        else:
            command = [os.environ["CROSS_CARGO"], "build", "--profile", "cross-test", "--lib", "--quiet", "--features", "test-hooks",
                       "-p", "converting-span", "--target", p.target,
                       "--target-dir", str(ROOT / "target" / "cross-test")]
            prefix = "" if p.suffix == ".dll" else "lib"
            libraries[p.folder] = ROOT / "target" / "cross-test" / p.target / "cross-test" / f"{prefix}converting_span{p.suffix}"
        subprocess.run(command, cwd=ROOT, check=True)
    return libraries


def test_a_panic_in_a_step_comes_back_as_fmi2Error_on_every_platform(importers, descriptions, tmp_path):
    guid, variables = descriptions["ConvertingSpan"]
    s = Scene(variables)
    s.start("panic")
    s.steps(3)
    s.add("hook")
    s.steps(1)  # panics inside the FMU: fmi2Error, the instance is poisoned
    s.add("reset")
    s.add("setup", bits(10.0))
    s.add("enter")
    s.add("exit")
    s.steps(3)
    s.add("free")
    results = {}
    for folder, library in panic_libraries().items():
        proc = run_script(importers, folder, library, guid, s.text(), tmp_path)
        results[folder] = proc
        statuses = [l.split(",")[2:] for l in proc.stdout.splitlines() if l.startswith("call,")]
        assert ["steps", "3"] in statuses, f"{folder}: the panicking step did not give fmi2Error: {statuses}"
        assert statuses[-2:] == [["steps", "0"], ["free", "0"]], f"{folder}: no recovery after fmi2Reset: {statuses}"
    reference = results[REFERENCE]
    for folder in OTHERS:
        assert results[folder].stdout == reference.stdout
        assert log_lines(results[folder].stderr) == log_lines(reference.stderr)


# The Real input each reload scene steps and the output it compares.
RELOAD_SIGNALS = {"ConvertingSpan": ("web_b.v", "summary_Tension"), "Roller": ("tau_m", "omega")}


@pytest.mark.parametrize("platform", [p.folder for p in PLATFORMS])
@pytest.mark.parametrize("model", MODELS)
def test_a_library_unloaded_and_loaded_again_under_a_live_instance_keeps_it(importers, binaries, descriptions, model,
                                                                         platform, tmp_path):
    """An importer that closes the library and opens it again while an instance
    lives (importer.c --reload): both instances step to the same outputs, and
    the library unloads after the last free (the instances hold a reference)."""
    guid, variables = descriptions[model]
    stepped, compared = (variables[name].get("valueReference") for name in RELOAD_SIGNALS[model])
    proc = run(importers, platform, binaries[model, platform], guid, ["--reload", stepped, compared], tmp_path)
    assert proc.returncode == 0, f"{platform}: exit {proc.returncode}\n{proc.stdout[-2000:]}{proc.stderr[-2000:]}"
    rows = [line.split(",") for line in proc.stdout.splitlines() if line.startswith("reload,") and "unloaded" not in line]
    assert len(rows) == 10 and all(a == b for _, _, a, b in rows), rows
    assert "reload,unloaded,1" in proc.stdout.splitlines()


@pytest.fixture(scope="session")
def line_fmu(tmp_path_factory):
    """A Line FMU of the splice scene (a new roll and thinner films at exact event
    times) from the packaged Line libraries of every platform, unpacked:
    (folder, GUID, {name: variable})."""
    sys.path.insert(0, str(ROOT / "webline" / "src"))
    from webline import linefmu
    from webline.scene import load_scene

    folder = tmp_path_factory.mktemp("line")
    scene = load_scene(ROOT / "webline" / "scenes" / "splice.json", fmu_dir=OUT)
    fmu = linefmu.export(scene, folder / "splice.fmu", OUT)
    with zipfile.ZipFile(fmu) as zf:
        zf.extractall(folder / "fmu")
    root = ET.parse(folder / "fmu" / "modelDescription.xml").getroot()
    return folder / "fmu", root.get("guid"), {v.get("name"): v for v in root.iter("ScalarVariable")}


@pytest.mark.parametrize("platform", OTHERS)
def test_a_line_fmu_gives_the_same_bits_on_every_platform(importers, line_fmu, platform, tmp_path):
    """The splice scene as one Line FMU (Rodas5P inside, events at their times, a
    motor torque stepped, an FMU state saved and restored): every output of every
    1 ms step the same as on Linux x86-64."""
    unpacked, guid, variables = line_fmu
    s = Scene(variables)
    s.add("resources", (unpacked / "resources").as_uri())
    s.start("line", stop=3.0)
    torque = next(n for n in variables if n.endswith(".tau_m"))
    s.steps(700)
    s.set(torque, 2.0)
    state = tmp_path / "line-state.bin"
    s.steps(800)
    s.add("save", state)
    s.steps(1000)
    s.add("free")
    s.start("restored", stop=3.0)
    s.add("load", state, bits(1.5))
    s.steps(1000)
    s.add("free")
    texts = {}
    for folder in (REFERENCE, platform):
        p = BY_FOLDER[folder]
        library = unpacked / "binaries" / folder / f"Line{p.suffix}"
        assert library.exists(), f"the Line FMU lacks {library.name} for {folder}: run python3 fmu/package.py"
        proc = run_script(importers, folder, library, guid, s.text(), tmp_path)
        calls = [l for l in proc.stdout.splitlines() if l.startswith("call,")]
        assert all(l.endswith(",0") for l in calls), f"{folder}: {[l for l in calls if not l.endswith(',0')][:3]}\n{proc.stderr[-2000:]}"
        texts[folder] = proc.stdout
    worst, where = largest_difference(texts[REFERENCE], texts[platform])
    assert worst <= REL_TOL, f"Line on {platform}: {worst:.3g} at {where}"
    record(f"Line FMU (splice, 3500 steps of 1 ms, a saved state restored) on {platform}: largest relative difference to linux64 {worst:.3g}"
           f"{' (bit-identical)' if worst == 0 else ''}")
