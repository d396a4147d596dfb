"""The table of docs/ssp.md: every shipped scene exported to SSP and run by libcosim and FMPy, against
webline's master on the same coupling and against the monolithic reference; a scene the parts' co-simulation
refuses (runout, a lay-on roller, a web that slips: its SSP export refuses it too) gets the reason instead.

    .venv/bin/python bench/ssp_agreement.py
"""

import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def main():
    from webline.engines import agreement
    from webline.scene import SceneError

    print("| scene | step | steps | libcosim vs webline | FMPy vs webline (FMPy start) | libcosim vs reference "
          "| FMPy vs reference | webline (Jacobi, held) vs reference |")
    print("|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for path in sorted((ROOT / "webline" / "scenes").glob("*.json")):
            try:
                r = agreement(path, ROOT / "out", Path(tmp))
            except SceneError as refused:
                print(f"| {path.stem} | refused: {str(refused).split(': ', 1)[-1]} |||||||", flush=True)
                continue
            print(f"| {r['scene']} | {r['step'] * 1e3:g} ms | {r['steps']} | {r['libcosim_vs_webline']:.1e} "
                  f"| {r['fmpy_vs_webline']:.1e} | {r['libcosim_vs_reference']:.1e} | {r['fmpy_vs_reference']:.1e} "
                  f"| {r['webline_vs_reference']:.1e} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
