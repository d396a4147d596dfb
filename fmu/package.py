#!/usr/bin/env python3
"""Build the release libraries and write the FMUs: ConvertingSpan and Roller.

    python3 fmu/package.py [--out out/ConvertingSpan.fmu] [--platforms linux64,win64,aarch64-linux]
                           [--add-binary PLATFORM=PATH ...] [--no-build] [--host-build]

Each FMU is one model of the cargo workspace, and every model has the same
shape (Cargo.toml, src/, modelDescription.xml, build.rs, documentation/,
resources/): ConvertingSpan the root package, Roller the one in models/roller;
Roller.fmu is written next to ConvertingSpan.fmu. Each FMU holds its
modelDescription.xml, one library per platform in
binaries/<platform>/<modelIdentifier>.<so|dll>, documentation/index.html and
the files of the model's resources/ (the span's library of webs). Each model
with an FMI 3.0 API also gets an FMI 3.0 FMU, out/fmi3/<model>.fmu (one
fmiVersion per FMU): the same library (it exports the fmi2 and the fmi3
functions) under FMI 3.0's platform folders, the
modelDescription.xml and terminalsAndIcons.xml that fmi-build writes from the
FMI 2.0 description, the same documentation and resources. The documentation's variable and unit tables are
rendered from the model description, so they never disagree with the FMU.
out/line/ is the Line FMU's template: its library for each platform, each
platform's line-description (the tool that writes a line's model description)
and its documentation page; `webline export --fmu` makes a line's FMU from it,
and the wheel (fmu/wheel.py) carries it.
Only the Python standard library is used (and binutils' objdump).

The platforms (README, "Platforms"; docs/platforms.md):

    linux64        x86-64 Linux, glibc >= 2.17: cargo-zigbuild (zig links
                   against glibc 2.17's symbol versions)
    win64          x86-64 Windows 10 or later: rustc-web (std in its sysroot),
                   x86_64-w64-mingw32-gcc as the linker
    aarch64-linux  ARM64 Linux, glibc >= 2.17: the same rustc-web through
                   cargo-zigbuild; the folder is FMI 3.0's platform tuple,
                   which FMI 2.0.4 names for platforms beyond win/linux/darwin

fmu/env.sh installs every tool once (fmu/toolchain.sh,
fmu/cross_toolchain.sh); run without it, this script goes through it.
`--platforms` builds only the chosen ones (quick development loops).
`--add-binary PLATFORM=PATH` adds a library built elsewhere (macOS: darwin64)
after checking that it exports exactly the 44 fmi2 functions; its FMU then
also carries every platform built here. `--host-build` packages a plain
`cargo build --release` library as linux64 only: for development, it needs the
glibc of the machine that built it.
"""

