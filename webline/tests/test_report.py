"""`webline run --report`: the page holds what the terminal said (the same numbers, findings and
warnings), a plot per quantity, the scene file as run and the identity of the FMUs that ran, read here
by FMPy; nothing on it points outside it. (That it opens whole in Chromium:
tests/integration/python/test_browser.py.)"""

import base64
import io
from pathlib import Path

import lxml.html
import matplotlib.image
from fmpy import read_model_description

from webline import linefmu
from webline.cli import main
from webline.scene import load_scene

from .conftest import SCENES


def run(capsys, scene: Path, tmp_path, *options):
    assert main(["run", str(scene), "--report", "--no-plot", "--no-progress", "--out", str(tmp_path), *options]) == 0
    said = capsys.readouterr().out
    return said, lxml.html.parse(str(tmp_path / f"{scene.stem}.html")).getroot()


def section(page, name):
    return page.get_element_by_id(name)


def test_the_page_holds_the_terminal_summary_the_plots_the_scene_and_the_line_fmu(capsys, fmus, tmp_path):
    scene = SCENES / "idler_skid.json"  # a roller that slides: a traction report besides the tables
    said, page = run(capsys, scene, tmp_path, "--fmu-dir", str(fmus))
    summary = section(page, "summary")
    rows = [[c.text_content().strip() for c in tr.findall("td")] for tr in summary.iter("tr") if tr.findall("td")]
    parts = [p.name for p in load_scene(scene).parts]
    table_lines = [line.split() for line in said.splitlines() if line.split() and line.split()[0] in parts]
    assert len(table_lines) == len(rows) >= 5
    for words, row in zip(table_lines, rows):
        assert [w for w in row if w] == words  # the terminal's numbers, as printed
    findings = [li.text_content() for li in summary.iter("li")]
    traction = [line.strip() for line in said.splitlines() if "of its traction" in line]
    assert traction and traction == [f for f in findings if "of its traction" in f]
    assert said.splitlines()[0] == summary.find("p").text_content()
    assert "no warning" in section(page, "warnings").text_content() and "warning" not in said

    recorded = [c for c in (tmp_path / "idler_skid.csv").read_text().splitlines()[0].split(",")[1:]]
    figures = section(page, "plots").findall(".//figure")
    captions = [f.find("figcaption").text_content() for f in figures]
    for column in recorded:  # "idler.slip [m/s]": in exactly one plot, the one of its unit
        key, unit = column.split(" [")
        holding = [c for c in captions if key in c.split(": ")[1].split(", ")]
        assert len(holding) == 1 and f"[{unit}" in holding[0], (column, captions)
    for figure in figures:
        uri = figure.find("img").get("src")
        assert uri.startswith("data:image/png;base64,")
        assert matplotlib.image.imread(io.BytesIO(base64.b64decode(uri.split(",", 1)[1])), format="png").shape[0] > 100

    assert section(page, "scene").find("pre").text_content() == scene.read_text(encoding="utf-8")
    drawn = section(page, "drawing").findall(".//img")  # the line as `webline draw` draws it, first
    assert len(drawn) == 1 and drawn[0].get("src").startswith("data:image/png;base64,")
    assert [s.get("id") for s in page.iter("section")][0] == "drawing"

    exported = read_model_description(str(linefmu.export(load_scene(scene), tmp_path / "again.fmu", fmus)))
    versions = section(page, "versions")
    row = [td.text_content() for td in versions.find(".//table").findall(".//td")]
    assert row[1:3] == [exported.modelName, exported.fmiVersion] and row[4] == exported.guid
    assert row[5] == exported.generationTool
    assert "webline 0.1.0" in versions.text_content()

    links = [e.get("href") or e.get("src") for e in page.iter() if e.get("href") or e.get("src")]
    assert all(u.startswith(("#", "data:")) for u in links), links


def test_the_parts_engine_names_the_span_and_roller_fmus_as_they_carry_themselves(capsys, fmus, tmp_path):
    _, page = run(capsys, SCENES / "lamination.json", tmp_path, "--fmu-dir", str(fmus), "--engine", "parts")
    rows = [[td.text_content() for td in tr.findall("td")] for tr in section(page, "versions").iter("tr") if tr.findall("td")]
    for row, name in zip(rows, ("ConvertingSpan.fmu", "Roller.fmu"), strict=True):
        md = read_model_description(str(Path(fmus) / name))
        assert row == [name, md.modelName, md.fmiVersion, md.version, md.guid, md.generationTool,
                       md.generationDateAndTime or "not given"]


def test_the_warnings_before_and_during_the_run_are_on_the_page(tmp_path):
    from webline.report import write_report
    from webline.result import Result
    from webline.summary import Summary

    import numpy as np

    result = Result("x", ["a.T [N]"], np.array([0.0, 1.0]), np.array([[1.0], [2.0]]), {"engine": "reference", "fmus": []})
    scene = SCENES / "lamination.json"
    said = Summary("x: engine reference", ["the step was cut <here>"], [])
    page = lxml.html.parse(str(write_report(tmp_path / "x.html", load_scene(scene), scene, said, ["a loop grows"], result))).getroot()
    warnings = [li.text_content() for li in section(page, "warnings").iter("li")]
    assert warnings == ["a loop grows", "the step was cut <here>"]  # escaped, not markup
    assert "No FMU ran" in section(page, "versions").text_content()


def test_an_ssp_archive_is_refused_in_one_line(capsys, tmp_path):
    assert main(["run", str(tmp_path / "line.ssp"), "--report", "--out", str(tmp_path)]) == 2
    assert capsys.readouterr().err.strip().endswith("--report needs a scene (.json): its page shows the scene and its parts' tables")
