"""Benchmark of the physics core. Prints a Markdown table; timings are best of N.

    .venv/bin/python scripts/bench_core.py [--repeat 5]
    .venv/bin/python scripts/bench_core.py --terrain [--repeat 3]


- One figure: 60 s of a 2 s / 23 deg slalom under the phase-ellipse controller with heading
  control, at the default step (the accuracy the tests demand): simulated seconds per wall second;
  also the open-loop slalom of Section 4 (no feedback), for scale, and the slalom on one ellipse
  (no heading) against the same run as a bare float RK4 loop with the same arithmetic
  (:func:`bare_loop`, bit for bit the core's trajectory): what the core's structure costs.
  Baseline in the same run: the same figure stepped by the numpy backend (a batch of one).
- A batch of 1,000 figures stepped together: figure-steps per second.  Baseline in the same run:
  50 of the figures one after another on floats.  Also the numpy floor: the cheapest RK4 step
  numpy can take for the batch (no controller, no bounds), and its sines and cosines alone.
- ``--terrain``: 60 s of the same slalom through ``simulate`` on flat ground (today's
  path, the baseline), through the terrain loop on flat ground, down an 18 deg plane and down
  the demo's mogul slope (``terrain_gen.ski_slope``, a height field), with the skier's snow
  friction and drag.  Warm: the feasibility tables the phase-ellipse controller builds per
  0.5 m/s of speed are cached across runs; the cold first run is reported too.
"""
from __future__ import annotations

import argparse
import datetime
import math
import os
import platform
import time

import numpy as np

from blender_turning.core import OpenLoop, PhaseEllipse, preset, run
from blender_turning.core.controllers.heading_table import heading_table
from blender_turning.core.physics.simulate import DEFAULT_DT
from bench_common import best  # noqa: E402  (scripts/)


def numpy_floor(n, repeat, dt=DEFAULT_DT):
    """The cheapest RK4 step numpy can take for ``n`` figures: Eqs. 2 and 21 under a fixed
    curvature (no controller, no bounds), in place where numpy allows.  Any real step does this
    and more, so its rate caps what the batch can reach.  Also the cap from the 16 sines and
    cosines alone (sin/cos of theta_v and theta_dir at each of the four stages).
    Returns ``(step seconds, trig-only seconds)``."""
    b = preset("skier").body
    rng = np.random.default_rng(0)
    x = np.zeros((5, n))
    x[3] = rng.uniform(-0.3, 0.3, n)
    cf = np.full(n, 0.05)
    ks = [np.empty((5, n)) for _ in range(4)]

    def rhs(s, out):
        sn, cs = np.sin(s[3]), np.cos(s[3])
        r = 1.0 / (1.0 - cf * b.l * sn)
        vf = b.V_cm * r
        out[0], out[1], out[2], out[3] = vf * np.cos(s[2]), vf * np.sin(s[2]), vf * cf, s[4]
        out[4] = (b.g * sn - cf * b.V_cm ** 2 * cs * r) / b.J
        return out

    def step():
        h = 0.5 * dt
        k1 = rhs(x, ks[0])
        k2 = rhs(x + h * k1, ks[1])
        k3 = rhs(x + h * k2, ks[2])
        k4 = rhs(x + dt * k3, ks[3])
        return x + (dt / 6.0) * (k1 + 2.0 * (k2 + k3) + k4)

    def trig():
        for _ in range(4):
            np.sin(x[3]), np.cos(x[3]), np.sin(x[2]), np.cos(x[2])

    return (best(lambda: [step() for _ in range(100)], repeat) / 100,
            best(lambda: [trig() for _ in range(100)], repeat) / 100)


