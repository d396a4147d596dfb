#!/usr/bin/env python3
"""The line-level accuracy-cost study (docs/line-coupling.md): co-simulation
error and wall time against the communication step for each master variant,
and the stability limit of a stiff line with and without input derivatives.

    .venv/bin/python bench/line_study.py [SCENE.json] [--stiff STIFF.json] [--steps 2ms,1ms,...]
                                         [--stiff-steps ...] [--fmu-dir out] [--out out]

Writes OUT/line_study.png (the figure docs/line-coupling.md shows from
docs/images/) and prints the tables. Every run is measured against webline's monolithic reference
(webline.accuracy).
"""

import argparse
import sys
from pathlib import Path

from webline.accuracy import UNSTABLE, convergence, stability_limit, union_grid
from webline.cli import time_arg
from webline.fmus import DEFAULT_FMU_DIR
from webline.reference import reference
from webline.scene import load_scene

ROOT = Path(__file__).resolve().parents[1]
SCENES = ROOT / "webline" / "scenes"


VARIANTS = [
    ("gauss-seidel", "extrapolate"),
    ("gauss-seidel", "hold"),
    ("jacobi", "extrapolate"),
    ("jacobi", "hold"),
]


def line_study(scene, stiff_scene, steps, stiff_steps, fmu_dir, out_png):
    """The line-level accuracy–cost study: co-simulation error and wall time
    against the communication step for each master variant (scene), and the
    stability limit of a stiff line with and without input derivatives
    (stiff_scene). Writes a PNG; returns the rows for printing."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    accuracy = {}
    ref = reference(scene, times=union_grid(scene, steps))
    for alg, coupling in VARIANTS:
        accuracy[(alg, coupling)], _ = convergence(scene, steps, ref=ref, algorithm=alg, coupling=coupling, fmu_dir=fmu_dir)
    stiff = {}
    sref = reference(stiff_scene, times=union_grid(stiff_scene, stiff_steps))
    for coupling in ("extrapolate", "hold"):
        stiff[coupling], _ = convergence(stiff_scene, stiff_steps, ref=sref, coupling=coupling, fmu_dir=fmu_dir)

    fig, axes = plt.subplots(1, 3, figsize=(14, 4.2))
    for (alg, coupling), rows in accuracy.items():
        ok = [r for r in rows if r.error < UNSTABLE]
        label = f"{alg}, {coupling}"
        axes[0].loglog([r.step * 1e3 for r in ok], [r.error for r in ok], "o-", label=label)
        axes[1].loglog([r.step * 1e3 for r in ok], [r.wall_time for r in ok], "o-", label=label)
        bad = [r for r in rows if not r.error < UNSTABLE]
        if bad:
            axes[0].plot([r.step * 1e3 for r in bad], [UNSTABLE] * len(bad), "x", color=axes[0].lines[-1].get_color(), ms=10)
    axes[0].set_title(f"{scene.name}: error against the reference\n(x: diverged)")
    axes[0].set_xlabel("communication step [ms]")
    axes[0].set_ylabel("largest tension error / tension range")
    axes[1].set_title(f"{scene.name}: wall time ({scene.stop_time:g} s simulated)")
    axes[1].set_xlabel("communication step [ms]")
    axes[1].set_ylabel("wall time [s]")
    for coupling, rows in stiff.items():
        label = "input derivatives, extrapolation" if coupling == "extrapolate" else "inputs held"
        ok = [r for r in rows if r.error < UNSTABLE]
        (line,) = axes[2].loglog([r.step * 1e3 for r in ok], [r.error for r in ok], "o-", label=label)
        bad = [r for r in rows if not r.error < UNSTABLE]
        axes[2].plot([r.step * 1e3 for r in bad], [UNSTABLE] * len(bad), "x", color=line.get_color(), ms=10)
    axes[2].set_title(f"{stiff_scene.name}: stability limit\n(x: diverged)")
    axes[2].set_xlabel("communication step [ms]")
    axes[2].set_ylabel("largest tension error / tension range")
    from matplotlib.ticker import NullFormatter

    for ax, hs in zip(axes, (steps, steps, stiff_steps)):
        ax.set_xticks([h * 1e3 for h in hs])
        ax.set_xticklabels([f"{h * 1e3:g}" for h in hs], fontsize=7)
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out_png, dpi=110)
    plt.close(fig)
    return accuracy, stiff


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("scene", nargs="?", default=str(SCENES / "lamination.json"))
    p.add_argument("--stiff", default=str(SCENES / "stiff_line.json"))
    p.add_argument("--steps", default="2ms,1ms,0.5ms,0.25ms")
    p.add_argument("--stiff-steps", default="1ms,0.5ms,0.35ms,0.25ms,0.18ms,0.125ms,0.0625ms")
    p.add_argument("--fmu-dir", type=Path, default=DEFAULT_FMU_DIR)
    p.add_argument("--out", default=str(DEFAULT_FMU_DIR))
    args = p.parse_args(argv)

    scene = load_scene(args.scene, fmu_dir=args.fmu_dir)
    stiff = load_scene(args.stiff, fmu_dir=args.fmu_dir)
    steps = [time_arg(x) for x in args.steps.split(",")]
    stiff_steps = [time_arg(x) for x in args.stiff_steps.split(",")]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    png = out / "line_study.png"
    accuracy, stiff_rows = line_study(scene, stiff, steps, stiff_steps, args.fmu_dir, png)
    print(f"{scene.name}: largest tension error (and wall time) by communication step")
    print("  " + f"{'variant':<28}" + "".join(f"{h * 1e3:>16g}ms" for h in steps))
    for (alg, coupling), rows in accuracy.items():
        cells = "".join(f"{'diverged':>18}" if not r.error < UNSTABLE else f"{r.error:>10.2e} ({r.wall_time:.2f}s)" for r in rows)
        print(f"  {alg + ', ' + coupling:<28}{cells}")
    print(f"{stiff.name}: stability limit of the communication step")
    for coupling, rows in stiff_rows.items():
        ok, bad = stability_limit(rows)
        what = "with input derivatives and extrapolation" if coupling == "extrapolate" else "with inputs held"
        print(f"  {what}: stable at {ok * 1e3 if ok else '-'} ms, diverges at {bad * 1e3 if bad else '-'} ms")
    print(f"wrote {png}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
