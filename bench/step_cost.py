#!/usr/bin/env python3
"""What one co-simulation step costs, beside the Modelica Reference FMUs' Dahlquist.

    .venv/bin/python bench/step_cost.py [--so LIB.so] [--reference-fmus DIR [--reference-rev REV]]
                                        [--rounds R] [--steps N] [--out docs/performance.md]

The call sequence an importer makes per communication step: set the three
inputs (fmi2SetReal), fmi2DoStep (h = 1 ms), get two outputs (fmi2GetReal),
called from C through dlopen by bench/native_cost.c (its `step` mode); the
elastic scene (5 m/s, strain 0.1 %, roller b's speed oscillating slightly).

  ConvertingSpan  by default `cargo build --release --lib` of this tree
                  (target/release/libconverting_span.so); --so takes another
                  build (its GUID and value references from this tree's
                  modelDescription.xml, or --model-description).
  Dahlquist       the Reference FMUs' Dahlquist (x' = -k x), Co-Simulation with
                  FMI 2.0, compiled here with gcc -O3 -DNDEBUG (what their
                  CMake Release build uses) and FIXED_SOLVER_STEP = 1 ms, so
                  that it takes one Euler step per fmi2DoStep like the span
                  takes one exact step. Its source is not fetched: give a
                  checkout or a git directory of github.com/modelica/Reference-FMUs
                  with --reference-fmus or REFERENCE_FMUS_DIR (for a git
                  directory, --reference-rev picks the revision, default HEAD).
                  Without it only ConvertingSpan is measured. Dahlquist has no
                  inputs: its "three inputs" are its parameter k set three times,
                  its two outputs x and time.

Measured:
  instructions   callgrind (deterministic): two runs of N and 2N sequences
                 (N a multiple of 1024, the period of the input oscillation);
                 their difference divided by N is the exact cost of one
                 sequence, loading and instantiation cancel. Split into the
                 three calls (inclusive) and the harness's loop.
  time           CPU time of the thread per sequence, both FMUs in one process,
                 alternating rounds (every round runs each once); the medians
                 over the rounds and their ratio, the fastest rounds and theirs
                 (steadier when the machine is busy), the ratio in each round.
  breakdown      where ConvertingSpan's instructions go, from a build with debug
                 symbols (target/symbols, CARGO_PROFILE_RELEASE_DEBUG=true,
                 STRIP=false): every executed instruction is charged to the
                 innermost function of this crate that it was inlined into
                 (addr2line -i), and the functions are grouped by GROUPS below.

Prints the tables and writes them with this command to docs/performance.md.
Numbers for people to read, not assertions.
"""

import argparse
import os
import re
import shutil
import statistics
import subprocess
import sys
import xml.etree.ElementTree as ET
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "target" / "step_cost"
SYMBOLS_TARGET = ROOT / "target" / "symbols"
LIB_NAME = "libconverting_span.so"
INPUTS, OUTPUTS = ("web_a.v", "web_a.eps", "web_b.v"), ("v", "T")
# u = {a, b, c + d*(k mod 1024)/1024}: the elastic scene, roller b's speed oscillating by 0.1 %
SPAN_U = "5,1e-3,5,0.005"
# k (vr 3) set three times, small enough that x never becomes subnormal; x (vr 1) and time (vr 0) read
DAHLQUIST_IO = ("3,3,3", "1,0", "1e-4,1e-4,1e-4,1e-5")
DAHLQUIST_STEP = "1e-3"
CALLS = ("fmi2SetReal", "fmi2DoStep", "fmi2GetReal")

# Where ConvertingSpan's instructions go: the innermost function of this crate
# an instruction belongs to (after inlining), matched in order; the first
# pattern that matches the function's name (or, for "model", its file) wins.
GROUPS = [
    ("entry and exit: tag and poison checks, catch_unwind, status mapping, argument pointers",
     r"^fmi_abi::|^handle::(enter|handle)\b|^raw::|^fmi2\w+$|is_allowed_when_poisoned"
     r"|Instance::fail\b|traces_calls|LogFilter"),
    ("state mask: is the call allowed in this phase", r"Instance::(begin|prepare_get|check_computable)\b|\b(Call|Phase)::"),
    ("time checks in do_step", r"Instance::(do_step|check_step)\b"),
    ("input checks: finite and in range", r"Instance::set_reals::\{\{closure\}\}|Range::contains|out_of_range"),
    ("value-reference lookup: table, family, settable, from_vr, field match",
     r"ModelDescription::variable\b|Instance::variable\b|Family::of|check_settable|wrong_variable|::from_vr"
     r"|<\w+ as Model>::(get|set)_real\b|Variables for \w+>::(get|set)_real\b|ConvertingSpan::(real|real_field|set_real_var)$|input_field"
     r"|<(Causality|Variability|Initial|Kind) as PartialEq>"),
    ("get/set loops", r"Instance::(get_reals|set_reals|set_all)$"),
    ("model arithmetic: the step and the outputs (libm included)", r"^src/|^numerics/|^libm"),
]
OTHER = "other"


