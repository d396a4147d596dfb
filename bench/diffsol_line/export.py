"""Writes the bench's lines (lines/<scene>/line.json and profiles/<part>.json)
from webline's scenes, as `webline export --fmu` puts them in resources/.
Run from the repository, after fmu/package.py (or give the folder of its FMUs):
    PYTHONPATH=webline/src python bench/diffsol_line/export.py [out]"""

import sys
from pathlib import Path

from webline import linefmu
from webline.scene import load_scene
from webline.system import profile_text

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
SCENES = {"splice": ROOT / "webline/scenes/splice.json", "lamination": ROOT / "webline/scenes/lamination.json",
          "ten_spans": HERE / "ten_spans.json"}

fmu_dir = sys.argv[1] if len(sys.argv) > 1 else None
for name, path in SCENES.items():
    scene = load_scene(str(path), fmu_dir=fmu_dir)
    spec = linefmu.line_spec(scene, fmu_dir, "given")
    out = HERE / "lines" / name
    (out / "profiles").mkdir(parents=True, exist_ok=True)
    (out / "line.json").write_text(linefmu.spec_text(spec))
    for part in spec["parts"]:
        if part.get("profile"):
            (out / "profiles" / f"{part['name']}.json").write_text(profile_text(part["profile"]))
    print(out)
