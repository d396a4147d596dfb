"""Scenes and the runner: the shipped scenes, strict parsing (every error names
the key and the file position), the complete example of docs/scenes.md, and the
`webline` command (CSV, PNG, summary, Jacobi, rollback on a discarded step).
"""

import re
import subprocess
import sys

import numpy as np
import pytest
from webline.compiler import run_scene
from webline.scene import SceneError, load_scene, parse_scene

from .conftest import ROOT, SCENES



# A small valid scene the error tests start from (line numbers below refer to it).
BASE = """{
  "name": "small",
  "stop_time": "0.2 s",
  "step": "1 ms",
  "webs": {"PET": {"E": "4.5 GPa", "thickness": "50 um", "width": "1 m", "density": "1390 kg/m3"}},
  "line": [
    {"type": "source", "name": "in", "speed": "5 m/s", "strain": 0.001},
    {"type": "span", "name": "a", "L": "1 m", "web": "PET"},
    {"type": "roller", "name": "idler", "J": "0.02 kg.m2", "R": "0.05 m"},
    {"type": "span", "name": "b", "L": "1 m", "web": "PET"},
    {"type": "sink", "name": "out", "speed": {"step": {"time": "0.1 s", "from": "5 m/s", "to": "5.005 m/s"}}}
  ]
}
"""


def test_shipped_scenes_parse_and_use_only_their_effects():
    expected = {
        "lamination": {"includeDamping"},
        "emergency_stop": {"preventNegativeTension"},
        "dancer": {"variableLength"},
        "splice": set(),
        "laminator": {"includeDamping"},
        "slitter": {"includeDamping"},
        "idler_skid": {"includeDamping"},
    }
    found = {p.stem for p in SCENES.glob("*.json")}
    assert set(expected) <= found
    for name, effects in expected.items():
        s = load_scene(SCENES / f"{name}.json")
        used = {e for sp in s.spans for e in sp.effects}
        assert used == effects, (name, used)
        assert s.description
    lam = load_scene(SCENES / "lamination.json")
    conv = [sp for sp in lam.spans if sp.wp1 != sp.wp2]
    assert conv and conv[0].wp1.name == "PET" and conv[0].wp2.name == "PET/Al", "the film meets the laminate"
    assert len(load_scene(SCENES / "splice.json").events) == 5
    # Webs that merge and split: side paths beside the main line (docs/merge-split.md).
    assert [b.kind for b in load_scene(SCENES / "laminator.json").branches] == ["merge"]
    assert [b.kind for b in load_scene(SCENES / "slitter.json").branches] == ["split", "split"]


def test_base_scene_is_valid():
    s = parse_scene(BASE, "base.json")
    assert [c.type for c in s.line] == ["source", "span", "roller", "span", "sink"]
    assert s.breakpoints() == [0.1]


def _error(text):
    with pytest.raises(SceneError) as e:
        parse_scene(text, "base.json")
    return str(e.value)