import argparse
import concurrent.futures
import io
import html
import json
import os
import re
import struct
import subprocess
import sys
import zipfile
import xml.etree.ElementTree as ET
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
# One stylesheet for every FMU's documentation page (inlined: a page stays one file).
STYLE = ROOT / "fmu" / "style.css"
RANGE_TOOL = "ConvertingSpan.range"
EFFECT_TOOL = "ConvertingSpan.effects"
# Fixed timestamp: the same inputs give the same archive bytes.
ZIP_TIME = (2026, 1, 1, 0, 0, 0)
# Present only in a library built with the test-only feature `test-hooks`.
TEST_HOOK_MARKER = b"testHook.panicInNextDoStep"
# The FMI 2.0 C API: what every binary exports, nothing more, nothing less.
FMI2_FUNCTIONS = frozenset(
    "fmi2" + name
    for name in """
    GetTypesPlatform GetVersion SetDebugLogging Instantiate FreeInstance SetupExperiment
    EnterInitializationMode ExitInitializationMode Terminate Reset GetReal GetInteger GetBoolean
    GetString SetReal SetInteger SetBoolean SetString GetFMUstate SetFMUstate FreeFMUstate
    SerializedFMUstateSize SerializeFMUstate DeSerializeFMUstate GetDirectionalDerivative
    EnterEventMode NewDiscreteStates EnterContinuousTimeMode CompletedIntegratorStep SetTime
    SetContinuousStates GetDerivatives GetEventIndicators GetContinuousStates
    GetNominalsOfContinuousStates SetRealInputDerivatives GetRealOutputDerivatives DoStep
    CancelStep GetStatus GetRealStatus GetIntegerStatus GetBooleanStatus GetStringStatus
    """.split()
)
assert len(FMI2_FUNCTIONS) == 44
# The FMI 3.0 C API (fmi/abi): every function of the standard's headers.
FMI3_FUNCTIONS = frozenset(
    "fmi3" + name
    for name in """
    GetVersion SetDebugLogging InstantiateModelExchange InstantiateCoSimulation InstantiateScheduledExecution
    FreeInstance EnterInitializationMode ExitInitializationMode EnterEventMode Terminate Reset
    GetFloat32 GetFloat64 GetInt8 GetUInt8 GetInt16 GetUInt16 GetInt32 GetUInt32 GetInt64 GetUInt64
    GetBoolean GetString GetBinary GetClock SetFloat32 SetFloat64 SetInt8 SetUInt8 SetInt16 SetUInt16
    SetInt32 SetUInt32 SetInt64 SetUInt64 SetBoolean SetString SetBinary SetClock
    GetNumberOfVariableDependencies GetVariableDependencies GetFMUState SetFMUState FreeFMUState
    SerializedFMUStateSize SerializeFMUState DeserializeFMUState GetDirectionalDerivative
    GetAdjointDerivative EnterConfigurationMode ExitConfigurationMode GetIntervalDecimal
    GetIntervalFraction GetShiftDecimal GetShiftFraction SetIntervalDecimal SetIntervalFraction
    SetShiftDecimal SetShiftFraction EvaluateDiscreteStates UpdateDiscreteStates EnterContinuousTimeMode
    CompletedIntegratorStep SetTime SetContinuousStates GetContinuousStateDerivatives GetEventIndicators
    GetContinuousStates GetNominalsOfContinuousStates GetNumberOfEventIndicators
    GetNumberOfContinuousStates EnterStepMode GetOutputDerivatives DoStep ActivateModelPartition
    """.split()
)
assert len(FMI3_FUNCTIONS) == 75


class Platform:
    """One binaries/<folder> of the FMUs: its cargo target and where the library lands."""

    def __init__(self, folder, target, suffix, prefix, target_dir):
        self.folder = folder
        self.target = target
        self.suffix = suffix
        self.prefix = prefix  # "lib" for Linux shared objects, none for DLLs
        self.target_dir = target_dir

    def library(self, model):
        return self.release(model.target_dir(self.target_dir)) / f"{self.prefix}{model.crate}{self.suffix}"

    def release(self, target_dir):
        return target_dir / self.target.removesuffix(".2.17") / "release"

    def description_tool(self):
        """The Line's line-description for this platform, which the wheel carries (webline export --fmu
        outside a checkout): built in a folder of its own, as its build of the Line's library with
        the feature `cli` would replace the library the FMUs ship."""
        exe = ".exe" if self.suffix == ".dll" else ""
        return self.release(tools_target_dir(self.target_dir)) / f"line-description{exe}"


PLATFORMS = {
    p.folder: p
    for p in [
        # The oldest glibc the binary supports is part of the target name.
        Platform("linux64", "x86_64-unknown-linux-gnu.2.17", ".so", "lib", ROOT / "target" / "portable"),
        Platform("win64", "x86_64-pc-windows-gnu", ".dll", "", ROOT / "target" / "cross"),
        Platform("aarch64-linux", "aarch64-unknown-linux-gnu.2.17", ".so", "lib", ROOT / "target" / "cross"),
    ]
}
# Libraries built elsewhere may go into these folders too (--add-binary).
SUFFIXES = {"linux64": ".so", "win64": ".dll", "aarch64-linux": ".so", "darwin64": ".dylib", "aarch64-darwin": ".dylib"}
# FMI 3.0 names the platform folders by architecture and system.
FMI3_FOLDERS = {"linux64": "x86_64-linux", "win64": "x86_64-windows", "aarch64-linux": "aarch64-linux",
                "darwin64": "x86_64-darwin", "aarch64-darwin": "aarch64-darwin"}


