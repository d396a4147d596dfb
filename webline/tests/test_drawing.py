"""`webline draw`: every shipped scene drawn and checked from its layout file (radii, tangent points
on the circles within 1 um and perpendicular to the radius within 1e-6 rad, wraps the scene's to 1
degree, no overlap); the checker itself, on layouts spoiled one way at a time; a scene's positions
honoured, and refused where they contradict its wrap."""

import copy
import json
import math
import re

import pytest
from matplotlib.figure import Figure
from webline.cli import main
from webline.drawing import DrawError, check_layout, figure, lay_out, layout_dict
from webline.scene import SceneError, load_scene, parse_scene

from .conftest import ROOT, SCENES

SHIPPED = sorted(SCENES.glob("*.json"))


@pytest.mark.parametrize("path", SHIPPED, ids=[p.stem for p in SHIPPED])
def test_every_shipped_scene_draws_without_overlap(path, tmp_path, capsys):
    assert main(["draw", str(path), "-o", str(tmp_path / "line.svg")]) == 0
    assert "wrote" in capsys.readouterr().out
    assert (tmp_path / "line.svg").stat().st_size > 0 and (tmp_path / "line.png").stat().st_size > 0
    layout = json.loads((tmp_path / "line.layout.json").read_text())
    scene = load_scene(path)
    assert check_layout(layout, scene) == []
    assert {r["name"] for r in layout["rollers"]} == {n.name for n in scene.nodes}
    assert {s["name"] for s in layout["spans"]} == {s.name for s in scene.spans}
    # The automatic layout draws every span at its L (a dancer's legs at its y_start).
    for s in layout["spans"]:
        assert s["length"] == pytest.approx(s["L"], abs=1e-9), s["name"]


def test_the_default_output_is_out_name_svg(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["draw", str(SCENES / "lamination.json")]) == 0
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["lamination.layout.json", "lamination.png",
                                                                     "lamination.svg"]


def test_the_drawing_is_an_svg(tmp_path, capsys):
    assert main(["draw", str(SCENES / "lamination.json"), "-o", str(tmp_path / "line.png")]) == 2
    assert "the drawing is an SVG; give FILE.svg" in capsys.readouterr().err
    assert not list(tmp_path.iterdir())


def test_a_figure_for_the_report():
    fig, layout = figure(load_scene(SCENES / "laminator.json"))
    assert isinstance(fig, Figure) and layout.placement == "automatic"
    assert {"web: side path that merges", "merge: webs laminated", "tension drive"} <= {
        t.get_text() for t in fig.axes[0].get_legend().get_texts()}


# A line placed by hand: an unwinder, an idler the web wraps 90 degrees clockwise (over its top, down its
# right side), a winder below it; every radius 0.1 m, so the spans are the rollers' outer tangents.
PLACED = {
    "name": "placed", "stop_time": "1 s", "step": "1 ms",
    "webs": {"PET": {"E": "4.5 GPa", "thickness": "50 um", "width": "1 m", "density": "1390 kg/m3"}},
    "line": [
        {"type": "unwinder", "name": "unwind", "J": "1 kg.m2", "R": "0.1 m", "drive": {"tension": "100 N"}, "strain": 0.0,
         "at": ["0 m", "0 m"]},
        {"type": "span", "name": "a", "L": "1 m", "web": "PET"},
        {"type": "roller", "name": "idler", "J": "0.01 kg.m2", "R": "100 mm", "wrap": "90 deg", "at": ["1 m", "0 m"]},
        {"type": "span", "name": "b", "L": "1 m", "web": "PET"},
        {"type": "winder", "name": "rewind", "J": "1 kg.m2", "R": "0.1 m", "drive": {"tension": "100 N"},
         "at": ["100 cm", "-1 m"]},
    ],
}


def placed(**changes):
    data = copy.deepcopy(PLACED)
    for name, values in changes.items():
        part = next(c for c in data["line"] if c["name"] == name)
        part.update(values)
    return parse_scene(json.dumps(data), "placed.json")


