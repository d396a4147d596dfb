"""PNG plots of a run: tensions of the spans and speeds of the rollers along the line."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from .result import Result  # noqa: E402


def plot(result: Result, path, title=None, reference: Result | None = None):
    """Tensions (N) on top, speeds (m/s) below, in line order; other recorded
    quantities (strain, dancer position, torque) in a third panel if any."""
    groups = {"tension": [], "speed": [], "other": []}
    for c in result.columns:
        key, unit = c.split(" [")[0], c.split(" [")[1].rstrip("]")
        q = key.split(".", 1)[1]
        if q in ("T", "F_a", "F_b"):
            groups["tension"].append((c, key))
        elif q == "v":
            groups["speed"].append((c, key))
        else:
            groups["other"].append((c, key))
    panels = [g for g in ("tension", "speed", "other") if groups[g]]
    fig, axes = plt.subplots(len(panels), 1, figsize=(9, 2.8 * len(panels) + 0.6), sharex=True, squeeze=False)
    labels = {"tension": "tension [N]", "speed": "speed [m/s]", "other": "value"}
    for ax, g in zip(axes[:, 0], panels):
        for col, key in groups[g]:
            (line,) = ax.plot(result.time, result.column(key), lw=1.3, label=col if g == "other" else key)
            if reference is not None and key in reference.keys():
                ax.plot(reference.time, reference.column(key), lw=0.8, ls="--", color=line.get_color())
        ax.set_ylabel(labels[g])
        ax.grid(True, alpha=0.3)
        ax.legend(loc="best", fontsize=8, ncol=2)
    axes[-1, 0].set_xlabel("time [s]")
    info = result.info
    sub = f"{info.get('method', '')}, step {info.get('step', 0) * 1e3:g} ms" if info else ""
    if reference is not None:
        sub += "; dashed: monolithic reference"
    fig.suptitle(f"{title or result.scene}\n{sub}", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
