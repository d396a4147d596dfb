"""webline: web lines of ConvertingSpan and Roller FMUs, co-simulated with FMPy.

    webline run webline/scenes/lamination.json      # CSV, PNG and a summary in out/
    python -m webline --help

Modules: `scene` (the JSON format, read strictly), `system` (a line as FMU
components and connections), `master` (runs a System), `compiler` (scenes
compiled into a System, and run), `reference` (the monolithic SciPy
reference), `accuracy` (errors against it), `sweep` (parameter grids on Dask).
"""

from .scene import SceneError, load_scene, parse_scene  # noqa: F401

__all__ = ["load_scene", "parse_scene", "SceneError"]
