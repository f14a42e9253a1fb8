#!/usr/bin/env bash
# The main job: a slalom simulated by the core (trajectory CSV, plot, the paper's figures), then
# the Blender demo: all four figures and a ski school for a few seconds, baked and rendered small
# with Workbench.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/scripts/env.sh"
cd "$root"
out="${1:-$root/out}"
mkdir -p "$out"
py="$root/.venv/bin/python"
"$py" -m blender_turning simulate --preset skier --controller ellipse --period 2 --lean-deg 23 \
  --heading-deg 0 --duration 20 --fps 24 --out "$out/slalom.csv" --plot "$out/slalom.png"
# The paper's figures (27 s of CPU) on the second core, while Blender bakes and renders.
"$py" -m blender_turning figures --out "$out/figures" > "$out/figures.log" 2>&1 &
figures=$!
trap 'kill "$figures" 2> /dev/null || true' EXIT      # a failed render ends it too
# The Blender demo (bpy wheel, background): skier, snowboarder and telemark skier down a snowy
# mountain, a cyclist on a road over a hill, one follow shot each, and a ski school (an
# instructor and 8 pupils) with a shot of its own, 4 s at 320x180.  Prints a line per figure
# baked and per shot rendered (with the time left), then where the frames (frames/<figure>/,
# shots.png) and .blend are.
"$py" "$root/scripts/render_job.py" --config "$root/scripts/configs/demo.toml" \
  --output "$out/blender_demo" | grep --line-buffered -v "| Saved:\|rendered frame "
wait "$figures" || { cat "$out/figures.log"; exit 1; }
cat "$out/figures.log"
echo "demo: trajectory $out/slalom.csv, plot $out/slalom.png, figures in $out/figures"
echo "demo: Blender frames in $out/blender_demo/frames/<figure>, all shots in" \
  "$out/blender_demo/shots.png, scene in $out/blender_demo/demo.blend"
