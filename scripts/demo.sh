#!/usr/bin/env bash
# The main job: a slalom simulated by the core, its trajectory CSV, and the paper's figures.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/scripts/env.sh"
cd "$root"
out="${1:-$root/out}"
mkdir -p "$out"
py="$root/.venv/bin/python"
"$py" -m blender_turning simulate --preset skier --controller ellipse --period 2 --lean-deg 23 \
  --heading-deg 0 --duration 20 --fps 24 --out "$out/slalom.csv" --plot "$out/slalom.png"
"$py" -m blender_turning figures --out "$out/figures"
echo "demo: trajectory $out/slalom.csv, plot $out/slalom.png, figures in $out/figures"
