"""Web records in the webline runner (tests/integration/python/test_records.py: through FMPy).

A scene whose webs are records (shipped and the scene's own file) runs in
webline, bit-identical to the same scene with the numbers written out where
the record is linear, and within its coupling error of the monolithic
reference where the record is a curve.
"""

import json

import numpy as np
from webline import records
from webline.compiler import run_scene
from webline.reference import reference
from webline.scene import parse_scene
from webline.accuracy import errors

from .conftest import ROOT

USER = ROOT / "tests" / "records" / "user_webs.json"


SCENE = """{
  "name": "records", "stop_time": "0.6 s", "step": "1 ms",
  "web_library": "%(library)s",
  "webs": {
    "film": {"record": "PET-50"},
    "laminate": {"record": "PET12-Al9"},
    "paper": {"record": "paper-measured"}
  },
  "line": [
    {"type": "source", "name": "in", "speed": "5 m/s", "strain": 0.001},
    {"type": "span", "name": "a", "L": "1 m", "wp1": "film", "wp2": "laminate"},
    {"type": "roller", "name": "idler", "J": "0.02 kg.m2", "R": "0.05 m", "b": "0.001 N.m.s"},
    {"type": "span", "name": "b", "L": "0.5 m", "web": "paper", "effects": ["includeDamping"], "T_start": "600 N"},
    {"type": "sink", "name": "out", "speed": {"step": {"time": "0.1 s", "from": "5 m/s", "to": "5.02 m/s"}}}
  ]
}"""


def test_a_scene_with_records_runs_in_webline(fmus, tmp_path):
    scene = parse_scene(SCENE % {"library": USER}, "records.json", fmu_dir=fmus)
    assert scene.webs["paper"].curve is not None and scene.webs["film"].record == "PET-50"
    result = run_scene(scene, fmu_dir=fmus)
    # The same line with the linear records' numbers written out.
    film, laminate = (records.shipped_library(fmus / "ConvertingSpan.fmu")[n] for n in ("PET-50", "PET12-Al9"))
    spelled = json.loads(SCENE % {"library": USER})
    for key, r in (("film", film), ("laminate", laminate)):
        spelled["webs"][key] = {"E": f"{r.E!r} Pa", "thickness": f"{r.thickness!r} m", "width": f"{r.width!r} m",
                                "density": f"{r.density!r} kg/m3"}
    same = run_scene(parse_scene(json.dumps(spelled), "spelled.json", fmu_dir=fmus), fmu_dir=fmus)
    assert np.array_equal(result.column("a.T"), same.column("a.T")), "linear records: bit-identical"
    # The curve span against the monolithic reference (SciPy's Radau), at this step's coupling error.
    ref = reference(scene, times=result.time)
    err = errors(result, ref)["b.T"]
    assert err < 5e-3, f"paper span: {err:.1e} from the reference"
    print(f"scene with records: span b within {err:.1e} of the monolithic reference")
