"""Crowd pictures: a ski school behind its instructor, a peloton through a bend,
from the shipped crowd scenes (``scenes/crowds/``)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..crowd import load_crowd, run_crowd
from .planner import SCENES, plot_scene
from .plots import pyplot, save_figure


def ski_school(out: Path) -> None:
    """The instructor's slalom (black) and eight pupils 1.5 s apart, 1.5 m either side, each
    a little different (seeded); dots: everybody at t = 20 s."""
    crowd = load_crowd(SCENES / "crowds" / "ski_school.json")
    res = run_crowd(crowd)
    plt = pyplot()
    f, ax = plt.subplots(figsize=(14, 2.6))
    for i, r in enumerate(res.figures):
        tr = r.trajectory
        lead = i == 0
        ax.plot(tr.x, tr.y, "k" if lead else f"C{i % 10}", lw=2.0 if lead else 0.9,
                label=r.name if lead or i == 1 else None)
        k = int(np.argmin(np.abs(tr.t - 20.0)))
        ax.plot(tr.x[k], tr.y[k], "o", color="k" if lead else f"C{i % 10}", ms=5)
    ax.set_aspect("equal")
    ax.set_ylim(-8, 8)
    ax.set(xlabel="x (m)", ylabel="y (m)",
           title=f"Crowd: {crowd.name} ({len(crowd.figures)} figures, follow_leader); "
                 f"dots at t = 20 s")
    ax.legend(fontsize=8, loc="upper right")
    save_figure(f, Path(out) / "crowd_ski_school.png")


def peloton(out: Path) -> None:
    """Six cyclists two abreast round the corner of Fig. 18, each planning its own line."""
    crowd = load_crowd(SCENES / "crowds" / "peloton.json")
    res = run_crowd(crowd)
    scene = crowd.figures[0].controller.scene
    tracks = [(r.trajectory, r.name, "-") for r in res.figures if r.trajectory is not None]
    plot_scene(scene, tracks, Path(out) / "crowd_peloton.png",
               f"Crowd: {crowd.name} ({len(crowd.figures)} riders, peloton)")
