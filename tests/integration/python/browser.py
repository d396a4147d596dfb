"""A page opened in headless Chromium and checked as a reader meets it: Debian's chromium driven by
its own chromium-driver through Selenium (docs/testing.md says why), installed by the project's
set-up (tests/tools.sh, `browser_setup`).

`check_page(driver, page, screenshot)` is the one check of a page, for every page a test opens (the
FMUs' documentation, a run's report): the console, the images, the links, every heading and table
shown, and a screenshot of the whole page.
"""

from __future__ import annotations

import base64
import os
import re
import shutil
import subprocess
from contextlib import contextmanager
from dataclasses import dataclass, field
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urljoin, urlsplit

ROOT = Path(__file__).resolve().parents[3]
CHROMIUM, DRIVER = "chromium", "chromedriver"
# What a reader sees on the page: each of these, in the file and on the screen.
SECTIONS = ("h1", "h2", "h3", "table")
EXTERNAL = ("http", "https", "ftp", "mailto")


def install() -> str | None:
    """Chromium and its driver, installed by the set-up's own step if they are missing (apt, as
    root); None when they are there, else the set-up's one line saying why they cannot be."""
    if shutil.which(CHROMIUM) and shutil.which(DRIVER):
        return None
    step = subprocess.run(["bash", "-c", "export SETUP_FUNCTIONS_ONLY=1; source fmu/env.sh && source tests/tools.sh "
                                         "&& browser_setup"], cwd=ROOT, capture_output=True, text=True)
    if step.returncode == 0 and shutil.which(CHROMIUM) and shutil.which(DRIVER):
        return None
    said = step.stderr.strip().splitlines() or ["browser_setup installed them, yet they are not on PATH"]
    return "Chromium cannot be installed here: " + " / ".join(said)


@contextmanager
def chromium(width=1280, height=900):
    """Headless Chromium under Selenium, its console kept (goog:loggingPrefs)."""
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = shutil.which(CHROMIUM)
    for argument in ("--headless=new", f"--window-size={width},{height}", "--disable-gpu", "--hide-scrollbars",
                     # root (CI, the set-up) has no user namespace sandbox; /dev/shm may be small in a container
                     *(["--no-sandbox"] if os.geteuid() == 0 else []), "--disable-dev-shm-usage"):
        options.add_argument(argument)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    # The driver given by path: Selenium Manager, which would download one, never runs.
    driver = webdriver.Chrome(options=options, service=Service(executable_path=shutil.which(DRIVER)))
    try:
        yield driver
    finally:
        driver.quit()


class _Source(HTMLParser):
    """What the file itself holds: how many of each of SECTIONS, and its elements' ids."""

    def __init__(self):
        super().__init__()
        self.counts = dict.fromkeys(SECTIONS, 0)
        self.ids = set()
        self.styles = []  # what the page's <style> and style="" load: url(...) and @import
        self._in_style = False

    def handle_starttag(self, tag, attrs):
        if tag in self.counts:
            self.counts[tag] += 1
        self.ids.update(value for name, value in attrs if name in ("id", "name") and value)
        self._in_style = tag == "style"
        self._loads(" ".join(value or "" for name, value in attrs if name == "style"))

    def handle_data(self, data):
        if self._in_style:
            self._loads(data)

    def _loads(self, css):
        self.styles += re.findall(r"""(?:url\(\s*['"]?|@import\s+['"])([^'")\s]+)""", css)


def _source(path: Path) -> _Source:
    parsed = _Source()
    parsed.feed(path.read_text(encoding="utf-8"))
    return parsed


@dataclass
class PageCheck:
    page: Path
    problems: list = field(default_factory=list)  # each a line naming what is wrong
    external: list = field(default_factory=list)  # the links out of the page (not followed: the test runs offline)
    screenshot: Path | None = None


# Every element a reader should see, with the attribute a link or a resource is in.
LINKS_JS = """return Array.from(document.querySelectorAll('a[href], link[href], script[src], img[src], iframe[src]'))
    .map(e => [e.tagName.toLowerCase(), e.getAttribute(e.hasAttribute('href') ? 'href' : 'src')]);"""
