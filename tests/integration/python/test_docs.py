"""The documentation stands on its own: a user has the repository and nothing else. Every
relative link of the README and docs/ names a file of the repository (and a heading of it, where
it names one), and no tracked file cites a path outside the repository."""

import re
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[3]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")


def anchors(page: Path) -> set[str]:
    """GitHub's anchors of a page's headings: lower case, punctuation dropped, spaces to '-'."""
    found = set()
    for line in page.read_text(encoding="utf-8").splitlines():
        if line.startswith("#"):
            title = line.lstrip("#").strip().lower()
            found.add(re.sub(r"\s", "-", re.sub(r"[^\w\s-]", "", title)))
    return found


def links(page: Path):
    text = re.sub(r"```.*?```", "", page.read_text(encoding="utf-8"), flags=re.S)  # code is not a link
    for target in LINK.findall(text):
        if not re.match(r"[a-z]+:", target):  # http:, https:, mailto:
            yield target


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_every_relative_link_resolves_inside_the_repository(page):
    broken = []
    for target in links(page):
        path, _, anchor = target.partition("#")
        file = (page.parent / path).resolve() if path else page
        if ROOT not in file.parents and file != ROOT:
            broken.append(f"{target}: outside the repository")
        elif not file.exists():
            broken.append(f"{target}: no such file")
        elif anchor and file.suffix == ".md" and anchor not in anchors(file):
            broken.append(f"{target}: no heading #{anchor} in {file.relative_to(ROOT)}")
    assert not broken, f"{page.relative_to(ROOT)}: " + "; ".join(broken)


def test_the_check_can_fail(tmp_path):
    page = tmp_path / "page.md"
    page.write_text("[a](missing.md) [b](https://example.org) [c](#here)\n# Here\n")
    assert list(links(page)) == ["missing.md", "#here"]
    assert anchors(page) == {"here"}


def test_no_tracked_file_cites_a_path_outside_the_repository():
    """The project's own docs/physics.md holds the model: nothing points at a folder beside the
    checkout (such as the team's shared notes), which users never have."""
    listed = subprocess.run(["git", "grep", "-n", "-I", "-E", r"\.\./shared/|shared/docs/", "--", ".", ":!tests/integration/python/test_docs.py"],
                            cwd=ROOT, capture_output=True, text=True)
    assert listed.stdout == "", listed.stdout


def test_the_readme_links_the_physics_page():
    assert "docs/physics.md" in (ROOT / "README.md").read_text(encoding="utf-8")