class Model:
    """One FMU of the workspace: its interface, documentation and library name."""

    def __init__(self, name, package, crate_dir, fmi3=False):
        self.name = name
        # The library exports the FMI 3.0 API too (fmi/abi), and an FMI 3.0 FMU is written.
        self.fmi3 = fmi3
        self.package = package
        self.crate = package.replace("-", "_")
        self.description = crate_dir / "modelDescription.xml"
        self.template = crate_dir / "documentation" / "index.html"
        # Files shipped in the FMU's resources/ folder (the span's library of webs).
        self.resources = crate_dir / "resources"
        self.host_library = self.target_dir(ROOT / "target") / "release" / f"lib{self.crate}.so"

    def shipped_resources(self):
        """The zip entries of the files in the model's resources/, but its README (which says
        what the folder holds, for the developers)."""
        if not self.resources.is_dir():
            return []
        return [(f"resources/{f.name}", f.read_bytes()) for f in sorted(self.resources.iterdir())
                if f.is_file() and f.name != "README.md"]

    def target_dir(self, base):
        """Where cargo builds it: the Line in a folder of its own, as its build of the
        span's crate (without the C API) would replace the span's library in a shared one."""
        return base.parent / "line" / base.name if self.name == "Line" else base


MODELS = [
    Model("ConvertingSpan", "converting-span", ROOT, fmi3=True),
    Model("Roller", "roller", ROOT / "models" / "roller", fmi3=True),
]


def packages():
    return [arg for model in MODELS for arg in ("-p", model.package)]


# The Line FMU's generic library: a workspace of its own (models/line/Cargo.toml
# says why); `webline export --fmu` adds a line's description and resources.
LINE = Model("Line", "line", ROOT / "models" / "line", fmi3=True)
LINE_MANIFEST = ["--manifest-path", str(ROOT / "models" / "line" / "Cargo.toml")]
# What the Line library exports beyond FMI: one call for a study's whole run (fmi/abi's
# `export_fmi2_steps!`, webline's native loop); importers never need it.
LINE_EXTENSIONS = frozenset({"convertingSpanDoSteps"})

LINE_TOOL = [*LINE_MANIFEST, "--features", "cli", "--bin", "line-description"]


def tools_target_dir(base):
    return base.parent / "line-tools" / base.name


class StepFailed(Exception):
    """A step of packaging failed: the one line the user reads instead of a traceback."""


def run(step, command, **kwargs):
    """Runs one tool of a packaging step; its failure becomes StepFailed naming the step."""
    try:
        return subprocess.run(command, cwd=ROOT, check=True, **kwargs)
    except FileNotFoundError:
        raise StepFailed(f"{step} failed: {command[0]} is not installed. Run through fmu/env.sh "
                         "(bash fmu/main.sh does), which installs it.") from None
    except subprocess.CalledProcessError as error:
        why = "it could not start a program or load a shared library" if error.returncode in (126, 127) else \
            f"{Path(command[0]).name} exited with status {error.returncode}"
        raise StepFailed(f"{step} failed: {why}; its own message is above. Fix what it names, then run again "
                         "(a broken cached toolchain: remove the folder CONVERTING_SPAN_TOOLS names).") from None


def build_host():
    run("building the host libraries", ["cargo", "build", "--release", "--lib", "--quiet", *packages()])
    run("building the host Line library", ["cargo", "build", "--release", "--lib", "--quiet", *LINE_MANIFEST,
        "--target-dir", str(LINE.target_dir(ROOT / "target"))])


def build(platforms):
    """Both models' libraries and the Line's for each platform, with the tools of fmu/env.sh.
    Two builds at a time: a release build ends in one long single-threaded link (LTO, one
    codegen unit), so a second build keeps the other core busy. Builds that share a target
    folder wait for each other on cargo's lock."""
    models = [(p, ["--lib", *packages()], "libraries", p.target_dir) for p in platforms]
    lines = [(p, ["--lib", *LINE_MANIFEST], "Line library", LINE.target_dir(p.target_dir)) for p in platforms]
    tools = [(p, LINE_TOOL, "Line's line-description", tools_target_dir(p.target_dir)) for p in platforms]
    # interleaved, so that the two running builds rarely share a target folder
    jobs = [job for triple in zip(models, lines, tools) for job in triple]
    with concurrent.futures.ThreadPoolExecutor(max_workers=2) as pool:
        waiting = [pool.submit(build_crates, *job) for job in jobs] + [pool.submit(build_export_tool)]
        for done in waiting:
            done.result()  # a failed build's StepFailed


