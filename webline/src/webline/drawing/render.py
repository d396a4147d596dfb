"""The drawing of a line with matplotlib, from its layout (layout.py): rollers as circles to scale, a
part without a radius as a point, the web on its wraps and spans (each path of the web in a colour of
its own), each span labelled with its name, length and web, the drives, loops, brakes, nips, traction,
load cells and dancers marked, with a legend. `figure(scene)` is what `webline draw` saves and what a
report shows."""

from __future__ import annotations

import math

from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Arc, Circle
from matplotlib.transforms import offset_copy

from ..scene import Dancer
from .geometry import CCW, angle_apart, heading_of, sub
from .layout import Layout, lay_out

PATH_COLOURS = {"line": "tab:blue", "merge": "tab:orange", "split": "tab:green"}
# The marks: key -> (legend text, marker, colour), in the legend's order.
MARKS = {
    "speed": ("speed drive (ideal)", "s", "tab:red"),
    "speed loop": ("speed loop on a motor", "s", "tab:purple"),
    "torque": ("torque drive", "P", "tab:red"),
    "tension": ("tension drive", "D", "tab:red"),
    "pi": ("tension loop (PI); dotted: what it measures", "h", "tab:purple"),
    "brake": ("brake", "X", "black"),
    "nip": ("nip pressing on the wrap", "v", "tab:brown"),
    "traction": ("traction: the web may slip", "*", "tab:olive"),
    "load cell": ("load cell (on the wrap the scene states)", "^", "tab:cyan"),
    "dancer": ("dancer: carriage under load", r"$\updownarrow$", "black"),
    "merge": ("merge: webs laminated", "<", "tab:orange"),
    "split": ("split: slitter", ">", "tab:green"),
    "wound": ("roll that winds or unwinds web", "o", "tab:gray"),
}
DRIVES = {"speed": "speed", "speed loop": "speed loop", "torque": "torque", "tension": "tension", "pi": "pi",
          "brake": "brake"}


def marks_of(scene, node) -> list[str]:
    """The marks a part carries, in MARKS' order."""
    found = set()
    drive = getattr(node, "drive", None)
    if drive is not None and drive.kind in DRIVES:
        found.add(DRIVES[drive.kind])
    traction = getattr(node, "traction", None)
    if traction is not None and traction.mu > 0:
        found.add("traction")
    if traction is not None and traction.nip_load is not None:
        found.add("nip")
    if getattr(node, "wrap", None):
        found.add("load cell")
    if isinstance(node, Dancer):
        found.add("dancer")
    if getattr(node, "wound", None) is not None:
        found.add("wound")
    found.update(b.kind for b in scene.branches if b.node == node.name)
    return [k for k in MARKS if k in found]


def _colour(path: str) -> str:
    return PATH_COLOURS[path.split(" ")[0]]


def figure(scene, layout: Layout | None = None) -> tuple[Figure, Layout]:
    """The drawing of a scene's line (lay_out's layout unless one is given) and its layout."""
    layout = layout or lay_out(scene)
    xs = [v for r in layout.rollers for v in (r.centre[0] - r.radius, r.centre[0] + r.radius)]
    ys = [v for r in layout.rollers for v in (r.centre[1] - r.radius, r.centre[1] + r.radius)]
    pad = 0.12 * max(max(xs) - min(xs), max(ys) - min(ys), 0.5) + 0.25  # room for the names beside the parts
    x0, x1, y0, y1 = min(xs) - pad, max(xs) + pad, min(ys) - pad, max(ys) + pad
    width = 9.0
    fig = Figure(figsize=(width + 3.2, max(2.5, min(9.0, width * (y1 - y0) / (x1 - x0)))), layout="constrained")
    ax = fig.add_subplot()
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.grid(True, color="0.93", lw=0.5)
    ax.set_axisbelow(True)
    ax.set_title(f"{scene.name}: drawn to scale ({'at the scene' + chr(39) + 's positions' if layout.placement == 'scene' else 'laid out automatically'})",
                 fontsize=10)
    _spans(ax, layout)
    _rollers(ax, scene, layout)
    _wraps(ax, layout)
    used = _marks(fig, ax, scene, layout)
    _loops(ax, scene, layout)
    ax.legend(handles=_legend(layout, used), loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7, frameon=False)
    return fig, layout


def _spans(ax, layout):
    for s in layout.spans:
        ax.plot([s.a[0], s.b[0]], [s.a[1], s.b[1]], color=_colour(s.path), lw=2, solid_capstyle="butt", zorder=3)
        mid = ((s.a[0] + s.b[0]) / 2, (s.a[1] + s.b[1]) / 2)
        ax.annotate(f"{s.name}: {s.length:g} m, {s.web}", mid, xytext=(0, 3), textcoords="offset points", fontsize=6,
                    ha="center", va="bottom", rotation=_upright(heading_of(sub(s.b, s.a))), rotation_mode="anchor",
                    zorder=6)


