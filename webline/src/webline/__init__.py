"""webline: web lines of ConvertingSpan and Roller FMUs, co-simulated with FMPy.

    webline run webline/scenes/lamination.json      # CSV, PNG and a summary in out/
    python -m webline --help

Modules: `scene` (the JSON format, read strictly), `system` (a line as FMU
components and connections), `master` (runs a System), `compiler` (scenes
compiled into a System, and run), `reference` (the monolithic SciPy
reference), `accuracy` (errors against it), `sweep` (parameter grids on Dask).
"""

import os

# A line's matrices have tens of rows: BLAS threads only contend for the cores, and on a busy machine
# a stability prediction took 70 times longer with them (5.3 s against 0.08 s). One thread unless the
# user says otherwise; OpenBLAS reads this when NumPy loads, so it acts where webline is imported first.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from .scene import SceneError, load_scene, parse_scene  # noqa: F401

__all__ = ["load_scene", "parse_scene", "SceneError"]
