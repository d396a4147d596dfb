"""The pages a user opens, in a real browser (headless Chromium, browser.py): the model documentation
each FMU ships (documentation/index.html of ConvertingSpan.fmu, Roller.fmu, their FMI 3.0 twins and an
exported Line FMU, opened from the unpacked FMU) and the report of a shipped scene (`webline run --report`, default engine).

Each page: no console error, every image loaded, every link resolved, every heading and table shown;
its screenshot goes to target/browser/. Skipped, with the set-up's reason, only where Chromium cannot
be installed (tests/tools.sh installs it).
"""

import zipfile
from pathlib import Path

import pytest

from browser import ROOT, check_page, chromium, install
from packaged import packaged

SCREENSHOTS = ROOT / "target" / "browser"
SCENE = ROOT / "webline" / "scenes" / "lamination.json"


@pytest.fixture(scope="module")
def driver():
    reason = install()
    if reason:
        pytest.skip(reason)
    with chromium() as browser:
        yield browser


def unpacked(fmu: Path, folder: Path) -> Path:
    """The FMU's documentation page, in the FMU unpacked as an importer unpacks it."""
    with zipfile.ZipFile(fmu) as z:
        z.extractall(folder)
    return folder / "documentation" / "index.html"


def span_page(fmus, tmp):
    return unpacked(fmus / "ConvertingSpan.fmu", tmp)


def roller_page(fmus, tmp):
    return unpacked(fmus / "Roller.fmu", tmp)


def span_fmi3_page(fmus, tmp):
    return unpacked(packaged(fmus / "fmi3" / "ConvertingSpan.fmu"), tmp)


def roller_fmi3_page(fmus, tmp):
    return unpacked(packaged(fmus / "fmi3" / "Roller.fmu"), tmp)


def line_page(fmus, tmp):
    from webline import linefmu
    from webline.scene import load_scene

    return unpacked(linefmu.export(load_scene(SCENE), tmp / "lamination.fmu", fmus), tmp / "unpacked")


def report_page(fmus, tmp):
    from webline.cli import main

    assert main(["run", str(SCENE), "--report", "--no-progress", "--fmu-dir", str(fmus), "--out", str(tmp)]) == 0
    return tmp / f"{SCENE.stem}.html"


# (name, how the page is made, whether it may link out: the report must stand alone offline)
PAGES = [("ConvertingSpan", span_page, True), ("Roller", roller_page, True), ("Line", line_page, True),
         ("ConvertingSpan-fmi3", span_fmi3_page, True), ("Roller-fmi3", roller_fmi3_page, True),
         ("report-lamination", report_page, False)]


@pytest.mark.parametrize("name, make, external_allowed", PAGES, ids=[p[0] for p in PAGES])
def test_the_page_opens_whole_in_chromium(driver, fmus, tmp_path, name, make, external_allowed):
    page = make(Path(fmus), tmp_path)
    check = check_page(driver, page, SCREENSHOTS / f"{name}.png", external_allowed=external_allowed)
    assert not check.problems, f"{name} ({page}):\n" + "\n".join(check.problems)
    assert check.screenshot.stat().st_size > 0
    if check.external:  # not followed (the test runs offline): said, so that a reader sees where the page points
        print(f"{name}: links out, not followed: {', '.join(sorted(set(check.external)))}")


def test_the_check_finds_what_a_broken_page_hides(driver, tmp_path):
    """Every check can fail: a page with one fault of each kind is named for each."""
    page = tmp_path / "broken.html"
    page.write_text("""<!DOCTYPE html><html><head><meta charset="utf-8"><title>broken</title>
<style>h3 { display: none } body { background: url(missing.png) }</style></head><body>
<h1>shown</h1><h2>shown too</h2><h3>hidden</h3>
<table></table>
<img src="nowhere.png" alt="">
<a href="#nothing">to no anchor</a> <a href="#there">to an anchor</a> <a href="gone.html">to no file</a>
<a href="https://example.org/">out</a>
<p id="there">x</p>
<script>undefinedFunction();</script>
</body></html>""", encoding="utf-8")
    check = check_page(driver, page, tmp_path / "broken.png", external_allowed=False)
    said = "\n".join(check.problems)
    for expected in ("console: ", "image not loaded: nowhere.png", "#nothing: no element with id 'nothing'",
                     "gone.html: ", "missing.png: ", "<h3> 'hidden' is not shown", "<table> '' is not shown",
                     "external link or resource in a page that must stand alone: https://example.org/"):
        assert expected in said, f"{expected!r} not among:\n{said}"
    assert "#there" not in said