def build_export_tool():
    """The host's line-description, which `webline export --fmu` runs (webline/src/webline/linefmu.py
    builds it on first use too): built with the FMUs, so that the first export takes seconds."""
    run("building the Line FMU's export tool (line-description)",
        ["cargo", "build", "--release", "--quiet", *LINE_MANIFEST, "--features", "cli", "--bin", "line-description",
         "--target-dir", str(ROOT / "target" / "line")])


def build_crates(platform, selection, what, target_dir):
    common = ["--release", "--quiet", *selection, "--target", platform.target]
    common += ["--target-dir", str(target_dir)]
    env = dict(os.environ)
    if platform.folder == "linux64":
        command = ["cargo", "zigbuild", *common]
    else:
        # rustup has no standard library for these targets here: rustc-web's, whose
        # sysroot has it (fmu/cross_toolchain.sh builds it there once).
        command = [os.environ["CROSS_CARGO"], "build", *common]
        if platform.target.endswith(".2.17"):
            # cargo-zigbuild drives rustc-web's cargo and links with zig (glibc 2.17 floor).
            env.pop("CARGO_TARGET_AARCH64_UNKNOWN_LINUX_GNU_LINKER", None)
            env.update(CARGO=command[0], RUSTC=os.environ["CROSS_RUSTC"])
            command[0:2] = ["cargo-zigbuild", "build"]
    run(f"building the {platform.folder} {what}", command, env=env)


def exported_functions(path):
    """The functions a library exports, read with objdump: the dynamic symbol
    table of an ELF object, the export table of a PE DLL."""
    data = path.read_bytes()[:4]
    if data == b"\x7fELF":
        listing = run(f"reading the exports of {path}", ["objdump", "-T", str(path)], capture_output=True, text=True).stdout
        # defined (not *UND*) global symbols in .text
        return set(re.findall(r"^\S+\s+g\s+DF\s+\.text\s+\S+\s+(?:\S+\s+)?(\w+)$", listing, re.M))
    if data[:2] == b"MZ":
        listing = run(f"reading the exports of {path}", ["objdump", "-p", str(path)], capture_output=True, text=True).stdout
        table = listing.split("[Ordinal/Name Pointer] Table", 1)[1].split("\n\n", 1)[0]
        return set(re.findall(r"^\s+\[\s*\d+\]\s+(\S+)$", table, re.M))
    if data in (b"\xcf\xfa\xed\xfe", b"\xca\xfe\xba\xbe"):
        return macho_exports(path)
    sys.exit(f"package.py: {path} is neither an ELF, a PE nor a Mach-O library")


def macho_exports(path):
    """The external symbols a Mach-O library defines (LC_SYMTAB), each
    architecture of a universal binary alike; Mach-O prefixes C names with '_'."""
    data = path.read_bytes()
    if data[:4] == b"\xca\xfe\xba\xbe":
        count = struct.unpack_from(">I", data, 4)[0]
        slices = [struct.unpack_from(">iiII", data, 8 + 20 * i)[2:] for i in range(count)]
        found = [macho_exports_thin(data[offset : offset + size]) for offset, size in slices]
        if any(names != found[0] for names in found):
            sys.exit(f"package.py: the architectures of {path} export different functions")
        return found[0]
    return macho_exports_thin(data)


def macho_exports_thin(data):
    ncmds = struct.unpack_from("<I", data, 16)[0]
    offset, names = 32, set()  # after the 64-bit header
    for _ in range(ncmds):
        cmd, size = struct.unpack_from("<II", data, offset)
        if cmd == 0x2:  # LC_SYMTAB
            symoff, nsyms, stroff, _ = struct.unpack_from("<IIII", data, offset + 8)
            for k in range(nsyms):
                strx, kind = struct.unpack_from("<IB", data, symoff + 16 * k)
                # N_EXT set, defined in a section (N_SECT), not a debugging entry
                if kind & 0xE0 == 0 and kind & 0x01 and kind & 0x0E == 0x0E:
                    name = data[stroff + strx : data.index(b"\0", stroff + strx)].decode()
                    names.add(name.removeprefix("_"))
        offset += size
    return names


