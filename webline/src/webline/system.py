"""The System: a line as FMU components and connections, and the FMU copies that carry their profiles.

A System is the one in-memory form of a line: webline runs it (`master`),
exports it to SSP and reads it back; `compiler` makes one of a scene. Every
part of a line is an FMU of this project: a ConvertingSpan per span, a
Roller per everything else (source, sink, driven roller, idler, unwinder,
winder, dancer). A component's profile JSON (tables and timed `set`
entries) is read by the FMU itself.
"""

from __future__ import annotations

import hashlib
import json
import zipfile
from dataclasses import dataclass, field
from pathlib import Path


@dataclass
class Component:
    name: str
    kind: str  # "span" | "roller"
    fmu: Path  # the FMU file it instantiates
    start: dict  # variable name -> start value (float/int/bool/str), parameters and inputs
    profile: dict | None = None  # profile JSON; exported as resources/profile.json of a per-component FMU copy


@dataclass
class Connection:
    source: tuple  # (component, output)
    target: tuple  # (component, input)


@dataclass
class System:
    name: str
    components: list  # list order = Gauss–Seidel order (rollers first, then spans in line order)
    connections: list
    start_time: float
    stop_time: float
    step: float
    record: list = field(default_factory=list)  # (component, variable)
    # The columns, where they are not the recorded variables one by one (a laminate's tension is the sum of
    # its layers' spans, docs/merge-split.md [M6]): per column its name and [(record index, weight), ...].
    sums: list | None = None

    def combine(self, data):
        """The columns from rows of the recorded variables (`sums`); the rows themselves without sums."""
        if self.sums is None:
            return data
        import numpy as np

        W = np.zeros((len(self.record), len(self.sums)))
        for j, (_, terms) in enumerate(self.sums):
            for i, w in terms:
                W[i, j] += w
        return np.asarray(data) @ W

    def component(self, name) -> Component:
        return next(c for c in self.components if c.name == name)

    def inputs_of(self, name):
        """The connections into a component, in list order."""
        return [c for c in self.connections if c.target[0] == name]

    def breakpoints(self):
        """Every time a profile table kinks or jumps and every `set` time, inside (start, stop)."""
        times = set()
        for c in self.components:
            for key, value in (c.profile or {}).items():
                if key == "set":
                    times.update(e["time"] for e in value)
                elif len(value) > 1:
                    times.update(t for t, _ in value)
        return sorted(t for t in times if self.start_time < t < self.stop_time)


# ---------------------------------------------------------------- FMU copies


def profile_text(profile: dict) -> str:
    return json.dumps(profile, indent=1, sort_keys=True) + "\n"


def fmu_with_profiles(fmu: Path, profiles: dict, cache_dir: Path) -> Path:
    """A copy of `fmu` with profiles added as resources/<file> ({file name: profile}), in `cache_dir`
    (named by the content, so equal copies are written once). An instance reads resources/<its name>.json,
    else resources/profile.json: one FMU can carry the profiles of a whole line."""
    fmu = Path(fmu)
    texts = {f"resources/{name}": profile_text(p).encode() for name, p in sorted(profiles.items())}
    h = hashlib.sha256()
    h.update(fmu.read_bytes())
    for name, text in texts.items():
        h.update(name.encode() + b"\0" + text)
    path = Path(cache_dir) / f"{fmu.stem}-{h.hexdigest()[:16]}.fmu"
    if path.exists():
        return path
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".part")
    with zipfile.ZipFile(fmu) as src, zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as dst:
        for item in src.infolist():
            if item.filename not in texts:
                dst.writestr(item, src.read(item))
        for name, text in texts.items():
            dst.writestr(name, text)
    tmp.replace(path)
    return path


def component_fmus(system: System, cache_dir: Path) -> dict:
    """Component name -> the FMU it runs from: a per-component copy carrying its profile (as
    resources/profile.json and resources/<component>.json, which an archive's FMU may already hold),
    or the FMU itself when it has none."""
    return {c.name: fmu_with_profiles(c.fmu, {"profile.json": c.profile, f"{c.name}.json": c.profile}, cache_dir)
            if c.profile else Path(c.fmu) for c in system.components}