def sh(cmd, **kw):
    return subprocess.run(cmd, check=True, **kw)


def fmpy_headers():
    import fmpy
    return Path(fmpy.__file__).parent / "c-code"


def harness():
    exe = OUT / "native_cost"
    sh(["gcc", "-O2", "-Wall", "-Wextra", "-Werror", f"-I{fmpy_headers()}", f"-I{ROOT / 'tests' / 'integration' / 'c_importer'}", str(ROOT / "bench" / "native_cost.c"), "-o", str(exe), "-ldl"])
    return exe


def cargo_build(target_dir, symbols=False):
    env = dict(os.environ, CARGO_TARGET_DIR=str(target_dir))
    if symbols:
        env.update(CARGO_PROFILE_RELEASE_DEBUG="true", CARGO_PROFILE_RELEASE_STRIP="false")
    sh(["cargo", "build", "--release", "--lib", "--quiet"], cwd=ROOT, env=env)
    return Path(target_dir) / "release" / LIB_NAME


def has_symbols(lib):
    out = subprocess.run(["readelf", "-S", "-W", str(lib)], capture_output=True, text=True).stdout
    return ".debug_info" in out and ".symtab" in out


def span_target(lib, md):
    root = ET.parse(md).getroot()
    vrs = {v.get("name"): v.get("valueReference") for v in root.iter("ScalarVariable")}
    return [str(lib), root.get("guid"), ",".join(vrs[n] for n in INPUTS), ",".join(vrs[n] for n in OUTPUTS), SPAN_U]


def reference_sources(path, rev):
    """A directory holding Dahlquist/, include/ and src/ of the Reference FMUs:
    `path` itself, or exported from it with git archive when it is a git directory.
    Returns it and the version (git describe) when known."""
    path = Path(path)
    if (path / "Dahlquist" / "model.c").exists():
        return path, None
    tree = OUT / "reference-fmus"
    shutil.rmtree(tree, ignore_errors=True)
    tree.mkdir(parents=True)
    git = ["git", f"--git-dir={path}"] if (path / "objects").is_dir() else ["git", "-C", str(path)]
    archive = subprocess.run([*git, "archive", rev, "Dahlquist", "include", "src"], check=True, capture_output=True).stdout
    sh(["tar", "-x", "-C", str(tree)], input=archive)
    def describe(*how):
        return subprocess.run([*git, "describe", "--tags", *how, rev], capture_output=True, text=True).stdout.strip()
    # a release's name, never a commit's: "v0.0.41", or "v0.0.41+" for a revision after it
    version = describe("--exact-match") or (describe("--abbrev=0") + "+" if describe("--abbrev=0") else "")
    return tree, version or None


def build_dahlquist(src):
    """Dahlquist's FMI 2.0 library with a 1 ms fixed step: its config.h (and
    model.c, which includes it from its own folder) copied and patched."""
    build = OUT / "dahlquist"
    shutil.rmtree(build, ignore_errors=True)
    build.mkdir(parents=True)
    for f in (src / "Dahlquist").iterdir():
        if f.suffix in (".c", ".h"):
            shutil.copy(f, build / f.name)
    config = build / "config.h"
    text, n = re.subn(r"^#define FIXED_SOLVER_STEP .*$", f"#define FIXED_SOLVER_STEP {DAHLQUIST_STEP}", config.read_text(), flags=re.M)
    if n != 1:
        sys.exit(f"{src}/Dahlquist/config.h: no FIXED_SOLVER_STEP to set")
    config.write_text(text)
    lib = build / "Dahlquist.so"
    sh(["gcc", "-O3", "-DNDEBUG", "-shared", "-fPIC", "-DFMI_VERSION=2", "-DDISABLE_PREFIX", f"-I{build}", f"-I{src / 'include'}",
        str(src / "src" / "fmi2Functions.c"), str(build / "model.c"), str(src / "src" / "cosimulation.c"), "-o", str(lib), "-lm"])
    guid = ET.parse(src / "Dahlquist" / "FMI2.xml").getroot().get("guid")
    return [str(lib), guid, *DAHLQUIST_IO]


