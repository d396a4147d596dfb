"""bench/ holds benchmarks only: no Python file outside it imports from it, by name (`import
line_study` with bench/ on sys.path, `from bench...`) or by path (`ROOT / "bench"` put on
sys.path or loaded as a file). A rule a study and a test share lives in webline."""

import ast
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]


def bench_modules():
    return {p.stem for p in (ROOT / "bench").rglob("*.py")} | {"bench"}


def reaches_into_bench(code: str, modules) -> list[str]:
    """What in `code` imports from bench/: the lines, with what they name."""
    found = []
    for node in ast.walk(ast.parse(code)):
        if isinstance(node, ast.Import):
            found += [f"{node.lineno}: import {a.name}" for a in node.names if a.name.split(".")[0] in modules]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module.split(".")[0] in modules:
            found.append(f"{node.lineno}: from {node.module} import ...")
        elif isinstance(node, ast.BinOp) and isinstance(node.op, ast.Div) and isinstance(node.right, ast.Constant) \
                and str(node.right.value).split("/")[0] == "bench":
            found.append(f"{node.lineno}: the path .../{node.right.value}")
    return sorted(found, key=lambda hit: int(hit.split(":")[0]))


def test_nothing_outside_bench_imports_from_it():
    listed = subprocess.run(["git", "ls-files", "*.py"], cwd=ROOT, capture_output=True, text=True, check=True).stdout.split()
    this = Path(__file__).resolve().relative_to(ROOT).as_posix()  # it names bench/ to list the modules there
    outside = [f for f in listed if not f.startswith("bench/") and f != this and (ROOT / f).exists()]
    assert len(outside) > 50, outside
    modules = bench_modules() - {p.stem for f in outside for p in [Path(f)]}  # a name both sides have is not bench's
    found = {f: hits for f in outside if (hits := reaches_into_bench((ROOT / f).read_text(encoding="utf-8"), modules))}
    assert not found, found


def test_the_check_finds_an_import_from_bench():
    modules = {"line_study", "bench"}
    assert reaches_into_bench('sys.path.insert(0, str(ROOT / "bench"))\nfrom line_study import stability_limit\n', modules) == [
        '1: the path .../bench', "2: from line_study import ..."]
    assert reaches_into_bench("import bench.step_cost\n", modules) == ["1: import bench.step_cost"]
    assert reaches_into_bench('"""bench/line_study.py shows it"""\nfrom webline.accuracy import stability_limit\n', modules) == []
