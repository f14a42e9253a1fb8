"""Plotting helpers shared by the figures and the CLI (matplotlib, Agg backend)."""
from __future__ import annotations

import numpy as np


def pyplot():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def save_figure(fig, path, dpi: int = 90) -> None:
    """Lay out, write as PNG and close a matplotlib figure."""
    fig.tight_layout()
    fig.savefig(path, dpi=dpi, format="png")
    pyplot().close(fig)


def plot_trajectory(traj, path, title: str = "") -> None:
    """Track, lean and curvature over time, and the phase diagram of one trajectory."""
    plt = pyplot()
    fig, ax = plt.subplots(1, 3, figsize=(15, 4.2))
    ax[0].plot(traj.x, traj.y, lw=1.2)
    ax[0].set_aspect("equal", adjustable="datalim")
    ax[0].set(xlabel="x (m)", ylabel="y (m)", title="foot track")
    ax[1].plot(traj.t, np.degrees(traj.theta_v), label="lean theta_v (deg)")
    ax1b = ax[1].twinx()
    ax1b.plot(traj.t, traj.C_f, color="C1", lw=1, label="C_f (1/m)")
    ax[1].set(xlabel="t (s)", ylabel="theta_v (deg)", title="lean and foot curvature")
    ax1b.set_ylabel("C_f (1/m)", color="C1")
    ax[2].plot(np.degrees(traj.omega_v), np.degrees(traj.theta_v), lw=1)
    ax[2].set(xlabel="omega_v (deg/s)", ylabel="theta_v (deg)", title="phase diagram")
    fig.suptitle(title)
    save_figure(fig, path)