# --------------------------------------------------------------------------
# callgrind


def parse_callgrind(path):
    """Self cost per (object, function, instruction address) and the inclusive
    cost of the harness's calls into CALLS, from a callgrind file written with
    --dump-instr=yes (positions: instr line)."""
    names = {"ob": {}, "fn": {}}
    self_cost, inclusive = defaultdict(int), defaultdict(int)
    ob = fn = cfn = None
    in_call, addr = False, 0

    def name(kind, rest):
        m = re.match(r"\((\d+)\)(?: (.*))?$", rest)
        if not m:
            return rest
        if m.group(2) is not None:
            names[kind][m.group(1)] = m.group(2)
        return names[kind][m.group(1)]

    for line in Path(path).read_text().splitlines():
        c = line[:1]
        if c.isdigit() or c in ("+", "-", "*"):
            parts = line.split()
            p = parts[0]
            addr = int(p, 16) if p.startswith("0x") else addr if p == "*" else addr + int(p) if c in "+-" else int(p)
            cost = int(parts[2]) if len(parts) > 2 else 0
            if in_call:    # the inclusive cost of the call on the line before
                if cfn in CALLS and ob.endswith("/native_cost"):
                    inclusive[cfn] += cost
                in_call = False
            else:
                self_cost[(ob, fn, addr)] += cost
            continue
        key, _, rest = line.partition("=")
        if key == "ob":
            ob = name("ob", rest)
        elif key == "fn":
            fn = name("fn", rest)
        elif key == "cob":
            name("ob", rest)
        elif key == "cfn":
            cfn = name("fn", rest)
        elif key == "calls":
            in_call = True
    return self_cost, inclusive


def callgrind(exe, target, steps, out):
    sh(["valgrind", "--tool=callgrind", "--dump-instr=yes", f"--callgrind-out-file={out}", str(exe), "step", "1", str(steps), *target],
       capture_output=True)
    return parse_callgrind(out)


def instructions(exe, target, label, n):
    """Per sequence: the total, each call's inclusive cost, and the self cost
    per (object, function, address), as the difference of runs of n and 2n."""
    runs = [callgrind(exe, target, k, OUT / f"callgrind.{label}.{k}") for k in (n, 2 * n)]
    (s1, i1), (s2, i2) = runs
    per_addr = {k: (s2.get(k, 0) - s1.get(k, 0)) / n for k in set(s1) | set(s2)}
    per_addr = {k: v for k, v in per_addr.items() if v}
    calls = {c: (i2[c] - i1[c]) / n for c in CALLS}
    return {"total": sum(per_addr.values()), "calls": calls, "per_addr": per_addr}


def inline_chains(lib, addrs):
    """addr2line -i: for each address the inlined frames, innermost first, as
    (function, file:line)."""
    out = subprocess.run(["addr2line", "-a", "-f", "-i", "-C", "-e", str(lib)], input="\n".join(f"{a:#x}" for a in addrs),
                         check=True, capture_output=True, text=True).stdout.splitlines()
    chains, current, i = {}, None, 0
    while i < len(out):
        if re.fullmatch(r"0x[0-9a-f]+", out[i]):    # -a: the address, then its frames as function, file:line
            current = int(out[i], 16)
            chains[current] = []
            i += 1
        else:
            chains[current].append((out[i], out[i + 1]))
            i += 2
    return chains


def crate_frame(chain):
    """The innermost frame that belongs to this crate (its source under the
    tree's src/ or the generated model description), else the outermost."""
    for function, where in chain:
        if where.startswith(str(ROOT / "src")) or "/out/model_description.rs" in where:
            return function, where
    return chain[-1] if chain else ("??", "??:0")


