"""What `webline run` says of a run: the summary (its tables, the traction report, the events), one
object that the terminal's text and the report's page (report.py) both show."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .result import Result
from .scene import Dancer, Span


@dataclass
class Table:
    """One table of a run's summary: a row per part, its numbers formatted as the terminal shows them."""

    part: str  # what a row is: "span", "roller"
    columns: list  # the numbers' headings
    unit: str
    rows: list  # (part name, [formatted numbers], the last column's text or None)
    last: str | None = None  # the heading of a column of text after the numbers ("slack")


@dataclass
class Summary:
    """What `webline run` says of a run: its headline, warnings, tables and one line per finding (a
    dancer's travel, a roller's traction, an event). The terminal's text and the report's page both
    show this one object."""

    headline: str
    warnings: list
    tables: list
    findings: list = field(default_factory=list)

    def text(self) -> str:
        lines = [self.headline] + [f"  warning: {w}" for w in self.warnings]
        for t in self.tables:
            last = f"  {t.last}" if t.last is not None else ""
            lines.append(f"  {t.part:<14}" + "".join(f"{c:>10}" for c in t.columns) + f"  [{t.unit}]{last}")
            for name, numbers, text in t.rows:
                tail = f"       {text}" if t.last is not None else ""
                lines.append(f"  {name:<14}" + "".join(f"{n:>10}" for n in numbers) + tail)
        lines += [f"  {f}" for f in self.findings]
        return "\n".join(lines)


def summary(scene, result: Result) -> Summary:
    info = result.info
    if "instances" in info:
        cost = f"{info['steps']} steps, {info['rollbacks']} rollbacks, {info['instances']} FMU instances"
    elif "rhs_evaluations" in info:  # the monolithic reference
        cost = f"{len(result.time)} points, {info['rhs_evaluations']} right-hand sides"
    else:
        cost = f"{info['steps']} steps"
    headline = (f"{scene.name}: engine {info['engine']}: {info['method']}, step {info['step'] * 1e3:g} ms, {cost}, "
                f"{info['wall_time']:.2f} s wall time")
    tables, findings = [], []
    keys = result.keys()
    spans = [c for c in scene.parts if isinstance(c, Span) and f"{c.name}.T" in keys]
    if spans:
        rows = []
        for sp in spans:
            T = result.column(f"{sp.name}.T")
            slack = ""
            if "preventNegativeTension" in sp.effects:
                dt = np.diff(result.time)
                slack_time = float(np.sum(dt[(T[1:] <= 0.0)]))
                slack = f"{slack_time:.3f} s"
            rows.append((sp.name, [f"{x:.1f}" for x in (T[0], T.min(), T.max(), T[-1])], slack))
        tables.append(Table("span", ["T start", "T min", "T max", "T end"], "N", rows, last="slack"))
    nodes = [c for c in scene.parts if not isinstance(c, Span) and f"{c.name}.v" in keys]
    if nodes:
        rows = []
        for n in nodes:
            v = result.column(f"{n.name}.v")
            rows.append((n.name, [f"{x:.4f}" for x in (v[0], v.min(), v.max(), v[-1])], None))
        tables.append(Table("roller", ["v start", "v min", "v max", "v end"], "m/s", rows))
    for d in [c for c in scene.parts if isinstance(c, Dancer) and f"{c.name}.y" in keys]:
        y = result.column(f"{d.name}.y")
        findings.append(f"dancer {d.name}: position {y[0]:.4f} m at start, {y.min():.4f} .. {y.max():.4f} m, {y[-1]:.4f} m at the end")
    for c in [c for c in scene.parts if getattr(c, "traction", None) is not None and f"{c.name}.traction" in keys]:
        column = lambda q: result.column(f"{c.name}.{q}") if f"{c.name}.{q}" in keys else None  # noqa: E731
        findings.append(traction_report(c, result.time, column('traction'), column('slip'), column('mu_eff'), column('v_web')))
        floating = floating_report(scene, c, result)
        if floating is not None:
            findings.append(floating)
    warnings = list(info.get("warnings", []))
    for c in [c for c in scene.parts if getattr(c, "layon", None) is not None and f"{c.name}.layon.N" in keys]:
        finding, warning = layon_report(c, result.time, result.column(f"{c.name}.layon.N"))
        findings.append(finding)
        if warning is not None:
            warnings.append(warning)
    for t, name, what in info.get("events", []):
        findings.append(f"event at t = {t:g} s: {name} changed {what}")
    return Summary(headline, warnings, tables, findings)


@dataclass
class Separations:
    """Where a lay-on's nip let go (N <= 0) at the output samples [R18]: how often, the first time, the
    longest and the total time apart (s). A separation runs from its first sample at N <= 0 to the next
    sample at N > 0 (or the end), so one shorter than the output step may be missed."""

    count: int = 0
    first: float | None = None
    longest: float = 0.0
    total: float = 0.0


def separations(time, force) -> Separations:
    apart = np.asarray(force) <= 0.0
    starts = np.flatnonzero(apart & ~np.concatenate([[False], apart[:-1]]))
    ends = np.flatnonzero(~apart & np.concatenate([[False], apart[:-1]]))
    out = Separations(count=len(starts))
    if len(starts):
        closing = np.append(np.asarray(time)[ends], time[-1]) if len(ends) < len(starts) else np.asarray(time)[ends]
        durations = closing - np.asarray(time)[starts]
        out.first, out.longest, out.total = float(time[starts[0]]), float(durations.max()), float(durations.sum())
    return out


