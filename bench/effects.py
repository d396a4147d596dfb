#!/usr/bin/env python3
"""Benchmark: what each effect costs per fmi2DoStep, and what the code of
the effects costs when they are off.

    .venv/bin/python bench/effects.py [--baseline REV] [--steps N] [--repeats R]

Builds the current release library and the library of a baseline commit (by
default the last commit before the effects and solvers were added), and
measures both side by side in one run with bench/step_cost.c: set the
three inputs, fmi2DoStep, get v and T, as an importer does. Prints the median
ns per step over the repeats, the spread, and the ratio to the baseline's
elastic scene; and, with valgrind installed, the instructions per step counted
by callgrind, which do not depend on what else the machine is doing.
Numbers, not assertions: timing is for people to read.
"""

import argparse
import os
import re
import shutil
import platform
import subprocess
import tempfile
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

from webline.fmus import effects

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "target" / "bench"
# The commit before the issue that added effects and solvers.
DEFAULT_BASELINE = "c021732"


def fmpy_headers():
    import fmpy

    return os.path.join(os.path.dirname(fmpy.__file__), "c-code")


def build_library(source: Path, target_dir: Path) -> Path:
    env = dict(os.environ, CARGO_TARGET_DIR=str(target_dir))
    subprocess.run(["cargo", "build", "--release", "--lib", "--quiet"], cwd=source, env=env, check=True)
    return target_dir / "release" / "libconverting_span.so"


def baseline_source(rev: str) -> Path:
    # Outside this repository: inside it, cargo would take the tree for a
    # member of this workspace.
    tree = Path(tempfile.gettempdir()) / "converting-span-bench" / f"baseline-{rev}"
    if not tree.exists():
        subprocess.run(["git", "worktree", "add", "--detach", str(tree), rev], cwd=ROOT, check=True,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return tree


def interface(model_description: Path):
    root = ET.parse(model_description).getroot()
    vrs = {v.get("name"): v.get("valueReference") for v in root.iter("ScalarVariable")}
    return root.get("guid"), vrs


def command(harness, lib, md, steps, repeats, settings):
    guid, vrs = interface(md)
    inputs = ",".join(vrs[n] for n in ["web_a.v", "web_a.eps", "web_b.v"])
    outputs = ",".join(vrs[n] for n in ["v", "T"])
    args = [f"{kind}:{vrs[name]}={value}" for kind, name, value in settings]
    return [str(harness), str(lib), guid, str(steps), str(repeats), inputs, outputs, *args]


def run(harness, lib, md, steps, repeats, settings):
    line = subprocess.run(command(harness, lib, md, steps, repeats, settings),
                          check=True, capture_output=True, text=True).stdout.split()
    return float(line[0]), float(line[1]), float(line[2]), float(line[4])


def instructions_per_step(harness, lib, md, settings, steps=100_000):
    """Instructions per step from callgrind: two runs of different length,
    so that loading, instantiation and initialization cancel out."""
    if not shutil.which("valgrind"):
        return float("nan")
    counts = []
    for n in (steps, 2 * steps):
        err = subprocess.run(["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null",
                              *command(harness, lib, md, n, 1, settings)],
                             check=True, capture_output=True, text=True).stderr
        counts.append(int(re.search(r"Collected : (\d+)", err).group(1)))
    return (counts[1] - counts[0]) / steps


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--baseline", default=DEFAULT_BASELINE)
    parser.add_argument("--steps", type=int, default=2_000_000)
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args()
    OUT.mkdir(parents=True, exist_ok=True)
    harness = OUT / "step_cost"
    subprocess.run(["gcc", "-O2", "-Wall", "-Werror", f"-I{fmpy_headers()}", f"-I{ROOT / 'tests' / 'integration' / 'c_importer'}", str(ROOT / "bench/step_cost.c"),
                    "-o", str(harness), "-ldl"], check=True)
    current = build_library(ROOT, ROOT / "target")
    base_tree = baseline_source(args.baseline)
    baseline = build_library(base_tree, OUT / "baseline-target")

    on = "1"
    md = ROOT / "modelDescription.xml"
    names = effects(md)  # the span's effects, as its model description names them
    scenes = [
        ("elastic (baseline build)", baseline, base_tree / "modelDescription.xml", []),
        ("elastic, effect code present but off", current, md, []),
        *[(n, current, md, [("b", n, on)]) for n in names],
        ("all four effects", current, md, [("b", n, on) for n in names]),
    ]
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, {platform.platform()}")
    print(f"{args.steps} steps x {args.repeats} repeats per scene; baseline = {args.baseline}\n")
    print(f"{'scene':40s} {'ns/step':>9s} {'min':>7s} {'max':>7s} {'vs baseline':>12s} {'instr/step':>11s} {'vs baseline':>12s}")
    reference = reference_instructions = None
    for name, lib, md, settings in scenes:
        median, low, high, tension = run(harness, lib, md, args.steps, args.repeats, settings)
        instructions = instructions_per_step(harness, lib, md, settings)
        reference = reference or median
        reference_instructions = reference_instructions or instructions
        print(f"{name:40s} {median:9.2f} {low:7.2f} {high:7.2f} {median / reference:11.3f}x "
              f"{instructions:11.0f} {instructions / reference_instructions:11.3f}x   (T = {tension:.6g} N)")


if __name__ == "__main__":
    sys.exit(main())
