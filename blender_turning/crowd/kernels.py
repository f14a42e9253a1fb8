"""The parametric figures of a crowd task, on the cheaper of the two kernels of the model.

:func:`blender_turning.core.run` steps the figures of Section 5 either one at a time on Python
floats (:mod:`..core.physics.one_figure`) or as one numpy batch (:mod:`..core.physics.dynamics`);
both are the
same model, held to its reference right-hand side by ``tests/test_model_kernels.py``.  A batch
pays numpy's dispatch once per step for all its figures, floats pay the arithmetic per figure:
measured on the project's 2-core machine (``scripts/bench_crowd_kernels.py``, 60 s at
dt = 0.02 s, CPU s), a batch costs about 2.2 s plus 10 ms a figure and floats 56 ms a figure,
so floats are cheaper below about 60 figures (4.4x at 10, 1.25x at 40, even at 60, the batch
1.9x cheaper at 100; BENCHMARKS.md).  Both scale with the number of steps alike, so the
crossover does not depend on the duration.
"""
from __future__ import annotations

import math

import numpy as np

from ..core.controllers import PhaseEllipse
from ..core.physics.simulate import run

__all__ = ["BATCH_FROM", "KERNELS", "kernel_for", "run_turns"]

#: Figures of one task from which the numpy batch is cheaper than floats (measured, above).
BATCH_FROM = 60
KERNELS = ("floats", "batch")


def kernel_for(count: int) -> str:
    """``"batch"`` for ``count >= BATCH_FROM`` figures, else ``"floats"``."""
    return "batch" if count >= BATCH_FROM else "floats"


def run_turns(dt: float, duration: float, figures: tuple, kernel: str | None = None) -> list:
    """Simulate ``figures`` (:class:`~.model.CrowdFigure` with :class:`~.model.Turns`, one body
    and limits) each for the crowd's ``duration`` less its time offset, on its own clock.

    ``kernel``: ``"floats"``, ``"batch"`` or ``None`` (:func:`kernel_for` the count).  Returns
    one ``(columns, fell_at, report)`` per figure: the columns of
    :func:`~..core.physics.simulate.run` (shape ``(n,)``, up to the figure's span or its fall),
    the time of the fall on its own clock (``None``: it did not fall within its span) and what
    the controller reports of the turns it followed (:class:`~..core.controllers.feasible.
    TurnsFollowed`: the lean reached where the bounds kept it below the one asked)."""
    kernel = kernel_for(len(figures)) if kernel is None else kernel
    if kernel not in KERNELS:
        raise ValueError(f"kernel = {kernel!r} is not one of {', '.join(KERNELS)}")
    fig = figures[0].figure
    spans = [duration - f.time_offset for f in figures]
    if kernel == "floats":
        out = []
        for f, span in zip(figures, spans):
            c = f.controller
            ctl = PhaseEllipse(fig.body, c.omega0, c.lean, heading=c.heading)
            r = run(fig.body, fig.limits, ctl, f.state0(), span, dt)
            out.append((r.columns, r.fell_at, ctl.report))
        return out
    heading = None if figures[0].controller.heading is None \
        else np.array([f.controller.heading for f in figures])
    ctl = PhaseEllipse(fig.body, np.array([f.controller.omega0 for f in figures]),
                       np.array([f.controller.lean for f in figures]), heading=heading)
    r = run(fig.body, fig.limits, ctl, np.stack([f.state0() for f in figures], axis=1),
            max(spans), dt)
    fell = dict(r.falls)
    out = []
    for k, span in enumerate(spans):
        n = min(int(math.floor(span / dt + 1e-9)) + 1, len(r.columns["t"]))
        at = fell.get(k)
        if at is not None and at <= (n - 1) * dt + 1e-9:       # a fall within its own span
            n = min(n, int(round(at / dt)) + 1)
        else:
            at = None
        out.append(({c: v[:n, k] for c, v in r.columns.items()}, at, ctl.batch_report(k)))
    return out