def layon_report(c, time, force) -> tuple:
    """(finding, warning or None) of a winder's lay-on roller from its nip's force at the output samples: the
    least force where it kept contact, or when and how long it lost it (`separations`)."""
    apart = separations(time, force)
    if apart.count == 0:
        k = int(np.argmin(force))
        return f"{c.name}: its lay-on roller kept contact (least nip force {force[k]:.4g} N at t = {time[k]:.4g} s)", None
    said = (f"lost contact {apart.count} times, first at t = {apart.first:.4g} s, longest {apart.longest:.3g} s, "
            f"{apart.total:.3g} s in all")
    return (f"{c.name}: its lay-on roller {said} (read at the output samples: a separation shorter than the output "
            "step can be missed)"), f"lay-on at {c.name} {said}"


# A contact slides where its grip sits on its limit, |g| >= psi(s) (1 - ON_LIMIT), or it slips faster
# than its v_slip (docs/physics.md, "Contacts that stick"): a slide at a slip far below v_slip still
# counts (a grip that holds sits below psi(0) at zero slip).
ON_LIMIT = 1e-6


def traction_report(c, time, used, slip, mu_eff=None, v_web=None) -> str:
    """Will it slip? The most traction a roller used while it held (|g|, the friction it needs over
    the kinetic limit) and when; where it slid, when, how fast at most and how much web slid over it
    (the integral of |slip|); where an air film leaves its wrap no friction (mu_eff = 0) and no nip
    presses, that it rides on air from which web speed, instead of a share of nothing."""
    from .reference import stribeck

    tr = c.traction
    psi = stribeck(slip, tr.v_slip, tr.static)
    floating = np.zeros(len(time), dtype=bool)
    if mu_eff is not None and tr.nip_load is None:
        floating = mu_eff == 0.0
    sliding = ((used >= psi * (1.0 - ON_LIMIT)) | (np.abs(slip) > tr.v_slip)) & ~floating
    held = ~sliding & ~floating
    parts = []
    if held.any():
        k = int(np.argmax(np.where(held, used, -np.inf)))
        parts.append(f"{100 * used[k]:.0f} % of its traction at most while it held (t = {time[k]:.3g} s)")
    dt = np.diff(time, prepend=time[0])
    if floating.any():
        first = int(np.argmax(floating))
        speed = f"{v_web[first]:.4g} m/s" if v_web is not None else f"t = {time[first]:.3g} s"
        parts.append(f"it rides on air from {speed} (t = {time[first]:.3g} s to {time[floating][-1]:.3g} s, "
                     f"{float(np.sum(dt[floating])):.3g} s in all): its air film leaves the wrap no friction")
    if sliding.any():
        fastest = float(np.max(np.abs(slip[sliding])))
        slid = float(np.trapezoid(np.where(sliding, np.abs(slip), 0.0), time))
        parts.append(f"it slid from t = {time[sliding][0]:.3g} s to {time[sliding][-1]:.3g} s "
                     f"({float(np.sum(dt[sliding])):.3g} s in all), at up to {fastest:.3g} m/s, "
                     f"{slid:.3g} m of web slid over it")
    elif not floating.any():
        parts.append("it never slid")
    return f"{c.name}: " + "; ".join(parts)


def traction_columns(scene, c) -> list:
    """What a roller the web may slip on records for the summary: its traction in use, its slip and
    mu_eff for `traction_report`, and for `floating_report` the web's speed over it and the tensions
    of the spans on either side."""
    return [(c.name, "traction"), (c.name, "slip"), (c.name, "mu_eff"), (c.name, "v_web"), (scene.span_before(c).name, "T"),
            (scene.span_after(c).name, "T")]


def floating_report(scene, c, result) -> str | None:
    """Where the web's centripetal force takes all its pressure off the wrap (T - rho_l v_w^2 <= 0 < T on
    a side, docs/physics.md "Rollers that slip"), the wrap has no traction: when, and at which speed."""
    if not (c.traction.mu > 0.0 and c.wrap):
        return None
    keys = result.keys()
    before, after = scene.span_before(c), scene.span_after(c)
    names = [f"{c.name}.v_web", f"{before.name}.T", f"{after.name}.T"]
    if not all(n in keys for n in names):
        return None
    v, t_a, t_b = (result.column(n) for n in names)
    relief = before.wp2.rho_l * v * v
    tension = np.minimum(t_a, t_b)
    floating = (tension - relief <= 0.0) & (tension > 0.0)
    if not floating.any():
        return None
    k = int(np.argmax(np.where(floating, relief - tension, -np.inf)))
    time = result.time
    dt = np.diff(time, prepend=time[0])
    return (f"{c.name}: no traction on its wrap from t = {time[floating][0]:.3g} s to {time[floating][-1]:.3g} s "
            f"({float(np.sum(dt[floating])):.3g} s in all): at v_web = {v[k]:.4g} m/s the web's centripetal "
            f"force rho_l v^2 = {relief[k]:.4g} N takes all of its tension {tension[k]:.4g} N off the wrap")


def system_summary(result: Result) -> str:
    """What a run of an SSP shows: each recorded column's start, range and end."""
    info = result.info
    lines = [f"{result.scene}: engine {info['engine']}: {info['method']}, step {info['step'] * 1e3:g} ms, "
             f"{info['steps']} steps, {info['wall_time']:.2f} s wall time"]
    lines += [f"  warning: {w}" for w in info.get("warnings", [])]
    lines.append(f"  {'variable':<28}{'start':>12}{'min':>12}{'max':>12}{'end':>12}")
    for c in result.columns:
        x = result.column(c)
        lines.append(f"  {c:<28}{x[0]:>12.6g}{x.min():>12.6g}{x.max():>12.6g}{x[-1]:>12.6g}")
    return "\n".join(lines)