IMAGES_JS = """return Array.from(document.images).map(i => [i.getAttribute('src').slice(0, 80), i.complete, i.naturalWidth]);"""
SHOWN_JS = """return Array.from(document.querySelectorAll(arguments[0])).map(e => {
    const r = e.getBoundingClientRect(), s = getComputedStyle(e);
    return [e.tagName.toLowerCase(), (e.textContent || '').trim().slice(0, 60), r.width, r.height,
            s.display !== 'none' && s.visibility !== 'hidden' && e.getClientRects().length > 0];
});"""


def check_page(driver, page: Path, screenshot: Path, external_allowed=True) -> PageCheck:
    """Opens `page` (a local HTML file) and checks it: no console error (a SEVERE entry), every image
    loaded (naturalWidth > 0), every link resolved (a local file exists, an anchor has its id there,
    an http link is listed in `external`, and is a problem where not `external_allowed`), every
    h1/h2/h3 and table of the file shown with a size; writes a screenshot of the whole page."""
    check = PageCheck(page)
    driver.get_log("browser")  # what an earlier page logged is not this page's
    driver.get(page.resolve().as_uri())
    driver.execute_async_script("const done = arguments[arguments.length - 1];"
                                "if (document.readyState === 'complete') done(); else addEventListener('load', () => done());")
    check.problems += [f"console: {e['message']}" for e in driver.get_log("browser") if e["level"] == "SEVERE"]
    for src, complete, width in driver.execute_script(IMAGES_JS):
        if not complete or width == 0:
            check.problems += [f"image not loaded: {src}"]
    source = _source(page)
    for tag, target in driver.execute_script(LINKS_JS) + [("style", u) for u in source.styles]:
        problem = _resolve(page, source, tag, target, check)
        if problem:
            check.problems.append(problem)
    if check.external and not external_allowed:
        check.problems += [f"external link or resource in a page that must stand alone: {u}" for u in check.external]
    shown = driver.execute_script(SHOWN_JS, ", ".join(SECTIONS))
    for tag in SECTIONS:
        on_screen = sum(1 for t, *_ in shown if t == tag)
        if on_screen != source.counts[tag]:
            check.problems.append(f"the file holds {source.counts[tag]} <{tag}>, the rendered page {on_screen}")
    for tag, text, width, height, visible in shown:
        if not (visible and width > 0 and height > 0):
            check.problems.append(f"<{tag}> {text!r} is not shown ({width:g} x {height:g} px)")
    check.screenshot = full_screenshot(driver, screenshot)
    return check


def _resolve(page: Path, source: _Source, tag: str, target: str, check: PageCheck) -> str | None:
    """Why a link or a resource of `page` does not resolve, or None."""
    if target.startswith("data:") or target.startswith("javascript:void"):
        return None
    parts = urlsplit(target)
    if parts.scheme in EXTERNAL:
        check.external.append(target)
        return None
    if parts.scheme not in ("", "file"):
        return f"<{tag}> {target}: a scheme the page cannot use offline"
    if not parts.path:  # an anchor in this page
        anchor = unquote(parts.fragment)
        return None if not anchor or anchor in source.ids else f"<{tag}> {target}: no element with id {anchor!r}"
    path = Path(unquote(urlsplit(urljoin(page.resolve().as_uri(), target)).path))
    if not path.exists():
        return f"<{tag}> {target}: {path} does not exist"
    if parts.fragment and path.suffix == ".html" and unquote(parts.fragment) not in _source(path).ids:
        return f"<{tag}> {target}: {path.name} has no element with id {unquote(parts.fragment)!r}"
    return None


def full_screenshot(driver, path: Path) -> Path:
    """The whole page, past the window's height (DevTools' captureBeyondViewport), as a PNG."""
    size = driver.execute_cdp_cmd("Page.getLayoutMetrics", {})["cssContentSize"]
    shot = driver.execute_cdp_cmd("Page.captureScreenshot", {
        "format": "png", "captureBeyondViewport": True,
        "clip": {"x": 0, "y": 0, "width": size["width"], "height": size["height"], "scale": 1}})
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(base64.b64decode(shot["data"]))
    return path
