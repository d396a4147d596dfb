#!/usr/bin/env bash
# Main job: build ConvertingSpan.fmu and simulate the default scene with FMPy.
# Writes out/ConvertingSpan.fmu, out/default_scene.csv and out/default_scene.png.
set -euo pipefail
source "$(dirname "$0")/env.sh"
cd "$ROOT"
python3 fmu/package.py
"$PY" fmu/demo.py out/ConvertingSpan.fmu --out out
