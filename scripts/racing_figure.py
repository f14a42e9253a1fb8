"""docs/racing.png: the skier's preset and the slalom racer at the apex of the same commanded
turn (period 2 s, lean asked 60 deg, 12 m/s, heading held), seen from behind: the built-in
rig's bones by forward kinematics of the mapping (Section 7), the skis' edge angle printed.

    PYTHONPATH=$PWD .venv/bin/python scripts/racing_figure.py [docs/racing.png]
"""
from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from blender_turning.core import PhaseEllipse, preset, simulate, slalom_start  # noqa: E402
from blender_turning.core.equipment import sport_of  # noqa: E402
from blender_turning.mapping import map_trajectory  # noqa: E402
from blender_turning.mapping.kinematics import Skeleton  # noqa: E402
from blender_turning.mapping.rig_spec import load_rig  # noqa: E402


def apex_pose(name: str, speed: float = 12.0, period: float = 2.0, lean_deg: float = 60.0):
    """``(skeleton, armature-space poses at the apex, theta_v, ski roll)`` of ``name``."""
    fig = preset(name, V_cm=speed)
    ctl = PhaseEllipse(fig.body, 2 * math.pi / period, math.radians(lean_deg), 0.0,
                       limits=fig.limits)
    w, tm = ctl.target(0.0)
    traj = simulate(fig, ctl, 3 * period, state0=slalom_start(fig.body, w, tm)).resample(24)
    k = int(np.argmax(traj.theta_v * (traj.t > period)))
    spec = load_rig(sport_of(name))
    skel = Skeleton.from_spec(spec)
    P = skel.fk(map_trajectory(sport_of(name), traj).bones, len(traj))
    ski = P["ski.L"][k, :3, :3]
    roll = math.atan2(ski[2, 0], ski[0, 0])
    return skel, {b: m[k] for b, m in P.items()}, float(traj.theta_v[k]), roll


def draw(ax, skel, P, title):
    for b in skel.names:
        head = P[b][:3, 3]
        tail = head + skel.length(b) * P[b][:3, 1]
        if b.startswith("ski"):          # seen along its length: its sole (x4), edge down
            mid, across = 0.5 * (head + tail), 0.28 * P[b][:3, 0]
            a, c = mid, mid + (across if across[2] > 0 else -across)
            ax.plot([a[0], c[0]], [a[2], c[2]], color="tab:red", lw=4, solid_capstyle="butt")
            continue
        ax.plot([head[0], tail[0]], [head[2], tail[2]], lw=1 if b.startswith("pole") else 1.8,
                color="0.6" if b.startswith("pole") else "k")
    ax.axhline(0.0, color="0.6", lw=1)
    ax.set_aspect("equal")
    ax.set_xlim(-1.8, 0.8)
    ax.set_ylim(-0.2, 1.9)
    ax.set_title(title, fontsize=9)
    ax.axis("off")


def main(argv=None) -> int:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    out = Path((argv or sys.argv[1:] or ["docs/racing.png"])[0])
    fig, axes = plt.subplots(1, 2, figsize=(7.0, 3.2))
    for ax, name, label in zip(axes, ("skier", "slalom_racer"), ("skier preset", "slalom racer")):
        skel, P, th, roll = apex_pose(name)
        draw(ax, skel, P, f"{label}: lean {math.degrees(th):.1f} deg, "
                          f"skis on edge {math.degrees(abs(roll)):.1f} deg")
    fig.suptitle("Apex of a left turn asked at 60 deg, 2 s, 12 m/s (seen from behind)",
                 fontsize=10)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    print(f"racing_figure: {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