def readable(function):
    """`converting_span::fmi2::instance::values::<impl converting_span::fmi2::instance::Instance>::set_all`
    -> `Instance::set_all`: generic parameters and module paths before a type dropped, the crate's name dropped."""
    function = re.sub(r"<[A-Z]\w*(?:, [A-Z]\w*)*>", "", function)   # generic parameters: Instance<M>
    function = re.sub(r"<impl ([\w:]+)>", r"\1", function)
    function = re.sub(r"\b(?:[a-z_][a-z0-9_]*::)+(?=[A-Z])", "", function)
    return function.replace("converting_span::", "")


def breakdown(per_addr, lib):
    """Instructions per sequence by function of this crate (instructions of
    other objects by object and symbol) and by group."""
    ours = Path(lib).resolve()
    addrs = sorted({a for (ob, _, a) in per_addr if ob and Path(ob).resolve() == ours})
    chains = inline_chains(lib, addrs)
    by_function, files = defaultdict(float), defaultdict(lambda: defaultdict(float))
    for (ob, fn, addr), cost in per_addr.items():
        obname = Path(ob or "?").name
        if ob and Path(ob).resolve() == ours:
            function, where = crate_frame(chains.get(addr, []))
            function = readable(function) if function != "??" else f"{fn} (no line info)"
            where = where.rsplit(":", 1)[0]
            where = ("model_description.rs (generated by build.rs)" if where.endswith("/out/model_description.rs")
                     else os.path.relpath(where, ROOT) if where.startswith(str(ROOT)) else Path(where).name)
        elif obname == "native_cost":
            function, where = "the harness's loop", "bench/native_cost.c"
        else:
            function, where = f"{obname.split('.so')[0]}: {fn}", obname
        by_function[function] += cost
        files[function][where] += cost
    rows = []
    for function, cost in by_function.items():
        where = max(files[function].items(), key=lambda kv: kv[1])[0]
        group = "the harness's loop (both FMUs pay it)" if where == "bench/native_cost.c" else OTHER
        for g, pattern in GROUPS if group == OTHER else []:
            if re.search(pattern, function) or re.search(pattern, where):
                group = g
                break
        rows.append({"function": function, "file": where, "group": group, "instructions": cost})
    rows.sort(key=lambda r: -r["instructions"])
    groups = defaultdict(float)
    for r in rows:
        groups[r["group"]] += r["instructions"]
    return rows, dict(sorted(groups.items(), key=lambda kv: -kv[1]))


# --------------------------------------------------------------------------
# time


def timing(exe, targets, rounds, steps):
    """ns per sequence of every target in every round; the rounds alternate the targets."""
    out = subprocess.run([str(exe), "step", str(rounds), str(steps), *sum(targets, [])], check=True, capture_output=True,
                         text=True).stdout.splitlines()
    return [[float(x) for x in line.split()[1:1 + rounds]] for line in out]


# --------------------------------------------------------------------------
# report


def fmt(x, digits=0):
    return f"{x:,.{digits}f}"


