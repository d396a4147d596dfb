"""Every mode of idler_skid with traction (at several creeps, `traction.creep`) against the same line
with the web tied to the surface (no traction), both linearized as `webline linearize` does: the
largest relative shift of a mode the tied line has, and the contact's own two fastest poles.

    .venv/bin/python bench/contact_modes.py . 5e-8,1e-7,5e-7 0      (ROOT, creeps in m, times in s)

Needs out/ (python3 fmu/package.py). Writes nothing: docs/physics.md quotes its lines."""
import copy, sys
import numpy as np
from webline import compiler, statespace
from webline.scene import load_scene

ROOT = sys.argv[1]
creeps = [float(c) for c in sys.argv[2].split(",")]
times = [float(t) for t in sys.argv[3].split(",")]
base = compiler.traction_values
creep = {"value": None}
def patched(scene, node):
    v = base(scene, node)
    if creep["value"] is not None:
        v["traction.creep"] = creep["value"]
    return v
compiler.traction_values = patched
scene = load_scene(f"{ROOT}/webline/scenes/idler_skid.json", fmu_dir=f"{ROOT}/out")
tied = copy.deepcopy(scene)
for n in tied.line:
    if getattr(n, "traction", None) is not None:
        n.traction = None
for at in times:
    ref = statespace.linearize(tied, at=at, fmu_dir=f"{ROOT}/out")
    lam0 = np.linalg.eigvals(ref.A)
    lam0 = lam0[np.abs(lam0) > 1e-9 * np.abs(lam0).max()]
    for c in creeps:
        creep["value"] = c
        ss = statespace.linearize(scene, at=at, fmu_dir=f"{ROOT}/out")
        lam = np.linalg.eigvals(ss.A)
        worst, which = 0.0, None
        for l0 in lam0:
            d = np.abs(lam - l0) / abs(l0)
            if d.min() > worst:
                worst, which = d.min(), l0
        extra = sorted(lam, key=abs)[-2:]
        print(f"t {at} s, creep {c:g} m: {len(lam0)} shared modes, largest shift {worst:.2e} (at {which:.4g}); "
              f"contact's own fastest {extra[0]:.3g}, {extra[1]:.3g}", flush=True)