def bare_loop(fig, w, tm, n, dt=DEFAULT_DT):
    """``run(body, limits, PhaseEllipse(body, w, tm), ...)`` for one figure (no heading: one
    ellipse throughout) as a bare float RK4 loop with the same arithmetic: one function for the
    right-hand side (Section 5.1's smooth law, Eq. 1, Section 3's bounds, Eqs. 21 and 2) and the
    classical RK4 written out, a row per sample; no controller, no schedules, no bookkeeping.
    Returns the rows (``run``'s columns x .. V_f)."""
    from blender_turning.core.controllers.ellipse import GAIN
    from blender_turning.core.controllers.feasible import feasible_turns
    from blender_turning.core.physics.dynamics import PHYSICAL_MARGIN
    b, lim = fig.body, fig.limits
    g, l, J, V = b.g, b.l, b.J, b.V_cm
    VV, VV2 = V * V, V ** 2
    cmax, rate, fall = lim.C_f_max, lim.dC_f_max, lim.theta_fall
    tmf = min(tm, feasible_turns(b, lim).max_lean(w))
    amax, r0, w2, wt = 2.0 * w * w * tmf, 0.05, w * w, w * tmf
    sin, cos, sqrt, inf, copysign = math.sin, math.cos, math.sqrt, math.inf, math.copysign

    def f(x2, x3, x4, anchor, tau):
        xe, ye = x4 / wt, x3 / tmf
        r = sqrt(xe * xe + ye * ye)
        a = -w2 * x3 + GAIN * w2 * tmf * (1.0 - r) * xe / (r if r > 1.0 else 1.0)
        if r < r0:
            q = 1.0 - r / r0
            a += 0.5 * amax * q * q
        a = -amax if a < -amax else (amax if a > amax else a)
        s, c = sin(x3), cos(x3)
        k = g * s - a * J
        den = k * l * s + VV2 * c
        cf = k / den if den > 0.0 else copysign(inf, k)
        ls = l * s
        lo = -cmax if ls >= 0.0 else max(-cmax, PHYSICAL_MARGIN / ls)
        hi = cmax if ls <= 0.0 else min(cmax, PHYSICAL_MARGIN / ls)
        cf = lo if cf < lo else hi if cf > hi else cf
        if anchor is not None:
            step = rate * tau
            cf = anchor - step if cf < anchor - step else anchor + step if cf > anchor + step \
                else cf
        ratio = 1.0 / (1.0 - cf * ls)
        V_f = V * ratio
        alpha = (g * s - cf * VV * c * ratio) / J
        return V_f * cos(x2), V_f * sin(x2), V_f * cf, x4, alpha, cf, V_f

    h, w6 = 0.5 * dt, dt / 6.0
    x0, x1, x2, x3, x4 = 0.0, 0.0, 0.0, 0.0, w * tm
    anchor, rows = None, []
    for i in range(n):
        a0, a1, a2, a3, a4, cf, V_f = f(x2, x3, x4, anchor, dt)
        rows.append((x0, x1, x2, x3, x4, a4, cf, V_f))
        if abs(x3) > fall or i + 1 == n:
            break
        b0, b1, b2, b3, b4, _, _ = f(x2 + h * a2, x3 + h * a3, x4 + h * a4, cf, h)
        c0, c1, c2, c3, c4, _, _ = f(x2 + h * b2, x3 + h * b3, x4 + h * b4, cf, h)
        d0, d1, d2, d3, d4, _, _ = f(x2 + dt * c2, x3 + dt * c3, x4 + dt * c4, cf, dt)
        x0 += w6 * (a0 + 2.0 * (b0 + c0) + d0)
        x1 += w6 * (a1 + 2.0 * (b1 + c1) + d1)
        x2 += w6 * (a2 + 2.0 * (b2 + c2) + d2)
        x3 += w6 * (a3 + 2.0 * (b3 + c3) + d3)
        x4 += w6 * (a4 + 2.0 * (b4 + c4) + d4)
        anchor = cf
    return rows


