"""Scenes: a web line described in JSON, read strictly.

A scene is a chain, source -> span -> roller -> span -> ... -> sink, with
the webs the spans carry, input profiles, the communication step, the stop
time, events (properties that change on the fly) and the outputs to record.
A roller of the chain may carry side paths: webs that merge into it (a
laminating nip, "merge") or webs it splits into (a slitter, "split");
docs/merge-split.md. The format is documented in docs/scenes.md. Every problem is a
`SceneError` whose message starts with `file:line:column` of the offending
key or value: an unknown key, a missing value, a wrong unit, a chain that is
not a line.

The package's rooms, by job: `types` (the model a scene is read into), `reading` (the JSON read
strictly, `parse_scene` and `load_scene`), `checks` (the line's rules, once its parts are read).
"""

from .reading import load_scene, parse_scene, set_path  # noqa: F401
from .types import (  # noqa: F401
    BRAKE_CREEP, BRAKE_V_SLIP, LAYON_QUANTITIES, LOAD_CELL_QUANTITIES, NIP_SIDES, QUANTITIES, STRAIN_RANGE, TRACTION_CREEP, TRACTION_QUANTITIES, Branch, Component, Dancer, Drive, Event, Loop,
    LayOn, Node, Prescribed, Roller, Runout, Scene, SceneError, Span, Traction, Web, Wound, quantities_of, quantity_unit, span_layers,
)