def outward(layout, r) -> tuple:
    """The unit vector from a roller to where its name and marks go: the middle of the widest gap between
    the webs that leave it and their labels (each label lies along its span, on its upright text's top
    side), sideways where gaps tie."""
    taken = []
    for s in layout.spans:
        if r.name not in (s.start, s.end):
            continue
        other = s.b if s.start == r.name else s.a
        away = heading_of(sub(other, r.centre))
        upright = _upright(heading_of(sub(s.b, s.a)))
        taken += [away, away + math.copysign(15.0, math.sin(math.radians(upright + 90.0 - away)))]
    if not taken:
        return (0.0, -1.0)
    best = max(range(0, 360, 15), key=lambda a: (round(min(angle_apart(a, t) for t in taken)), abs(math.cos(math.radians(a)))))
    return (math.cos(math.radians(best)), math.sin(math.radians(best)))


def _upright(angle: float) -> float:
    """A text's angle along a heading, turned so that it reads left to right."""
    return angle - 180.0 if angle > 90.0 else angle + 180.0 if angle <= -90.0 else angle


def _place(u) -> dict:
    """Text aligned to sit beyond a point in direction u."""
    return {"ha": "left" if u[0] > 0.4 else "right" if u[0] < -0.4 else "center",
            "va": "bottom" if u[1] > 0.4 else "top" if u[1] < -0.4 else "center"}


def _rollers(ax, scene, layout):
    for r in layout.rollers:
        if r.radius > 0:
            ax.add_patch(Circle(r.centre, r.radius, facecolor="0.88", edgecolor="0.25", lw=0.8, zorder=2))
            ax.plot(*r.centre, marker="+", color="0.25", ms=4, zorder=2)
            size = f"R {r.radius:g} m"
        else:
            ax.plot(*r.centre, marker="o", mfc="white", mec="black", ms=6, zorder=4)
            size = "a point"
        u = outward(layout, r)
        stated = [w.stated for w in layout.wraps if w.roller == r.name and w.stated is not None]
        size += "".join(f", wrap {w:g}°" for w in stated)
        ax.annotate(f"{r.name}\n{r.type}, {size}", (r.centre[0] + u[0] * r.radius, r.centre[1] + u[1] * r.radius),
                    xytext=(18 * u[0], 18 * u[1]), textcoords="offset points", fontsize=6.5, zorder=6, **_place(u))


def _wraps(ax, layout):
    spans = {s.name: s for s in layout.spans}
    for w in layout.wraps:
        r = layout.roller(w.roller)
        if r.radius == 0 or w.angle < 1e-9:
            continue
        start = heading_of(sub(spans[w.span_in].b, r.centre))
        end = heading_of(sub(spans[w.span_out].a, r.centre))
        first, last = (start, end) if w.side == CCW else (end, start)
        if abs(w.angle - 360.0) < 1e-9:
            last = first + 360.0
        ax.add_patch(Arc(r.centre, 2 * r.radius, 2 * r.radius, theta1=first, theta2=last, color=_colour(spans[w.span_out].path),
                         lw=2.5, zorder=3))


def _marks(fig, ax, scene, layout) -> set:
    """Each part's marks in a row above it; the marks used."""
    used = set()
    for r in layout.rollers:
        keys = marks_of(scene, scene.component(r.name))
        used.update(keys)
        u = outward(layout, r)
        for i, key in enumerate(keys):
            _, marker, colour = MARKS[key]
            at = offset_copy(ax.transData, fig=fig, x=8 * u[0] + (i - (len(keys) - 1) / 2) * 9, y=8 * u[1], units="points")
            ax.plot(r.centre[0] + u[0] * r.radius, r.centre[1] + u[1] * r.radius, marker=marker, color=colour, ms=6,
                    transform=at, zorder=7, linestyle="none")
    return used


def _loops(ax, scene, layout):
    """A loop's roller joined to what it measures (a span's middle or a load cell's roller), dotted."""
    spans = {s.name: s for s in layout.spans}
    for r in layout.rollers:
        loop = getattr(getattr(scene.component(r.name), "drive", None), "loop", None)
        if loop is None or loop.measure is None:
            continue
        part = loop.measure[0]
        if part in spans:
            s = spans[part]
            to = ((s.a[0] + s.b[0]) / 2, (s.a[1] + s.b[1]) / 2)
        else:
            to = layout.roller(part).centre
        ax.plot([r.centre[0], to[0]], [r.centre[1], to[1]], color="tab:purple", lw=0.8, ls=":", zorder=5)


def _legend(layout, used) -> list:
    paths = sorted({_colour(s.path) for s in layout.spans}, key=list(PATH_COLOURS.values()).index)
    names = {v: k for k, v in PATH_COLOURS.items()}
    words = {"line": "web: main line", "merge": "web: side path that merges", "split": "web: lane that splits off"}
    handles = [Line2D([], [], color=c, lw=2, label=words[names[c]]) for c in paths]
    if any(r.radius == 0 for r in layout.rollers):
        handles.append(Line2D([], [], marker="o", mfc="white", mec="black", ls="none",
                              label="part without a radius in the scene"))
    handles += [Line2D([], [], marker=MARKS[k][1], color=MARKS[k][2], ls="none", label=MARKS[k][0]) for k in MARKS if k in used]
    return handles