@pytest.mark.parametrize(
    "old,new,position,words",
    [
        # an unknown key, at the key
        ('"L": "1 m", "web": "PET"}', '"L": "1 m", "web": "PET", "lenght": "2 m"}', "8:", ["unknown key 'lenght'", "span 'a'"]),
        # a wrong unit, at the value
        ('"L": "1 m", "web": "PET"}', '"L": "1 s", "web": "PET"}', "8:40", ["'1 s' is a time", "a length"]),
        # a bare number where a unit is needed
        ('"J": "0.02 kg.m2"', '"J": 0.02', "9:46", ["has no unit", "kg.m2"]),
        # an unknown unit
        ('"R": "0.05 m"', '"R": "0.05 furlong"', "9:", ["unknown unit 'furlong'"]),
        # a missing value
        ('"speed": "5 m/s", "strain": 0.001', '"speed": "5 m/s"', "7:5", ["needs the key 'strain'"]),
        # a missing web property
        ('"density": "1390 kg/m3"', '"d_r": "1 ms"', "5:", ["needs the key 'density'"]),
        # an unknown effect
        ('"L": "1 m", "web": "PET"}', '"L": "1 m", "web": "PET", "effects": ["includeInk"]}', "8:", ["unknown effect 'includeInk'"]),
        # a chain that is not a line
        ('{"type": "roller", "name": "idler"', '{"type": "span", "name": "idler"', "9:", ["must be one of: roller, dancer"]),
        # a decreasing table
        ('"speed": "5 m/s", "strain"', '"speed": {"table": [["1 s", "5 m/s"], ["0.5 s", "4 m/s"]]}, "strain"', "7:", ["times must not decrease"]),
        # a duplicate key
        ('"name": "small",', '"name": "small", "name": "big",', "2:", ["appears twice"]),
        # a syntax error
        ('"stop_time": "0.2 s",', '"stop_time": "0.2 s"', "4:", ["expected"]),
        # a negative length
        ('"L": "1 m", "web": "PET"}', '"L": "-1 m", "web": "PET"}', "8:", ["must be > 0"]),
    ],
)
def test_errors_name_the_key_and_the_position(old, new, position, words):
    assert old in BASE
    msg = _error(BASE.replace(old, new, 1))
    assert msg.startswith(f"base.json:{position}"), msg
    for w in words:
        assert w in msg, msg


def test_more_scene_errors():
    assert "no web 'PE'" in _error(BASE.replace('"web": "PET"}', '"web": "PE"}', 1))
    assert "record: span 'a' records" in _error(BASE.replace('"line": [', '"record": ["a.v"],\n  "line": [', 1))
    assert "variableLength needs a dancer" in _error(BASE.replace('"web": "PET"}', '"web": "PET", "effects": ["variableLength"]}', 1))
    assert "time must be inside the run" in _error(
        BASE.replace('"line": [', '"events": [{"time": "5 s", "component": "a", "set": {"web": "PET"}}],\n  "line": [', 1)
    )
    assert "has no properties to change" in _error(
        BASE.replace('"line": [', '"events": [{"time": "0.1 s", "component": "in", "set": {"J": "1 kg.m2"}}],\n  "line": [', 1)
    )
    # Overrides (the sweep's) must name something that is there.
    path = SCENES / "lamination.json"
    with pytest.raises(SceneError, match="no 'Lx'"):
        load_scene(path, {"line.film.Lx": "2 m"})
    assert load_scene(path, {"line.film.L": "2 m"}).component("film").length == 2.0


def test_the_documented_example_is_a_valid_scene(tmp_path):
    doc = (ROOT / "docs" / "scenes.md").read_text()
    m = re.search(r"<!-- scene example -->\s*```json\n(.*?)```", doc, re.S)
    assert m, "the complete scene example of docs/scenes.md (marked <!-- scene example -->) is missing"
    s = parse_scene(m.group(1), "docs/scenes.md example")
    assert s.spans and s.nodes
    m = re.search(r"<!-- merge split example -->\s*```json\n(.*?)```", doc, re.S)
    assert m, "the merge and split example of docs/scenes.md (marked <!-- merge split example -->) is missing"
    s = parse_scene(m.group(1), "docs/scenes.md merge and split example")
    assert [b.kind for b in s.branches] == ["merge", "split"]


