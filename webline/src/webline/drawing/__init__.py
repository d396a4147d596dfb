"""The drawing of a scene's line (`webline draw`): `lay_out` places it (layout.py, pure geometry),
`figure` draws it with matplotlib (render.py), `layout_dict` is the layout as NAME.layout.json holds
it, and `check_layout` checks such a layout against its scene (checking.py)."""

from .checking import check_layout  # noqa: F401
from .layout import DrawError, Layout, lay_out, layout_dict  # noqa: F401
from .render import figure  # noqa: F401