def expected_exports(name):
    """What the library of the model `name` exports: the fmi2 API, and the fmi3 API where the model has one."""
    fmi3 = next(m.fmi3 for m in MODELS if m.name == name)
    return FMI2_FUNCTIONS | FMI3_FUNCTIONS if fmi3 else FMI2_FUNCTIONS


def check_library(folder, path, fmi3, extensions=frozenset()):
    """A library goes into an FMU only if it exports the fmi2 API (and, for a
    model with FMI 3.0, the fmi3 API) and its `extensions` exactly and has no test hook."""
    if not path.exists():
        sys.exit(f"package.py: {path} is missing; run without --no-build")
    if not path.name.endswith(SUFFIXES[folder]):
        sys.exit(f"package.py: {path} is not a {SUFFIXES[folder]} library, as binaries/{folder} needs")
    if TEST_HOOK_MARKER in path.read_bytes():
        sys.exit(f"package.py: {path} was built with the test-only feature test-hooks; it must not ship")
    exported = exported_functions(path)
    expected = (FMI2_FUNCTIONS | FMI3_FUNCTIONS if fmi3 else FMI2_FUNCTIONS) | extensions
    if exported != expected:
        missing = sorted(expected - exported)
        extra = sorted(exported - expected)
        what = "the 44 fmi2 and the 75 fmi3 functions" if fmi3 else "the 44 fmi2 functions"
        what += "".join(f" and {name}" for name in sorted(extensions))
        sys.exit(f"package.py: {path} must export exactly {what}; missing {missing}, extra {extra}")


def allowed_range(root, var, t):
    """The allowed values as the FMU checks them: XML min/max plus the strict
    bounds of the model-level VendorAnnotations."""
    strict = root.find(f"./VendorAnnotations/Tool[@name='{RANGE_TOOL}']/Ranges/Range[@variable='{var.get('name')}']")
    low = high = None
    if strict is not None and "greaterThan" in strict.attrib:
        low = f"&gt; {strict.get('greaterThan')}"
    elif t.get("min") is not None:
        low = f"&ge; {t.get('min')}"
    if strict is not None and "lessThan" in strict.attrib:
        high = f"&lt; {strict.get('lessThan')}"
    elif t.get("max") is not None:
        high = f"&le; {t.get('max')}"
    rate = f"|d/dt| &le; {strict.get('maxRate')} per s" if strict is not None and "maxRate" in strict.attrib else None
    return ", ".join(x for x in (low, high, rate) if x) or "any finite value"


def variable_rows(root):
    enums = {
        st.get("name"): [(i.get("value"), i.get("name")) for i in st.iter("Item")]
        for st in root.iter("SimpleType")
    }
    rows = []
    for var in root.find("ModelVariables"):
        kind_el = var[0]
        kind = kind_el.tag
        unit = kind_el.get("unit", "")
        if kind == "Enumeration":
            items = enums[kind_el.get("declaredType")]
            allowed = ", ".join(f"{v} = {html.escape(n)}" for v, n in items)
            kind = f"Enumeration ({kind_el.get('declaredType')})"
        elif kind == "Boolean":
            allowed = "true / false"
        else:
            allowed = allowed_range(root, var, kind_el)
        rows.append(
            "<tr><td><code>{}</code></td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>".format(
                html.escape(var.get("name")),
                var.get("causality", "local"),
                kind,
                html.escape(unit),
                html.escape(kind_el.get("start", "")),
                allowed,
                html.escape(var.get("description", "")),
            )
        )
    return "\n".join(rows)


def effect_rows(root):
    """The model's effects (the ConvertingSpan.effects tool of the description) with what each adds."""
    variables = {v.get("name"): v for v in root.find("ModelVariables")}
    return "\n".join(
        f"<tr><td><code>{html.escape(e.get('variable'))}</code></td>"
        f"<td>{html.escape(variables[e.get('variable')].get('description', ''))}</td></tr>"
        for e in root.findall(f"./VendorAnnotations/Tool[@name='{EFFECT_TOOL}']/Effects/Effect")
    )


