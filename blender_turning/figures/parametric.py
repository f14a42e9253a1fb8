"""Figs. 3, 5, 6 and 10 of the paper (Sections 4-5), regenerated from the core."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..core import OpenLoop, PhaseEllipse, Schedule, preset, simulate, slalom_start
from .plots import pyplot, save_figure

TWO_PI = 2 * math.pi


def fig03(out: Path) -> None:
    """Fig. 3: the phase diagram; a run that starts off the ellipse converges onto it."""
    plt = pyplot()
    fig = preset("skier")
    w, tm = TWO_PI / 2.0, math.radians(23)
    f, ax = plt.subplots(figsize=(6, 5.5))
    a = np.linspace(0, TWO_PI, 200)
    ax.plot(np.degrees(w * tm * np.cos(a)), np.degrees(tm * np.sin(a)), "k", lw=2.5,
            label="target ellipse")
    for th0, om0, c in ((0.0, 0.3, "C0"), (math.radians(35), 0.0, "C1"),
                        (math.radians(-5), -0.2, "C2")):
        tr = simulate(fig, PhaseEllipse(fig.body, w, tm), 4.0, state0=(0, 0, 0, th0, om0))
        ax.plot(np.degrees(tr.omega_v), np.degrees(tr.theta_v), c, lw=1,
                label=f"start ({math.degrees(om0):.0f} deg/s, {math.degrees(th0):.0f} deg)")
        ax.plot([math.degrees(om0)], [math.degrees(th0)], "o", color=c)
    for phi_deg in (0, 90, 180, 270):
        p = math.radians(phi_deg)
        ax.annotate(f"phi={phi_deg}", (math.degrees(w * tm * math.cos(p)),
                                       math.degrees(tm * math.sin(p))), fontsize=8)
    ax.set(xlabel="omega_v (deg/s)", ylabel="theta_v (deg)",
           title="Fig. 3: phase diagram of a turn (2 s, 23 deg)")
    ax.legend(fontsize=7, loc="lower right")
    save_figure(f, out / "fig03_phase_diagram.png", dpi=90)


def fig05(out: Path) -> None:
    """Fig. 5: theta_v, C_f and F_leg over one period of a typical turn, scaled to +-1."""
    plt = pyplot()
    fig = preset("skier")
    w, tm = TWO_PI / 2.0, math.radians(23)
    tr = simulate(fig, OpenLoop(fig.body, w, tm), 2.0, state0=(0, 0, 0, 0, w * tm))
    f, ax = plt.subplots(figsize=(7, 4))
    ph = np.degrees(np.unwrap(tr.phi))
    weight = fig.body.m * fig.body.g
    ax.plot(ph, tr.theta_v / tm, label=f"theta_v / {math.degrees(tm):.0f} deg")
    ax.plot(ph, tr.C_f / np.abs(tr.C_f).max(), label=f"C_f / {np.abs(tr.C_f).max():.3f} 1/m")
    ax.plot(ph, (tr.F_leg - weight) / (np.abs(tr.F_leg - weight).max()),
            label=f"(F_leg - mg) / {np.abs(tr.F_leg - weight).max():.0f} N "
                  f"({100 * np.abs(tr.F_leg - weight).max() / weight:.0f}% of mg)")
    ax.axhline(0, color="k", lw=0.5)
    ax.set(xlabel="phase (deg)", ylabel="scaled", title="Fig. 5: a typical turn")
    ax.legend(fontsize=8)
    save_figure(f, out / "fig05_typical_turn.png", dpi=90)


def fig06(out: Path) -> None:
    """Fig. 6: foot tracks of the three phase ellipses (2 s/23, 3 s/23, 2 s/7 deg)."""
    plt = pyplot()
    fig = preset("skier")
    f, ax = plt.subplots(figsize=(10, 4))
    for i, (period, lean) in enumerate(((2.0, 23), (3.0, 23), (2.0, 7))):
        w, tm = TWO_PI / period, math.radians(lean)
        tr = simulate(fig, OpenLoop(fig.body, w, tm), 3 * period,
                      state0=slalom_start(fig.body, w, tm, y=-8.0 * i))
        ax.plot(tr.x, tr.y, label=f"ellipse {i + 1}: {period:g} s, {lean} deg")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set(xlabel="x (m)", ylabel="y (m)", title="Fig. 6: tracks of three phase ellipses")
    ax.legend(fontsize=8)
    save_figure(f, out / "fig06_tracks.png", dpi=90)


def fig10(out: Path) -> None:
    """Fig. 10: figure-8 pair; decreasing frequency; increasing sharpness; heading control."""
    plt = pyplot()
    fig = preset("skier")
    w, tm = TWO_PI / 2.0, math.radians(23)
    f, axes = plt.subplots(4, 1, figsize=(10, 11))
    # 1: two figures turning out of phase on the same line: a figure-8 pattern (a synchronised
    # pair of the crowd code, run as one batch).
    from ..crowd import Crowd, CrowdFigure, Turns, run_crowd, synchronized
    pair = synchronized(CrowdFigure("skier", fig, Turns(TWO_PI / w, tm, 0.0)), 2, antiphase=True)
    for r, c in zip(run_crowd(Crowd("figure-8", pair, 12.0)).figures, ("C0", "C3")):
        axes[0].plot(r.trajectory.x, r.trajectory.y, c, label=f"{r.name}")
    axes[0].legend(fontsize=7, loc="upper right")
    axes[0].set_title("1: figure-8 (a synchronised pair in antiphase)")
    # 2: decreasing frequency: period 1.6 s -> 3.2 s.
    period = Schedule.sampled([0.0, 20.0], [1.6, 3.2])
    om = Schedule(lambda t: TWO_PI / period(t))
    tr = simulate(fig, PhaseEllipse(fig.body, om, tm, heading=0.0), 20.0,
                  state0=slalom_start(fig.body, om(0.0), tm))
    axes[1].plot(tr.x, tr.y, "C1")
    axes[1].set_title("2: decreasing frequency (period 1.6 -> 3.2 s)")
    # 3: increasing sharpness: lean 8 -> 30 deg.
    lean = Schedule.sampled([0.0, 16.0], np.radians([8.0, 30.0]))
    tr = simulate(fig, PhaseEllipse(fig.body, w, lean, heading=0.0), 16.0,
                  state0=slalom_start(fig.body, w, lean(0.0)))
    axes[2].plot(tr.x, tr.y, "C2")
    axes[2].set_title("3: increasing sharpness (lean 8 -> 30 deg)")
    # 4: heading control: 0 -> +10 deg at 6 s -> -10 deg at 14 s.
    head = Schedule(lambda t: math.radians(0 if t < 6 else (10 if t < 14 else -10)))
    tr = simulate(fig, PhaseEllipse(fig.body, w, tm, heading=head), 24.0,
                  state0=slalom_start(fig.body, w, tm))
    axes[3].plot(tr.x, tr.y, "C4")
    axes[3].set_title("4: heading control (0, +10 deg at 6 s, -10 deg at 14 s)")
    for ax in axes:
        ax.set_aspect("equal", adjustable="datalim")
        ax.set(xlabel="x (m)", ylabel="y (m)")
    f.suptitle("Fig. 10: tracks under parameterized control")
    save_figure(f, out / "fig10_parametric_tracks.png", dpi=80)
