#!/usr/bin/env python3
"""Build the webline wheel: out/dist/webline-VERSION-py3-none-any.whl (fmu/main.sh runs it).

    python fmu/wheel.py [--fmus out] [--dist out/dist]

The wheel is webline/ as its own build backend builds it (setuptools, through PyPA's
`python -m build`), with the files webline runs as package data, webline/data: the FMUs
fmu/package.py wrote into out/ (ConvertingSpan.fmu and Roller.fmu, FMI 2.0 and 3.0; the span's
library of webs is inside it), the Line FMU's template (out/line: each platform's library and
line-description, the documentation page) and the shipped scenes (webline/scenes). They are
copied, with webline/ and the README, into a temporary folder the wheel is built from, so that
the repository's webline/ stays as `pip install -e webline` uses it. docs/wheel.md says more.
"""

import argparse
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
# The FMUs and the Line's template, as fmu/package.py leaves them in out/.
FMU_FILES = ["ConvertingSpan.fmu", "Roller.fmu", "fmi3/ConvertingSpan.fmu", "fmi3/Roller.fmu"]
LINE_TEMPLATE = ["line/fmi2/binaries", "line/fmi3/binaries", "line/tools", "line/documentation/index.html"]
# The most the wheel may weigh (docs/wheel.md): a download users wait for, well under PyPI's 100 MB per file.
LIMIT = 30_000_000


def stage(fmus: Path, folder: Path) -> Path:
    """A copy of webline/ with its package data, ready for the build backend."""
    missing = [name for name in FMU_FILES + LINE_TEMPLATE if not (fmus / name).exists()]
    if missing:
        sys.exit(f"wheel.py: {fmus} lacks {', '.join(missing)}: build the FMUs first (bash fmu/main.sh)")
    project = folder / "webline"
    shutil.copytree(ROOT / "webline", project, ignore=shutil.ignore_patterns("__pycache__", "*.egg-info", "tests", "scenes"))
    shutil.copy(ROOT / "README.md", project / "README.md")
    data = project / "src" / "webline" / "data"
    for name in FMU_FILES + LINE_TEMPLATE:
        source, target = fmus / name, data / name
        target.parent.mkdir(parents=True, exist_ok=True)
        (shutil.copytree if source.is_dir() else shutil.copy)(source, target)
    shutil.copytree(ROOT / "webline" / "scenes", data / "scenes")
    return project


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--fmus", type=Path, default=ROOT / "out", help="where fmu/package.py wrote the FMUs (default: out/)")
    parser.add_argument("--dist", type=Path, default=ROOT / "out" / "dist", help="where the wheel goes (default: out/dist/)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="webline-wheel-") as tmp:
        project = stage(args.fmus.resolve(), Path(tmp))
        built = subprocess.run([sys.executable, "-m", "build", "--wheel", "--outdir", str(Path(tmp) / "dist"), str(project)],
                               capture_output=True, text=True)
        if built.returncode != 0:
            sys.exit(f"wheel.py: python -m build failed:\n{built.stdout[-3000:]}{built.stderr[-3000:]}")
        (new,) = (Path(tmp) / "dist").glob("webline-*-py3-none-any.whl")
        size = new.stat().st_size
        if size > LIMIT:
            sys.exit(f"wheel.py: {new.name} is {size / 1e6:.1f} MB, above the {LIMIT / 1e6:.0f} MB the wheel must stay under")
        args.dist.mkdir(parents=True, exist_ok=True)
        for old in args.dist.glob("webline-*.whl"):  # one wheel in dist/: the one just built
            old.unlink()
        wheel = Path(shutil.move(new, args.dist / new.name))
    print(f"wrote {wheel} ({size / 1e6:.1f} MB)")


if __name__ == "__main__":
    main()