def test_runner_writes_csv_png_and_a_summary(fmus, tmp_path):
    scene = tmp_path / "small.json"
    scene.write_text(BASE)
    cmd = [sys.executable, "-m", "webline", "run", str(scene), "--out", str(tmp_path), "--no-progress"]
    p = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, check=True)
    assert "small: engine line: Line FMU in FMPy, Co-Simulation, step 1 ms, 200 steps" in p.stdout
    assert re.search(r"^\s+a\s+[\d.]+", p.stdout, re.M), p.stdout
    header = (tmp_path / "small.csv").read_text().splitlines()[0]
    assert header == "time [s],a.T [N],b.T [N],in.v [m/s],idler.v [m/s],out.v [m/s]"
    assert (tmp_path / "small.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # A bad scene: exit code 2 and the position.
    scene.write_text(BASE.replace('"1 m", "web"', '"1 s", "web"', 1))
    p = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    assert p.returncode == 2 and "small.json:8:" in p.stderr, p.stderr


def test_jacobi_and_gauss_seidel_agree_on_a_gentle_line(fmus):
    s = parse_scene(BASE, "base.json")
    gs = run_scene(s, fmu_dir=fmus, step=2.5e-4)
    jac = run_scene(s, fmu_dir=fmus, step=2.5e-4, algorithm="jacobi")
    for k in ("a.T", "b.T"):
        scale = np.max(np.abs(gs.column(k)))
        assert np.max(np.abs(gs.column(k) - jac.column(k))) / scale < 1e-3


ONE_SPAN = """{
  "name": "short", "stop_time": "0.05 s", "step": "1 ms",
  "webs": {"PET": {"E": "4.5 GPa", "thickness": "50 um", "width": "1 m", "density": "1390 kg/m3"}},
  "line": [
    {"type": "source", "name": "in", "speed": "5 m/s", "strain": 0.001},
    {"type": "span", "name": "s", "L": "2 mm", "web": "PET", SOLVER},
    {"type": "sink", "name": "out", "speed": {"step": {"time": "0.01 s", "from": "5 m/s", "to": "5.005 m/s"}}}
  ]
}"""


def test_a_discarded_step_is_rolled_back_and_halved(fmus):
    """An explicit Euler span with one substep discards steps beyond its
    stability limit (lambda*h = v/L*h = 2.5 at h = 1 ms, above 2); the master
    restores every FMU and retries with half steps until they pass."""
    euler = parse_scene(ONE_SPAN.replace("SOLVER", '"solver": "euler", "substeps": 1'), "euler.json")
    exact = parse_scene(ONE_SPAN.replace("SOLVER", '"solver": "exact"'), "exact.json")
    r = run_scene(euler, fmu_dir=fmus)
    assert r.info["rollbacks"] > 0
    e = run_scene(exact, fmu_dir=fmus)
    assert e.info["rollbacks"] == 0
    # Euler on the halved steps (lambda*h = 1.25) is first order: near the exact step, not on it.
    scale = np.max(np.abs(e.column("s.T")))
    err = np.max(np.abs(r.column("s.T") - e.column("s.T"))) / scale
    assert 1e-6 < err < 0.05, err
    with pytest.raises(Exception, match="rollback is off"):
        run_scene(euler, fmu_dir=fmus, rollback=False)


def test_events_change_parameters_inside_the_fmus(fmus):
    """The splice's five events are `set` entries of the components' profiles:
    one instance per component for the whole run, the state kept."""
    s = load_scene(SCENES / "splice.json", {"stop_time": "1.6 s"})
    r = run_scene(s, fmu_dir=fmus)
    assert len(r.info["events"]) == 5 and r.info["instances"] == 5
    # The roll's surface speed is continuous through the roll change at 1 s.
    v = r.column("unwind.v")
    i = int(np.argmin(np.abs(r.time - 1.0)))
    assert abs(v[i + 1] - v[i]) < 1e-3
    assert r.column("unwind.omega")[i + 1] == pytest.approx(v[i + 1] / 0.3, rel=1e-9)


CASES = ROOT / "webline" / "tests" / "cases"


def test_webs_may_name_webs_defined_later():
    """A laminate defined before its layers (laminate_defined_first.json: PET/Al/paper, paper last)
    reads as the same web as with its layers first; the file's order of the webs is kept."""
    path = CASES / "laminate_defined_first.json"
    later = load_scene(path)
    assert list(later.webs) == ["PET", "Al", "PETAl", "paper"]
    assert later.webs["PETAl"].layer_names == ("PET", "Al", "paper")
    import json

    data = json.loads(path.read_text())
    data["webs"] = {k: data["webs"][k] for k in ("PET", "Al", "paper", "PETAl")}
    first = parse_scene(json.dumps(data, indent=1), "layers_first.json")
    assert later.webs["PETAl"] == first.webs["PETAl"]


@pytest.mark.parametrize("webs,words", [
    # a missing web names every web that is defined, later ones too
    ('"L1": {"laminate": ["PET", "PE"]}, "PET2": {"slit": "PET", "width": "0.5 m"}',
     ["web 'L1': laminate layer: no web 'PE'", "defined: PET, L1, PET2"]),
    # a web made of itself, directly or through another
    ('"L1": {"laminate": ["PET", "L1"]}', ["web 'L1' is made of itself (L1 -> L1)"]),
    ('"L1": {"laminate": ["PET", "L2"]}, "L2": {"slit": "L1", "width": "0.5 m"}', ["(L1 -> L2 -> L1)"]),
])
def test_a_missing_or_self_referring_web_names_the_problem(webs, words):
    text = BASE.replace('"density": "1390 kg/m3"}}', f'"density": "1390 kg/m3"}}, {webs}}}', 1)
    msg = _error(text)
    assert msg.startswith("base.json:5:"), msg
    for w in words:
        assert w in msg, msg


def test_a_backward_source_is_refused_by_name_before_any_arithmetic():
    """A side source running backwards (the laminator's foil at -5 m/s) is refused at its speed's position;
    before, NumPy's divide-by-zero warnings came first, then an `eps_start = -2.0003 outside range`."""
    import warnings

    text = (CASES / "laminator_unequal_sources.json").read_text()
    assert '"speed": "5.001 m/s"' in text
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no warning on the way
        with pytest.raises(SceneError) as e:
            parse_scene(text.replace('"speed": "5.001 m/s"', '"speed": "-5 m/s"'), "backward.json")
    msg = str(e.value)
    assert msg.startswith("backward.json:52:16: source 'src_foil': speed -5 m/s at t = 0 s"), msg
    assert "must be >= 0" in msg


@pytest.mark.parametrize("old,new,words", [
    # a sink at rest under a moving source: the span would hold no web
    ('"sink", "name": "out", "speed": {"step": {"time": "0.1 s", "from": "5 m/s"', '"sink", "name": "out", "speed": {"step": {"time": "0.1 s", "from": "0 m/s"',
     ["base.json:11:5: sink 'out' stands still at the start", "span 'b'", "T_start or eps_start"]),
    # a sink running backwards against the line
    ('"sink", "name": "out", "speed": {"step": {"time": "0.1 s", "from": "5 m/s"', '"sink", "name": "out", "speed": {"step": {"time": "0.1 s", "from": "-5 m/s"',
     ["base.json:11:5: sink 'out' runs backwards at the start (-5 m/s)", "span 'b'"]),
    # a strain the span cannot hold: 50 times faster at its far end (the idler starts at the source's speed)
    ('"speed": "5 m/s", "strain"', '"speed": "0.1 m/s", "strain"',
     ["base.json:10:5: span 'b' between roller 'idler' (0.1 m/s) and sink 'out' (5 m/s) would start at a strain of 49.05",
      "outside (-1, 10]"]),
    # a source feeding web at a strain of -1
    ('"strain": 0.001', '"strain": -1', ["base.json:7:66: source 'in': strain -1 is outside (-1, 10]"]),
])
def test_an_impossible_start_strain_is_refused_by_name(old, new, words):
    from webline.reference import LineODE

    assert old in BASE
    with pytest.raises(SceneError) as e:
        LineODE(parse_scene(BASE.replace(old, new, 1), "base.json")).given_state()
    for w in words:
        assert w in str(e.value), str(e.value)
