#!/usr/bin/env python3
"""Build the release libraries and write the FMUs: ConvertingSpan and Roller.

    python3 fmu/package.py [--out out/ConvertingSpan.fmu] [--no-build] [--host-build]

Each FMU is one package of the cargo workspace: ConvertingSpan the root
package, Roller the one in fmu/roller; Roller.fmu is written next to
ConvertingSpan.fmu. Each FMU holds its modelDescription.xml,
binaries/linux64/<modelIdentifier>.so, documentation/index.html and, for
the span, resources/webs.json (the library of webs, from fmu/resources). The
documentation's variable and unit tables are rendered from the model
description, so they never disagree with the FMU. Only the Python standard
library is used.

The shipped binaries are portable: they are built with cargo-zigbuild (zig as
the linker) for the target x86_64-unknown-linux-gnu.2.17, so they need no
glibc symbol newer than 2.17 and load on any x86-64 Linux since 2012 (CentOS
7); fmu/env.sh installs zig and cargo-zigbuild (fmu/toolchain.sh), and
tests/hardening/test_portable_so.py checks the result. `--host-build` packages
plain `cargo build --release` libraries instead: for development only, they
need the glibc of the machine that built them.
"""

import argparse
import html
import json
import os
import shutil
import subprocess
import sys
import zipfile
import xml.etree.ElementTree as ET
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
# One stylesheet for every FMU's documentation page (inlined: a page stays one file).
STYLE = ROOT / "fmu" / "documentation" / "style.css"
RANGE_TOOL = "ConvertingSpan.range"
# Fixed timestamp: the same inputs give the same archive bytes.
ZIP_TIME = (2026, 1, 1, 0, 0, 0)
# The oldest glibc the binaries support is part of the target name.
PORTABLE_TARGET = "x86_64-unknown-linux-gnu.2.17"
# Present only in a library built with the test-only feature `test-hooks`.
TEST_HOOK_MARKER = b"testHook.panicInNextDoStep"


class Model:
    """One FMU of the workspace: its interface, documentation and how to build its library."""

    def __init__(self, name, package, crate_dir):
        self.name = name
        self.package = package
        self.description = crate_dir / "modelDescription.xml"
        self.template = crate_dir / ("fmu/documentation" if crate_dir == ROOT else "documentation") / "index.html"
        # Files shipped in the FMU's resources/ folder (the span's library of webs).
        self.resources = crate_dir / ("fmu/resources" if crate_dir == ROOT else "resources")
        library = f"lib{package.replace('-', '_')}.so"
        self.library = ROOT / "target" / "release" / library
        # The portable build: one target directory for the workspace.
        self.portable_library = ROOT / "target" / "portable" / "x86_64-unknown-linux-gnu" / "release" / library


MODELS = [
    Model("ConvertingSpan", "converting-span", ROOT),
    Model("Roller", "roller", ROOT / "fmu" / "roller"),
]


def build_library(model):
    subprocess.run(["cargo", "build", "--release", "--lib", "--quiet", "-p", model.package], cwd=ROOT, check=True)


def tools_path():
    """PATH with the cached zig and cargo-zigbuild of fmu/toolchain.sh."""
    cache = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    tools = os.environ.get("CONVERTING_SPAN_TOOLS") or os.path.join(cache, "converting-span-tools")
    return os.pathsep.join([os.path.join(tools, "bin"), os.environ.get("PATH", "")])


def build_portable_library(model):
    env = dict(os.environ, PATH=tools_path())
    missing = [tool for tool in ("cargo-zigbuild", "zig") if shutil.which(tool, path=env["PATH"]) is None]
    if missing:
        sys.exit(
            f"package.py: {' and '.join(missing)} not found: `source fmu/env.sh` installs them "
            "(or use --host-build for development FMUs that are not portable)"
        )
    command = ["cargo", "zigbuild", "--release", "--lib", "--quiet", "-p", model.package, "--target", PORTABLE_TARGET]
    command += ["--target-dir", str(ROOT / "target" / "portable")]
    subprocess.run(command, cwd=ROOT, check=True, env=env)


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


def documentation(root, template, resources=None):
    text = template.read_text(encoding="utf-8")
    replacements = {
        "<!-- STYLE -->": STYLE.read_text(encoding="utf-8"),
        "<!-- VARIABLES -->": variable_rows(root),
        "<!-- GUID -->": html.escape(root.get("guid")),
        "<!-- VERSION -->": html.escape(root.get("version", "")),
    }
    if resources is not None and (resources / "webs.json").exists():
        replacements["<!-- WEBS -->"] = web_rows(resources / "webs.json")
    # A model with enumerations (unit choices) documents them.
    if root.find("TypeDefinitions") is not None:
        replacements["<!-- UNIT_CHOICES -->"] = unit_rows(root)
    for key, value in replacements.items():
        if key not in text:
            sys.exit(f"package.py: {template} lacks the placeholder {key}")
        text = text.replace(key, value)
    return text


def write_fmu(out, model, library):
    root = ET.parse(model.description).getroot()
    identifier = root.find("CoSimulation").get("modelIdentifier")
    if identifier != model.name:
        sys.exit(f"package.py: {model.description} names the model {identifier}, expected {model.name}")
    out.parent.mkdir(parents=True, exist_ok=True)
    entries = [
        ("modelDescription.xml", model.description.read_bytes()),
        (f"binaries/linux64/{identifier}.so", library.read_bytes()),
        ("documentation/index.html", documentation(root, model.template, model.resources).encode("utf-8")),
    ]
    if model.resources.is_dir():
        entries += [(f"resources/{f.name}", f.read_bytes()) for f in sorted(model.resources.iterdir()) if f.is_file()]
    with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as zf:
        for name, data in entries:
            info = zipfile.ZipInfo(name, ZIP_TIME)
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = 0o644 << 16
            zf.writestr(info, data)
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument(
        "--out",
        type=Path,
        default=ROOT / "out" / "ConvertingSpan.fmu",
        help="where to write ConvertingSpan.fmu (Roller.fmu goes into the same folder)",
    )
    parser.add_argument("--no-build", action="store_true", help="package the libraries as they are")
    parser.add_argument(
        "--host-build", action="store_true", help="plain cargo build against this machine's glibc (development only)"
    )
    args = parser.parse_args()
    span_out = args.out.resolve()
    for model in MODELS:
        library = model.library if args.host_build else model.portable_library
        if not args.no_build:
            build_library(model) if args.host_build else build_portable_library(model)
        if not library.exists():
            sys.exit(f"package.py: {library} is missing; run without --no-build")
        if TEST_HOOK_MARKER in library.read_bytes():
            sys.exit(f"package.py: {library} was built with the test-only feature test-hooks; it must not ship")
        out = span_out if model.name == "ConvertingSpan" else span_out.parent / f"{model.name}.fmu"
        write_fmu(out, model, library)
        kind = "host build, not portable" if args.host_build else f"portable, {PORTABLE_TARGET}"
        print(f"wrote {out} ({out.stat().st_size} bytes; library {library.stat().st_size} bytes, {kind})")


if __name__ == "__main__":
    main()