def test_a_scene_with_positions_is_honoured():
    scene = placed()
    layout = layout_dict(lay_out(scene))
    assert layout["placement"] == "scene"
    centres = {r["name"]: r["centre"] for r in layout["rollers"]}
    assert centres == {"unwind": [0.0, 0.0], "idler": [1.0, 0.0], "rewind": [1.0, -1.0]}
    spans = {s["name"]: s for s in layout["spans"]}
    assert spans["a"]["a"] == pytest.approx([0.0, 0.1], abs=1e-12) and spans["a"]["b"] == pytest.approx([1.0, 0.1], abs=1e-12)
    assert spans["b"]["a"] == pytest.approx([1.1, 0.0], abs=1e-12) and spans["b"]["b"] == pytest.approx([1.1, -1.0], abs=1e-12)
    (wrap,) = layout["wraps"]
    assert (wrap["roller"], wrap["direction"], wrap["stated"]) == ("idler", "cw", 90.0)
    assert wrap["angle"] == pytest.approx(90.0, abs=1e-9)
    assert check_layout(layout, scene) == []


def test_positions_that_contradict_a_wrap_are_refused(tmp_path, capsys):
    with pytest.raises(DrawError, match=r"roller 'idler': the scene states a wrap of 60 deg, its positions give 90\.0 deg"):
        lay_out(placed(idler={"wrap": "60 deg"}))
    path = tmp_path / "placed.json"
    data = copy.deepcopy(PLACED)
    data["line"][2]["wrap"] = "60 deg"
    path.write_text(json.dumps(data))
    assert main(["draw", str(path), "-o", str(tmp_path / "placed.svg")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "'idler'" in err and "60 deg" in err and "90.0 deg" in err
    assert not (tmp_path / "placed.svg").exists()


def test_a_wrap_beyond_the_turn_puts_the_web_on_the_other_side():
    """270 degrees at the same positions: the web runs under the idler and round it, a crossed tangent."""
    scene = placed(idler={"wrap": "270 deg"})
    layout = layout_dict(lay_out(scene))
    (wrap,) = layout["wraps"]
    assert wrap["direction"] == "ccw" and wrap["angle"] == pytest.approx(270.0, abs=1e-9)
    assert check_layout(layout, scene) == []


def test_positions_that_overlap_are_refused():
    with pytest.raises(DrawError, match="at their positions, rollers 'idler' and 'rewind' overlap"):
        lay_out(placed(rewind={"at": ["1 m", "-0.15 m"]}))


def test_a_span_drawn_off_its_length_is_warned_of():
    layout = lay_out(placed(rewind={"at": ["1 m", "-2 m"]}))
    assert layout.warnings == ["span 'b' is 2 m between its rollers' positions, its L 1 m"]


def test_positions_are_read_strictly():
    with pytest.raises(SceneError, match=r"placed.json:\d+:\d+: roller 'idler': at\[1\]: .* a length is needed"):
        placed(idler={"at": ["1 m", "2 s"]})
    with pytest.raises(SceneError, match="at must be a list of two lengths"):
        placed(idler={"at": ["1 m"]})
    data = copy.deepcopy(PLACED)
    del data["line"][4]["at"]
    with pytest.raises(SceneError, match="winder 'rewind' has no \"at\" while unwinder 'unwind' has one"):
        parse_scene(json.dumps(data), "placed.json")


def test_the_automatic_layout_keeps_every_stated_wrap():
    """A serpentine of wraps stated either way (and one past half a turn): each drawn to the degree, the
    sides chosen so that nothing overlaps."""
    data = copy.deepcopy(PLACED)
    line = [data["line"][0]]
    for i, wrap in enumerate(["30 deg", "200 deg", "90 deg", "135 deg"]):
        line += [{"type": "span", "name": f"s{i}", "L": "0.8 m", "web": "PET"},
                 {"type": "roller", "name": f"r{i}", "J": "0.01 kg.m2", "R": "0.07 m", "wrap": wrap}]
    line += [{"type": "span", "name": "last", "L": "1 m", "web": "PET"}, data["line"][4]]
    for part in line:
        part.pop("at", None)
    data["line"] = line
    scene = parse_scene(json.dumps(data), "serpentine.json")
    layout = layout_dict(lay_out(scene))
    assert check_layout(layout, scene) == []
    assert [round(w["angle"], 9) for w in layout["wraps"]] == [30.0, 200.0, 90.0, 135.0]


# ---------------------------------------------------------------- the checker can fail


def spoiled(change):
    scene = load_scene(SCENES / "laminator.json")
    layout = layout_dict(lay_out(scene))
    change(layout)
    return check_layout(layout, scene)


def span(layout, name):
    return next(s for s in layout["spans"] if s["name"] == name)


def roller(layout, name):
    return next(r for r in layout["rollers"] if r["name"] == name)


def test_the_checker_finds_a_wrong_radius():
    problems = spoiled(lambda d: roller(d, "idler").update(radius=0.07))
    assert problems[0] == "roller 'idler': radius 0.07 m drawn, the scene's is 0.06 m"


def test_the_checker_finds_a_tangent_point_off_its_circle():
    def move(d):  # 2 um outward from the idler's centre, along the radius: still perpendicular
        s, c = span(d, "laminate"), roller(d, "idler")["centre"]
        v = [s["b"][0] - c[0], s["b"][1] - c[1]]
        n = math.hypot(*v)
        s["b"] = [s["b"][0] + 2e-6 * v[0] / n, s["b"][1] + 2e-6 * v[1] / n]

    problems = spoiled(move)
    assert problems[0].startswith("span 'laminate': its tangent point") and "2e-06 m off the circle of 'idler'" in problems[0]


def test_the_checker_finds_a_span_off_the_tangent():
    def turn(d):  # the tangent point slid along the idler's circle by 1e-5 rad: on the circle, off the tangent
        s, c = span(d, "laminate"), roller(d, "idler")["centre"]
        x, y = s["b"][0] - c[0], s["b"][1] - c[1]
        a = 1e-5
        s["b"] = [c[0] + x * math.cos(a) - y * math.sin(a), c[1] + x * math.sin(a) + y * math.cos(a)]

    problems = spoiled(turn)
    assert problems and problems[0].startswith("span 'laminate' meets 'idler'") and "rad off the tangent" in problems[0]


def test_the_checker_finds_a_wrap_not_the_scenes():
    scene = placed()
    layout = layout_dict(lay_out(scene))
    assert check_layout(layout, placed(idler={"wrap": "91.5 deg"})) == ["roller 'idler': wrap 90.0 deg drawn, the scene's is 91.5 deg"]
    assert check_layout(layout, placed(idler={"wrap": "90.4 deg"})) == []
    layout["wraps"][0]["angle"] = 91.0
    assert check_layout(layout, scene) == ["roller 'idler': the layout says a wrap of 91 deg, its spans make 90 deg"]


def test_the_checker_finds_the_web_on_the_wrong_side():
    scene = placed()
    layout = layout_dict(lay_out(scene))
    layout["wraps"][0]["direction"] = "ccw"
    problems = check_layout(layout, scene)
    assert "roller 'idler': the web arrives on the side opposite its ccw wrap" in problems


def test_the_checker_finds_overlaps():
    def overlap(d):
        roller(d, "idler")["centre"] = list(roller(d, "rewind")["centre"])

    problems = spoiled(overlap)
    assert any(p.startswith("rollers 'idler' and 'rewind' overlap") for p in problems), problems

    def through(d):  # the foil's unwinder moved onto the middle of the film span
        s = span(d, "film")
        roller(d, "unwind_foil")["centre"] = [(s["a"][0] + s["b"][0]) / 2, (s["a"][1] + s["b"][1]) / 2]

    problems = spoiled(through)
    assert "span 'film' runs through roller 'unwind_foil'" in "\n".join(problems)


@pytest.mark.parametrize("mark", ["scene example", "merge split example"])
def test_the_docs_examples_draw(mark):
    """docs/scenes.md's examples: a converting span, and a merge and a split at rollers with a radius."""
    doc = (ROOT / "docs" / "scenes.md").read_text()
    scene = parse_scene(re.search(r"<!-- %s -->\s*```json\n(.*?)```" % mark, doc, re.S).group(1), mark)
    layout = layout_dict(lay_out(scene))
    assert check_layout(layout, scene) == []