def terrain(repeat):
    """The ``--terrain`` table."""
    from blender_turning.core import simulate, slalom_start
    from blender_turning.core.ground.terrain import FLAT, Plane
    from blender_turning.core.physics.model import RESISTANCE
    from blender_turning.core.ground.terrain_gen import ski_slope
    from blender_turning.core.physics.model import NO_RESISTANCE
    from blender_turning.core.physics.terrain_sim import simulate_free

    fig = preset("skier")
    w, tm = 2 * math.pi / 2.0, math.radians(23)
    fall = -math.pi / 2
    slope = ski_slope(length=1600.0, width=400.0, cell=2.0)
    res = RESISTANCE["skier"]

    def case(**kw):
        def go():
            s0 = slalom_start(fig.body, w, tm, fall, -40.0, 790.0)
            return simulate(fig, PhaseEllipse(fig.body, w, tm, heading=fall), 60.0, DEFAULT_DT,
                            s0, **kw)
        return go

    def terrain_flat():
        s0 = slalom_start(fig.body, w, tm, fall)
        return simulate_free(fig, PhaseEllipse(fig.body, w, tm, heading=fall), 60.0,
                             DEFAULT_DT, s0, FLAT, NO_RESISTANCE)

    cases = [("flat ground, `simulate` (today's path): baseline", case()),
             ("flat ground, the speed free (the any-ground loop)", terrain_flat),
             ("18 deg plane, fall line, skier's friction and drag", case(
                 ground=Plane(math.radians(18), fall), resistance=res)),
             ("mogul slope (height field 201 x 801, 2 m), fall line", case(ground=slope,
                                                                          resistance=res)),
             ("mogul slope, target speed 12 m/s", case(ground=slope, resistance=res,
                                                       target_speed=12.0))]
    print(f"date: {datetime.date.today()}, machine: {os.cpu_count()} cores, "
          f"Python {platform.python_version()}, numpy {np.__version__}, dt = {DEFAULT_DT} s")
    print()
    print("| 60 s phase-ellipse slalom | cold (first run) | warm (best) | rate | vs flat |")
    print("|---|---|---|---|---|")
    base = None
    for name, fn in cases:
        t0 = time.perf_counter()
        try:
            fn()
        except Exception as exc:                       # noqa: BLE001 (reported, not hidden)
            print(f"| {name} | failed: {exc} | | | |")
            continue
        cold = time.perf_counter() - t0
        warm = best(fn, repeat)
        base = warm if base is None else base
        print(f"| {name} | {cold * 1e3:.0f} ms | {warm * 1e3:.0f} ms | {60 / warm:.0f}x real time "
              f"| {warm / base:.1f}x |")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--batch", type=int, default=1000)
    ap.add_argument("--terrain", action="store_true", help="the terrain table")
    args = ap.parse_args()
    if args.terrain:
        terrain(args.repeat)
        return
    fig = preset("skier")
    w, tm = 2 * math.pi / 2.0, math.radians(23)
    heading_table(fig.body)                               # built once per body, not timed
    s0 = np.array([0.0, 0.0, 0.0, 0.0, w * tm])

    def one(state):
        return lambda: run(fig.body, fig.limits, PhaseEllipse(fig.body, w, tm, heading=0.0),
                           state, 60.0, DEFAULT_DT)

    t_scalar = best(one(s0), args.repeat)
    t_open = best(lambda: run(fig.body, fig.limits, OpenLoop(fig.body, w, tm), s0, 60.0,
                              DEFAULT_DT), args.repeat)
    t_one = best(lambda: run(fig.body, fig.limits, PhaseEllipse(fig.body, w, tm), s0, 60.0,
                             DEFAULT_DT), args.repeat)
    n60 = int(math.floor(60.0 / DEFAULT_DT + 1e-9)) + 1
    t_bare = best(lambda: bare_loop(fig, w, tm, n60), args.repeat)
    t_numpy1 = best(one(s0[:, None]), max(1, args.repeat // 2))
    n = args.batch
    rng = np.random.default_rng(0)
    starts = np.tile(s0[:, None], (1, n))
    starts[3] = rng.uniform(-0.1, 0.1, n)
    dur = 4.0
    steps = int(round(dur / DEFAULT_DT)) + 1
    t_batch = best(lambda: run(fig.body, fig.limits, PhaseEllipse(fig.body, w, tm, heading=0.0),
                               starts, dur, DEFAULT_DT), args.repeat)
    k = 50                                                # sequential baseline on 50 figures
    t_seq = best(lambda: [run(fig.body, fig.limits, PhaseEllipse(fig.body, w, tm, heading=0.0),
                              starts[:, j], dur, DEFAULT_DT) for j in range(k)], 1)
    t_floor, t_trig = numpy_floor(n, args.repeat)
    print(f"date: {datetime.date.today()}, machine: {os.cpu_count()} cores, "
          f"Python {platform.python_version()}, numpy {np.__version__}, dt = {DEFAULT_DT} s")
    print()
    print("| case | wall time | rate | goal |")
    print("|---|---|---|---|")
    print(f"| one figure, 60 s phase-ellipse slalom with heading control, on floats | {t_scalar * 1e3:.0f} ms | "
          f"{60 / t_scalar:.0f}x real time | 1000x |")
    print(f"| one figure, 60 s open-loop slalom (Section 4), on floats | {t_open * 1e3:.0f} ms | "
          f"{60 / t_open:.0f}x real time | 1000x |")
    print(f"| one figure, 60 s phase-ellipse slalom on one ellipse (no heading), on floats | "
          f"{t_one * 1e3:.0f} ms | {60 / t_one:.0f}x real time | |")
    print(f"| floor: the same run as a bare float RK4 loop, same arithmetic | "
          f"{t_bare * 1e3:.0f} ms | the core takes {t_one / t_bare:.2f}x | |")
    print(f"| baseline: the phase-ellipse run as a numpy batch of one | {t_numpy1 * 1e3:.0f} ms | "
          f"{60 / t_numpy1:.0f}x real time | |")
    print(f"| batch of {n}, {dur:g} s ({steps} steps) | {t_batch * 1e3:.0f} ms | "
          f"{n * steps / t_batch / 1e6:.2f} M figure-steps/s | 10 M |")
    print(f"| baseline: {k} figures one at a time (on floats) | {t_seq * 1e3:.0f} ms | "
          f"{k * steps / t_seq / 1e6:.3f} M figure-steps/s | |")

    print(f"| floor: the cheapest numpy RK4 step of {n} figures (Eqs. 2, 21; no controller, no "
          f"bounds) | {t_floor * 1e6:.0f} us/step | {n / t_floor / 1e6:.2f} M figure-steps/s | |")
    print(f"| floor: its 16 sines and cosines alone | {t_trig * 1e6:.0f} us/step | "
          f"{n / t_trig / 1e6:.2f} M figure-steps/s | |")


if __name__ == "__main__":
    main()