def report(res, command):
    """docs/performance.md: the tables and the command that regenerates them."""
    ours, dq = res["ours"], res.get("dahlquist")
    L = ["# Performance", ""]
    L.append("What one communication step costs an importer: set the three inputs (`fmi2SetReal`), `fmi2DoStep` with "
             "h = 1 ms, get two outputs (`fmi2GetReal`), called natively from C through `dlopen` "
             "(`bench/native_cost.c`); the elastic scene (1 m span at 5 m/s, strain 0.1 %, roller b's speed varying by 0.1 %).")
    if dq:
        version = f" {dq['version']}" if dq.get("version") else ""
        L.append("")
        L.append(f"Beside it, the same calls on the [Modelica Reference FMUs](https://github.com/modelica/Reference-FMUs)'"
                 f"{version} `Dahlquist` (x' = -k x; FMI 2.0 Co-Simulation, compiled with `gcc -O3 -DNDEBUG` and "
                 "`FIXED_SOLVER_STEP` = 1 ms, so that it takes one Euler step per `fmi2DoStep`; its three \"inputs\" are its "
                 "parameter `k`, its two outputs `x` and `time`).")
    L += ["", "Regenerate this file (it is written by the command):", "", "```sh", command, "```", "",
          "Without `--reference-fmus` (or `REFERENCE_FMUS_DIR`: a checkout or a git directory of the Reference FMUs) only "
          "ConvertingSpan is measured; `--so LIB.so` measures another build of it.", ""]
    L.append("Target: at most 700 instructions per sequence with every check kept. With two copies of the C boundary "
             "(FMI 2 and FMI 3 apart) and their forwarding calls the sequence took 1,020; one boundary whose hot paths "
             "are inlined into the exports brought it under the target.")
    L += ["", "## Instructions per sequence", ""]
    L.append("Counted by callgrind, which is deterministic: the difference of two runs of "
             f"{fmt(res['callgrind_steps'])} and {fmt(2 * res['callgrind_steps'])} sequences, divided by "
             f"{fmt(res['callgrind_steps'])}, so that loading and instantiation cancel; the calls inclusive of what they call.")
    L.append("")
    head = "| | ConvertingSpan |" + (" Dahlquist, 1 ms | ratio |" if dq else "")
    L += [head, "|---|---:|" + ("---:|---:|" if dq else "")]
    rows = [("whole sequence", "total")] + [(f"`{c}`" + {"fmi2SetReal": " (3 values)", "fmi2GetReal": " (2 values)"}.get(c, ""), c)
                                            for c in CALLS] + [("the harness's loop", "loop")]
    for label, key in rows:
        a = ours["instructions"][key]
        line = f"| {label} | {fmt(a)} |"
        if dq:
            b = dq["instructions"][key]
            line += f" {fmt(b)} | {a / b:.2f} |"
        L.append(line)
    L += ["", "## Time per sequence", ""]
    L.append(f"The thread's CPU time, both FMUs in one process, {res['rounds']} alternating rounds of {fmt(res['steps'])} "
             "sequences (every round runs each FMU once, on a fresh instance). Times depend on the machine"
             + ("; the ratio, measured side by side, less so. Yet when other processes compete for the cores, both times grow "
                "and their ratio drops (Dahlquist's calls slow down more); when that load comes and goes, the fastest rounds "
                "are the nearest to an idle machine." if dq else "."))
    L.append("")
    L += [head, "|---|---:|" + ("---:|---:|" if dq else "")]
    for label, key in (("ns per sequence, median", "median"), ("ns per sequence, fastest round", "min")):
        a = ours["ns"][key]
        line = f"| {label} | {a:.1f} |"
        if dq:
            line += f" {dq['ns'][key]:.1f} | {'**' if key == 'median' else ''}{a / dq['ns'][key]:.2f}{'**' if key == 'median' else ''} |"
        L.append(line)
    if dq:
        r = res["round_ratio"]
        L.append(f"| ratio in each round: median (lowest – highest) | | | {r['median']:.2f} ({r['min']:.2f} – {r['max']:.2f}) |")
    b = res["breakdown"]
    L += ["", "## Where ConvertingSpan's instructions go", ""]
    L.append("From a build with debug symbols (`CARGO_PROFILE_RELEASE_DEBUG=true CARGO_PROFILE_RELEASE_STRIP=false`, "
             f"target/symbols; {fmt(b['total'])} instructions per sequence against {fmt(ours['instructions']['total'])} for the "
             "release build measured above). Every instruction executed per sequence is charged to the innermost function of "
             "this crate it was inlined into (`addr2line -i`), the standard library's code (`catch_unwind`, iterators, "
             "`f64::is_finite`) to the function that uses it; the functions are grouped by the patterns in `GROUPS` "
             "(bench/step_cost.py).")
    L += ["", "| group | instructions | share |", "|---|---:|---:|"]
    for g, v in b["groups"].items():
        if abs(v) < 0.5:    # the harness parsing and printing numbers of other lengths: < 0.01 per sequence
            continue
        L.append(f"| {g} | {fmt(v)} | {100 * v / b['total']:.0f} % |")
    L.append(f"| **all** | **{fmt(b['total'])}** | |")
    L += ["", "By function (at least 1 instruction per sequence):", "", "| function | file | group | instructions |",
          "|---|---|---|---:|"]
    for r in b["rows"]:
        if r["instructions"] >= 0.95:
            group = r["group"].split(":")[0]
            L.append(f"| `{r['function']}` | {r['file']} | {group} | {fmt(r['instructions'])} |")
    return "\n".join(L) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--so", type=Path, help="the ConvertingSpan library to measure (default: cargo build --release of this "
                    "tree); the breakdown comes from it if it has debug symbols, else from this tree's build with symbols")
    ap.add_argument("--model-description", type=Path, default=ROOT / "modelDescription.xml",
                    help="its modelDescription.xml (GUID, value references)")
    ap.add_argument("--reference-fmus", type=Path, default=os.environ.get("REFERENCE_FMUS_DIR"),
                    help="a checkout or git directory of the Modelica Reference FMUs (default: $REFERENCE_FMUS_DIR)")
    ap.add_argument("--reference-rev", default="HEAD", help="the revision to build when --reference-fmus is a git directory")
    ap.add_argument("--rounds", type=int, default=101, help="alternating timing rounds (median reported)")
    ap.add_argument("--steps", type=int, default=200_000, help="sequences per timing round")
    ap.add_argument("--callgrind-steps", type=int, default=10240, help="N: callgrind counts runs of N and 2N sequences")
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "performance.md", help="the Markdown file to write")
    ap.add_argument("--no-write", action="store_true", help="print only")
    args = ap.parse_args()
    if args.callgrind_steps % 1024:
        ap.error("--callgrind-steps must be a multiple of 1024 (the period of the input oscillation)")
    for tool in ("gcc", "valgrind", "addr2line", "readelf"):
        if not shutil.which(tool):
            sys.exit(f"{tool} is needed (apt-get install {'binutils' if tool in ('addr2line', 'readelf') else tool})")
    OUT.mkdir(parents=True, exist_ok=True)

    exe = harness()
    lib = args.so.resolve() if args.so else cargo_build(ROOT / "target")
    symbols = lib if has_symbols(lib) else cargo_build(SYMBOLS_TARGET, symbols=True)
    targets = {"ours": span_target(lib, args.model_description)}
    res = {"callgrind_steps": args.callgrind_steps, "rounds": args.rounds, "steps": args.steps}
    if args.reference_fmus:
        src, version = reference_sources(args.reference_fmus, args.reference_rev)
        targets["dahlquist"] = build_dahlquist(src)
        res["dahlquist"] = {"version": version}
    else:
        print("no Reference FMUs given (--reference-fmus or REFERENCE_FMUS_DIR): measuring ConvertingSpan only", flush=True)
    res["ours"] = {}

    print(f"callgrind: {args.callgrind_steps} and {2 * args.callgrind_steps} sequences ...", flush=True)
    n = args.callgrind_steps
    for name, target in targets.items():
        counts = instructions(exe, target, name, n)
        res[name]["instructions"] = {"total": counts["total"], **counts["calls"],
                                     "loop": counts["total"] - sum(counts["calls"].values())}
    counts = instructions(exe, span_target(symbols, args.model_description), "symbols", n)
    rows, groups = breakdown(counts["per_addr"], symbols)
    res["breakdown"] = {"total": counts["total"], "rows": rows, "groups": groups}

    print(f"time: {args.rounds} alternating rounds of {args.steps} sequences ...", flush=True)
    ns = timing(exe, list(targets.values()), args.rounds, args.steps)
    for name, values in zip(targets, ns):
        res[name]["ns"] = {"median": statistics.median(values), "min": min(values), "max": max(values), "rounds": values}
    if "dahlquist" in targets:
        ratios = [a / b for a, b in zip(ns[0], ns[1])]
        res["round_ratio"] = {"median": statistics.median(ratios), "min": min(ratios), "max": max(ratios)}

    command = ".venv/bin/python bench/step_cost.py"
    if "dahlquist" in targets:
        command += " --reference-fmus PATH/TO/Reference-FMUs" + (f" --reference-rev {args.reference_rev}" if args.reference_rev != "HEAD" else "")
    text = report(res, command)
    print(text)
    ours = res["ours"]
    summary = f"ConvertingSpan: {ours['instructions']['total']:.0f} instructions, {ours['ns']['median']:.1f} ns per sequence"
    if "dahlquist" in targets:
        dq = res["dahlquist"]
        summary += (f"; Dahlquist: {dq['instructions']['total']:.0f} instructions, {dq['ns']['median']:.1f} ns; ratio "
                    f"{ours['instructions']['total'] / dq['instructions']['total']:.2f} in instructions, "
                    f"{ours['ns']['median'] / dq['ns']['median']:.2f} in time")
    print(summary)
    if not args.no_write:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(text)
        print(f"written: {os.path.relpath(args.out, Path.cwd())}")


if __name__ == "__main__":
    sys.exit(main())
