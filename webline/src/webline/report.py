"""`webline run --report`: one self-contained HTML page of a run (templates/report.html.j2), viewable
offline: its sections in order, each image inline as a data URI, no external link, script or font.

A section is a `Section` in the list `sections` builds; one of kind "figures" shows matplotlib
figures (`figure_image`), so a new picture of the run is one more entry there.
"""

from __future__ import annotations

import base64
import io
from dataclasses import dataclass
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from jinja2 import Environment, PackageLoader, StrictUndefined, select_autoescape  # noqa: E402

from .drawing import DrawError, figure  # noqa: E402
from .installation import version  # noqa: E402
from .plot import draw_panel, panels, subtitle  # noqa: E402
from .result import Result  # noqa: E402
from .summary import Summary  # noqa: E402


@dataclass
class Section:
    """One section of the page: its anchor, its heading, how it is shown (the template's `kind`: summary,
    warnings, figures, scene, versions) and what it shows."""

    id: str
    title: str
    kind: str
    content: object


@dataclass
class Image:
    caption: str
    uri: str  # data:image/png;base64,...


def figure_image(fig, caption: str) -> Image:
    """A matplotlib figure as an inline PNG (the figure is closed)."""
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=100)
    plt.close(fig)
    return Image(caption, "data:image/png;base64," + base64.b64encode(buffer.getvalue()).decode("ascii"))


def quantity_plots(result: Result, reference: Result | None = None) -> list:
    """A plot per quantity the run recorded (plot.panels: one per unit), time and the unit on the axes."""
    images = []
    for (unit, what), keys in panels(result):
        fig, ax = plt.subplots(figsize=(9, 3.2))
        draw_panel(ax, result, unit, what, keys, reference)
        ax.set_xlabel("time [s]")
        ax.set_title(f"{what or unit}: {subtitle(result, reference)}", fontsize=10)
        fig.tight_layout()
        images.append(figure_image(fig, f"{what or 'quantity'} [{unit}]: {', '.join(keys)}"))
    return images


def drawing(scene) -> dict:
    """The line as `webline draw` draws it, and what its layout says; a scene the layout cannot draw
    gets the reason instead (the run itself does not need a drawing)."""
    try:
        fig, layout = figure(scene)
    except DrawError as refused:
        return {"images": [], "notes": [f"not drawn: {refused}"]}
    return {"images": [figure_image(fig, f"{scene.name} as drawn, to scale (webline draw)")], "notes": list(layout.warnings)}


def sections(scene, scene_file: Path, said: Summary, growing: list, result: Result, reference: Result | None) -> list:
    """The page's sections, in the order shown (`scene`: the scene as run, read from `scene_file`)."""
    return [
        Section("drawing", "The line", "drawing", drawing(scene)),
        Section("summary", "Summary", "summary", said),
        Section("warnings", "Warnings", "warnings", growing + said.warnings),
        Section("plots", "Plots", "figures", quantity_plots(result, reference)),
        Section("scene", "Scene", "scene", {"name": scene.name, "parts": len(scene.parts), "file": str(scene_file),
                                            "text": scene_file.read_text(encoding="utf-8")}),
        Section("versions", "Versions", "versions", {"webline": version(), "fmus": result.info.get("fmus", []),
                                                     "engine": result.info["engine"]}),
    ]


ENVIRONMENT = Environment(loader=PackageLoader("webline", "templates"), autoescape=select_autoescape(["html", "j2"]),
                          undefined=StrictUndefined, trim_blocks=True, lstrip_blocks=True)


def write_report(path: Path, scene, scene_file: Path, said: Summary, growing: list, result: Result,
                 reference: Result | None = None, title: str | None = None) -> Path:
    """The run's page at `path`: `said` is the summary the terminal showed, `growing` the warnings said
    before the run (growth.check)."""
    page = ENVIRONMENT.get_template("report.html.j2").render(
        title=title or result.scene, sections=sections(scene, scene_file, said, growing, result, reference))
    path.write_text(page, encoding="utf-8")
    return path
