"""A tree on the line (docs/racing.md, "An obstacle on the line"): a straight 120 m path with a
tree of 0.5 m radius on it at 60 m (clearance 0.5 m: the foot must pass about 1 m to the side),
followed by the path planner (Section 6) at 8 m/s; prints how far the foot got from the path.

    python scripts/tree_on_line.py [--preset telemark skier] [--choices 5] [--stages 10]
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from blender_turning.core.course.scene import scene_from_dict  # noqa: E402


def course(preset: str, choices: int, stages: int, near: int) -> dict:
    """The scene document: the path along +x, the tree at (60, 0)."""
    return {"name": "tree on the line",
            "figure": {"preset": preset, "body": {"V_cm": 8.0}, "limits": {"dC_f_max": 0.3}},
            "path": {"points": [[0.0, 0.0], [120.0, 0.0]], "tangents": [[120.0, 0.0]] * 2},
            "clearance": 0.5, "obstacles": [{"type": "circle", "center": [60.0, 0.0],
                                             "radius": 0.5}],
            "start": {"position": [0, 0], "heading_deg": 0},
            "planner": {"stages": stages, "choices": choices, "stage_time": 0.3,
                        **({"choices_near": near} if near else {})}}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--preset", nargs="+", default=["telemark", "skier"])
    p.add_argument("--choices", type=int, default=5)
    p.add_argument("--stages", type=int, default=10)
    p.add_argument("--near", type=int, default=0,
                   help="the planner's choices near an obstacle (scene planner.choices_near)")
    a = p.parse_args(argv)
    for name in a.preset:
        scene = scene_from_dict(course(name, a.choices, a.stages, a.near), "tree")
        t0 = time.perf_counter()
        traj = scene.run().trajectory
        far = float(np.abs(traj.y).max())
        print(f"{name}: q = {a.choices}, near {a.near or a.choices}, N = {a.stages}: farthest "
              f"{far:.2f} m from the path ({time.perf_counter() - t0:.0f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
