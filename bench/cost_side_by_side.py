#!/usr/bin/env python3
"""Callgrind instructions per step of two builds side by side in one run, and their ratio: the
span, the Roller and a 10-span Line FMU (without and with traction), each driven natively from C.

    .venv/bin/python bench/cost_side_by_side.py BASE BRANCH

BASE and BRANCH are folders as `python3 fmu/package.py --host-build --out DIR/ConvertingSpan.fmu`
writes them: ConvertingSpan.fmu, Roller.fmu and line/ (the Line FMU's template, from which the
10-span lines are exported). A folder without line/ may hold the lines' FMUs ready made instead:
line10.fmu and line10-traction.fmu. Prints a Markdown table (docs/performance.md, "Base and
branch side by side").

Counting: the span and the Roller by bench/native_cost.c (set three inputs, fmi2DoStep with
h = 1 ms, get two outputs), the difference of 10,240 and 20,480 steps over 10,240; a line by
bench/line_cost.c (set idler0.tau_m, step 1 ms, get s0.T), the difference of 100 and 600 steps
over 500. Loading and instantiation cancel in the differences, and callgrind counts the same on
every run, so the ratio does not depend on the machine or its load.
"""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent / "webline" / "src"))

import fmpy  # noqa: E402
from fmpy import read_model_description  # noqa: E402
from line_fmu import long_line  # noqa: E402  (bench/)
from webline import linefmu  # noqa: E402
from webline.scene import parse_scene  # noqa: E402

STEPS = 10_240  # a model's steps in the shorter run; the longer runs twice as many
LINE_STEPS = (100, 600)


def compile_harnesses(tmp: Path) -> dict[str, Path]:
    include = [f"-I{Path(fmpy.__file__).parent / 'c-code'}", f"-I{HERE.parent / 'tests' / 'integration' / 'c_importer'}"]
    built = {}
    for name in ("native_cost", "line_cost"):
        built[name] = tmp / name
        subprocess.run(["gcc", "-O2", *include, str(HERE / f"{name}.c"), "-o", str(built[name]), "-ldl"], check=True)
    return built


def instructions(cmd: list) -> int:
    """The instructions callgrind counts for the whole run of `cmd`."""
    err = subprocess.run(["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null", *map(str, cmd)],
                         check=True, capture_output=True, text=True).stderr
    return int(re.search(r"Collected : (\d+)", err).group(1))


def unpack(fmu: Path, folder: Path, lib: str):
    with zipfile.ZipFile(fmu) as z:
        z.extractall(folder)
    md = read_model_description(str(fmu))
    return folder / "binaries" / "linux64" / lib, md.guid, {v.name: v.valueReference for v in md.modelVariables}


class Build:
    def __init__(self, name: str, folder: Path, tmp: Path, harness: dict[str, Path]):
        self.name, self.folder, self.tmp, self.harness = name, folder, tmp, harness

    def model(self, model: str, ins, outs, u: str) -> float:
        lib, guid, vr = unpack(self.folder / f"{model}.fmu", self.tmp / f"{self.name}-{model}", f"{model}.so")
        target = [lib, guid, ",".join(str(vr[i]) for i in ins), ",".join(str(vr[o]) for o in outs), u]
        short, long = (instructions([self.harness["native_cost"], "step", 1, k, *target]) for k in (STEPS, 2 * STEPS))
        return (long - short) / STEPS

    def line(self, traction: bool) -> float:
        name = "line10-traction" if traction else "line10"
        fmu = self.folder / f"{name}.fmu"
        if (self.folder / "line").is_dir():
            scene = parse_scene(long_line(10, stop=2.0, traction=traction), source=name, fmu_dir=self.folder)
            fmu = linefmu.export(scene, self.tmp / f"{self.name}-{name}.fmu", self.folder)
        folder = self.tmp / f"{self.name}-{name}"
        lib, guid, vr = unpack(fmu, folder, "Line.so")
        run = lambda steps: [self.harness["line_cost"], lib, guid, (folder / "resources").as_uri() + "/",
                             vr["idler0.tau_m"], vr["s0.T"], "1e-3", steps, 1]
        short, long = (instructions(run(k)) for k in LINE_STEPS)
        return (long - short) / (LINE_STEPS[1] - LINE_STEPS[0])


ROLLER_INPUTS = ("web_a.F", "web_b.F", "tau_m")
CASES = {
    "span": lambda b: b.model("ConvertingSpan", ("web_a.v", "web_a.eps", "web_b.v"), ("v", "T"), "5,1e-3,5,0.005"),
    "Roller, reading web_b.v and tau": lambda b: b.model("Roller", ROLLER_INPUTS, ("web_b.v", "tau"), "100,110,0.5,0.1"),
    "Roller, reading web_b.v and omega": lambda b: b.model("Roller", ROLLER_INPUTS, ("web_b.v", "omega"), "100,110,0.5,0.1"),
    "10-span line": lambda b: b.line(False),
    "10-span line, traction": lambda b: b.line(True),
}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("base", type=Path, help="the base build's folder (ConvertingSpan.fmu, Roller.fmu, line/)")
    parser.add_argument("branch", type=Path, help="the branch build's folder, the same files")
    parser.add_argument("--only", action="append", choices=list(CASES), help="measure this case only (repeatable)")
    args = parser.parse_args()
    for folder in (args.base, args.branch):
        if not (folder / "Roller.fmu").is_file():
            parser.error(f"{folder}: no Roller.fmu there (build one with fmu/package.py --host-build --out {folder}/ConvertingSpan.fmu)")
    tmp = Path(tempfile.mkdtemp(prefix="cost-side-by-side-"))
    harness = compile_harnesses(tmp)
    builds = [Build("base", args.base, tmp, harness), Build("branch", args.branch, tmp, harness)]
    print("| instructions per step | base | branch | ratio |")
    print("|---|---:|---:|---:|")
    for name in args.only or CASES:
        base, branch = (CASES[name](b) for b in builds)
        print(f"| {name} | {base:,.1f} | {branch:,.1f} | {branch / base:.3f} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