def unit_rows(root):
    rows = []
    for st in root.iter("SimpleType"):
        for item in st.iter("Item"):
            rows.append(
                f"<tr><td>{st.get('name')}</td><td>{item.get('value')}</td>"
                f"<td>{html.escape(item.get('name'))}</td><td>{html.escape(item.get('description', ''))}</td></tr>"
            )
    return "\n".join(rows)


def web_rows(library):
    """The shipped web records as table rows (the span's documentation)."""
    rows = []
    for w in json.loads(library.read_text(encoding="utf-8"))["webs"]:
        modulus = f"{w['E'] / 1e9:.4g} GPa" if "E" in w else f"table, {len(w['stress_strain'])} points"
        cells = [w["name"], w["description"], modulus, f"{w['thickness'] * 1e6:g} um", f"{w['density']:g}",
                 f"{w['d_r']:g} s", w.get("source", "")]
        rows.append("<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in cells) + "</tr>")
    return "\n".join(rows)


# The FMI 3.0 FMU's page: the same text, which names the FMI 2.0 functions, with a note.
FMI3_NOTE = (
    "FMI 3.0 FMU for Co-Simulation and Model Exchange (one binary, the same as the FMI 2.0 FMU's). "
    "The text below names the FMI 2.0 functions; their FMI 3.0 counterparts behave the same "
    "(fmi2SetReal: fmi3SetFloat64; enumerations: fmi3SetInt64; fmi2SetupExperiment: the arguments "
    "of fmi3EnterInitializationMode; fmi2SetRealInputDerivatives has none). "
    "The ports web_a and web_b are terminals (terminalsAndIcons.xml)."
)


def documentation(root, template, resources=None, fmi3=False):
    text = template.read_text(encoding="utf-8")
    if fmi3:
        text = text.replace("FMI 2.0 FMU for Co-Simulation and Model Exchange (one binary)", html.escape(FMI3_NOTE))
    replacements = {
        "<!-- STYLE -->": STYLE.read_text(encoding="utf-8"),
        "<!-- VARIABLES -->": variable_rows(root),
        "<!-- GUID -->": html.escape(root.get("guid")),
        "<!-- VERSION -->": html.escape(root.get("version", "")),
    }
    if resources is not None and (resources / "webs.json").exists():
        replacements["<!-- WEBS -->"] = web_rows(resources / "webs.json")
    # A model with effects lists them from its description.
    if root.find(f"./VendorAnnotations/Tool[@name='{EFFECT_TOOL}']") is not None:
        replacements["<!-- EFFECTS -->"] = effect_rows(root)
    # A model with enumerations (unit choices) documents them.
    if root.find("TypeDefinitions") is not None:
        replacements["<!-- UNIT_CHOICES -->"] = unit_rows(root)
    for key, value in replacements.items():
        if key not in text:
            sys.exit(f"package.py: {template} lacks the placeholder {key}")
        text = text.replace(key, value)
    return text


def write_fmu(out, model, libraries):
    """libraries: {platform folder: library path}."""
    root = ET.parse(model.description).getroot()
    identifier = root.find("CoSimulation").get("modelIdentifier")
    if identifier != model.name:
        sys.exit(f"package.py: {model.description} names the model {identifier}, expected {model.name}")
    entries = [("modelDescription.xml", model.description.read_bytes())]
    for folder, library in sorted(libraries.items()):
        entries.append((f"binaries/{folder}/{identifier}{SUFFIXES[folder]}", library.read_bytes()))
    entries.append(("documentation/index.html", documentation(root, model.template, model.resources).encode("utf-8")))
    entries += model.shipped_resources()
    write_zip(out, entries)
    return out


def fmi3_files(model):
    """The FMI 3.0 modelDescription.xml and terminalsAndIcons.xml, written by
    fmi-build from the FMI 2.0 description into target/fmi3/<model>."""
    folder = ROOT / "target" / "fmi3" / model.name
    run(f"writing {model.name}'s FMI 3.0 description", ["cargo", "run", "--release", "--quiet", "-p", "fmi-build",
        "--bin", "fmi3-description", "--", str(model.description), str(folder)])
    return folder / "modelDescription.xml", folder / "terminalsAndIcons" / "terminalsAndIcons.xml"


def write_fmu3(out, model, libraries):
    """The FMI 3.0 FMU of `model`: libraries as for write_fmu, under FMI 3.0's folders."""
    description, terminals = fmi3_files(model)
    root = ET.parse(description).getroot()
    identifier = root.find("CoSimulation").get("modelIdentifier")
    fmi2_root = ET.parse(model.description).getroot()
    entries = [("modelDescription.xml", description.read_bytes()),
               ("terminalsAndIcons/terminalsAndIcons.xml", terminals.read_bytes())]
    for folder, library in sorted(libraries.items()):
        entries.append((f"binaries/{FMI3_FOLDERS[folder]}/{identifier}{SUFFIXES[folder]}", library.read_bytes()))
    page = documentation(fmi2_root, model.template, model.resources, fmi3=True)
    entries.append(("documentation/index.html", page.encode("utf-8")))
    entries += model.shipped_resources()
    write_zip(out, entries)
    return out


def write_line_template(folder, libraries, tools):
    """The Line FMU's generic libraries under FMI 2.0's and FMI 3.0's platform folders
    (fmi2/binaries, fmi3/binaries), each platform's line-description (tools/<platform>/) and
    the FMU's documentation page with the stylesheet inlined (documentation/index.html): what
    `webline export --fmu` needs, in a checkout or from the wheel. Replaces what was there."""
    for standard, names in (("fmi2", {f: f for f in SUFFIXES}), ("fmi3", FMI3_FOLDERS)):
        wanted = {Path(standard, "binaries", names[platform], f"Line{SUFFIXES[platform]}"): library
                  for platform, library in libraries.items()}
        replace_folder(folder / standard / "binaries", {folder / k: v.read_bytes() for k, v in wanted.items()})
    replace_folder(folder / "tools", {folder / "tools" / platform / tool.name: tool.read_bytes()
                                      for platform, tool in tools.items()}, mode=0o755)
    page = LINE.template.read_text(encoding="utf-8").replace("<!-- STYLE -->", STYLE.read_text(encoding="utf-8"))
    write_if_changed(folder / "documentation" / "index.html", page.encode("utf-8"))
    return folder


def replace_folder(folder, files, mode=None):
    """The folder holds exactly files ({path: bytes}) afterwards."""
    for stale in [p for p in folder.rglob("*") if p.is_file() and p not in files] if folder.is_dir() else []:
        stale.unlink()
    for target, data in sorted(files.items()):
        write_if_changed(target, data)
        if mode is not None:
            target.chmod(mode)


def write_if_changed(out, data):
    """Writes data to out unless out holds it already, atomically: a run beside this
    one (tests that read the FMUs while another packaging runs) never sees half a file."""
    if out.is_file() and out.read_bytes() == data:
        return
    out.parent.mkdir(parents=True, exist_ok=True)
    part = out.with_name(out.name + ".part")
    part.write_bytes(data)
    os.replace(part, out)


def write_zip(out, entries):
    """A zip of entries; the same entries give the same bytes (fixed times), so an
    unchanged FMU is not written again."""
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED) as zf:
        for name, data in entries:
            info = zipfile.ZipInfo(name, ZIP_TIME)
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = 0o644 << 16
            zf.writestr(info, data)
    write_if_changed(out, buffer.getvalue())


