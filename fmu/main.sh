#!/usr/bin/env bash
# Main job: build ConvertingSpan.fmu and Roller.fmu, simulate the default scene
# with FMPy, and co-simulate the lamination line with the webline runner.
# Writes out/ConvertingSpan.fmu, out/Roller.fmu, their compatibility files
# (fmu/compat.py), the webline wheel with them (out/dist/webline-VERSION-py3-none-any.whl,
# fmu/wheel.py), out/default_scene.csv/png and out/lamination.csv/png.
set -euo pipefail
source "$(dirname "$0")/env.sh"
cd "$ROOT"
python3 fmu/package.py
"$PY" fmu/compat.py out
"$PY" fmu/wheel.py
"$PY" fmu/demo.py out/ConvertingSpan.fmu --out out
"$VENV/bin/webline" run webline/scenes/lamination.json --out out  # as one Line FMU: webline run's default engine