def added_binary(text):
    """--add-binary PLATFORM=PATH: PATH is a folder with each model's library
    under its model identifier (ConvertingSpan.dylib, Roller.dylib), or one
    such library for that model's FMU alone."""
    folder, sep, path = text.partition("=")
    if not sep or folder not in SUFFIXES:
        raise argparse.ArgumentTypeError(f"{text!r}: expected PLATFORM=PATH with PLATFORM one of {', '.join(SUFFIXES)}")
    return folder, Path(path).resolve()


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument(
        "--out",
        type=Path,
        default=ROOT / "out" / "ConvertingSpan.fmu",
        help="where to write ConvertingSpan.fmu (Roller.fmu goes into the same folder)",
    )
    parser.add_argument(
        "--platforms",
        default=",".join(PLATFORMS),
        help=f"comma-separated platforms to build and package (default: all, {','.join(PLATFORMS)})",
    )
    parser.add_argument(
        "--add-binary",
        type=added_binary,
        action="append",
        default=[],
        metavar="PLATFORM=PATH",
        help="add libraries built elsewhere: a folder with <modelIdentifier>.<suffix> of each model, or one such file",
    )
    parser.add_argument("--no-build", action="store_true", help="package the libraries as they are")
    parser.add_argument(
        "--host-build", action="store_true", help="plain cargo build against this machine's glibc (development only)"
    )
    args = parser.parse_args()
    chosen = [p for p in args.platforms.split(",") if p]
    unknown = [p for p in chosen if p not in PLATFORMS]
    if unknown:
        parser.error(f"unknown platform(s) {unknown}; known: {', '.join(PLATFORMS)}")
    if args.host_build:
        chosen = []
        if not args.no_build:
            build_host()
    elif not args.no_build:
        build([PLATFORMS[folder] for folder in chosen])
    names = {model.name for model in MODELS}
    for folder, path in args.add_binary:
        if not path.is_dir() and path.stem not in names:
            sys.exit(f"package.py: --add-binary {folder}={path}: name the library after its model, "
                     f"{' or '.join(n + SUFFIXES[folder] for n in sorted(names))}")
    span_out = args.out.resolve()
    for model in MODELS:
        libraries = {folder: PLATFORMS[folder].library(model) for folder in chosen}
        if args.host_build:
            libraries["linux64"] = model.host_library
        for folder, path in args.add_binary:
            if path.is_dir():
                libraries[folder] = path / f"{model.name}{SUFFIXES[folder]}"
            elif path.stem == model.name:
                libraries[folder] = path
        if not libraries:
            sys.exit("package.py: no platform chosen")
        for folder, library in libraries.items():
            check_library(folder, library, model.fmi3)
        out = span_out if model.name == "ConvertingSpan" else span_out.parent / f"{model.name}.fmu"
        written = [write_fmu(out, model, libraries)]
        if model.fmi3:
            written.append(write_fmu3(span_out.parent / "fmi3" / f"{model.name}.fmu", model, libraries))
        sizes = ", ".join(f"{folder} {library.stat().st_size} bytes" for folder, library in sorted(libraries.items()))
        kind = " (host build, not portable)" if args.host_build else ""
        for fmu in written:
            print(f"wrote {fmu} ({fmu.stat().st_size} bytes; {sizes}){kind}")
    line_libraries = {folder: PLATFORMS[folder].library(LINE) for folder in chosen}
    if args.host_build:
        line_libraries["linux64"] = LINE.host_library
    for folder, library in line_libraries.items():
        check_library(folder, library, True, LINE_EXTENSIONS)
    # A host build's tool is not portable: the wheel's tools come from the platforms' builds only.
    line_tools = {folder: PLATFORMS[folder].description_tool() for folder in chosen}
    for folder, tool in line_tools.items():
        if not tool.is_file():
            sys.exit(f"package.py: {tool} is missing; run without --no-build")
    print(f"wrote {write_line_template(span_out.parent / 'line', line_libraries, line_tools)} (the Line FMU's "
          f"libraries and line-description: {', '.join(sorted(line_libraries))}; webline export --fmu adds a line)")
    for folder, path in args.add_binary:
        # tests/run.sh runs the platforms built here; an added library only its own platform can run.
        print(f"added binaries/{folder} from {path}: its exports are checked, but it was not run here; "
              "run the FMU on that platform before publishing it")


if __name__ == "__main__":
    # The cross tools come from fmu/env.sh (installed once, cached): without
    # them in the environment, run again through it.
    if "CROSS_CARGO" not in os.environ and "--host-build" not in sys.argv and "--no-build" not in sys.argv:
        os.execvp("bash", ["bash", "-c", 'source "$0/fmu/env.sh" >&2 && exec python3 "$0/fmu/package.py" "$@"', str(ROOT), *sys.argv[1:]])
    try:
        main()
    except StepFailed as failure:
        sys.exit(f"package.py: {failure}")
