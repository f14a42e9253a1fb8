"""A preview run on terrain (``simulate(..., stride=3)`` or 5, Live Preview's drag step on a
Ground mesh, core/physics/terrain_sim.py): one RK4 step of up to ``stride`` dt where nothing
discrete happens, steps of dt on the bake's own grid about the lean's zero crossings (where
directional control plans its half-turns), where the controller takes a new feasibility table
and where a coarse step would move more than 1.25 cells.  The case: the cyclist of
``scripts/bench_live.py`` on the rolls of ``ski_slope`` (no slope), 3 m/s, 3 s turns, 4 deg,
30 s."""
import math

import numpy as np
import pytest
from dataclasses import replace

from blender_turning.core import PhaseEllipse, preset, simulate
from blender_turning.core.controllers import ellipse
from blender_turning.core.ground.terrain_gen import ski_slope
from blender_turning.core.physics.model import RESISTANCE
from blender_turning.core.physics.terrain_sim import preview_stride

ROLLS = ski_slope(length=200.0, width=200.0, slope_deg=0.0, cell=1.0)
CYCLIST = preset("cyclist")
W, TM, V = 2 * math.pi / 3.0, math.radians(4.0), 3.0
START = (-95.0, 10.0, 0.0, 0.0, W * TM, V)


def _run(stride=1, dt=0.02, limits=None, duration=30.0, keep=0.0):
    fig = replace(CYCLIST, body=replace(CYCLIST.body, V_cm=V),
                  limits=limits or CYCLIST.limits)
    return simulate(fig, PhaseEllipse(fig.body, W, TM, heading=0.0), duration, dt,
                    state0=START, ground=ROLLS, resistance=RESISTANCE["cyclist"], stride=stride,
                    keep=keep)


def _off(a, b):
    """The largest distance of the foot (m) and difference of heading (deg) of ``a`` from
    ``b`` at ``a``'s rows."""
    x, y = np.interp(a.t, b.t, b.x), np.interp(a.t, b.t, b.y)
    heading = np.interp(a.t, b.t, b.theta_dir)
    return (np.hypot(a.x - x, a.y - y).max(),
            math.degrees(np.abs(a.theta_dir - heading).max()))


def _given_ground(monkeypatch, **run):
    """``[(x, y, the ground given)]`` of every stage of ``_run(**run)`` given the ground
    (the others read it themselves at their foot)."""
    from blender_turning.core.physics import terrain_one_figure
    given, init = [], terrain_one_figure.TerrainStage.__init__

    def recording(self, *a, **k):
        init(self, *a, **k)
        stage = self.stage

        def read(t, x, y, d, th, om, V, anchor, tau, dv=None):
            if dv is not None:
                given.append((x, y, dv))
            return stage(t, x, y, d, th, om, V, anchor, tau, dv)
        self.stage = read

    monkeypatch.setattr(terrain_one_figure.TerrainStage, "__init__", recording)
    _run(**run)
    return given


def _with_events(monkeypatch, stride):
    """The run, and where its controller planned a half-turn (Section 5.2) and took a new
    feasibility table: ``[(t, "plan")]``, ``[(t, the table's speed, the lean it lets the turn
    have)]``, recorded at the steps' starts."""
    log, table = [], [None]
    plan, begin = ellipse.PhaseEllipse._plan, ellipse.PhaseEllipse.begin_step

    def planned(self, t, *a):
        log.append((t, "plan"))
        return plan(self, t, *a)

    def began(self, t, state):
        if table[0] != self._table_speed:
            table[0] = self._table_speed
            log.append((t, table[0], self.feasible_lean(W, TM)))
        return begin(self, t, state)

    with monkeypatch.context() as m:
        m.setattr(ellipse.PhaseEllipse, "_plan", planned)
        m.setattr(ellipse.PhaseEllipse, "begin_step", began)
        return _run(stride), log


def test_a_preview_plans_and_switches_tables_at_the_bakes_steps(monkeypatch):
    calls, slopes = [], ROLLS.slopes_one
    monkeypatch.setattr(ROLLS, "slopes_one", lambda x, y: calls.append(x) or slopes(x, y))
    exact, bake_events = _with_events(monkeypatch, 1)
    n_exact = len(calls)
    preview, events = _with_events(monkeypatch, 3)
    # The work (a count, the same on every run): the ground read 1,199 times for the bake's
    # 6,001 (1,283 trying coarse steps up to the crossings; 1,481 reading it at each stage of
    # the fine steps, 1,935 reading it again at a coarse step's end, 2,393 also at both
    # midpoints, 2,525 when every new table was also stepped finely).
    assert len(calls) - n_exact < 0.205 * n_exact
    # A sample at each step's start: steps of 3 dt and of dt.
    assert set(np.round(np.diff(preview.t) / 0.02)) == {1.0, 3.0}
    assert preview.t[-1] == pytest.approx(30.0)
    assert preview.meta["dt"] == 0.02 and preview.meta["stride"] == 3
    assert sum(len(e) == 2 for e in bake_events) == 22               # each half-turn
    assert sum(len(e) == 3 for e in bake_events) == 19               # the speed's tables
    assert [e[1] for e in events] == [e[1] for e in bake_events]
    late = np.abs([a[0] - b[0] for a, b in zip(events, bake_events)])
    # A plan, and a table that changes the lean the turn has (4 deg below 2 m/s: 3.87), at the
    # bake's step or the next one (two of them: the states differ by a few mm there); a table
    # that leaves the turn its lean changes nothing the law does, and may come a coarse step
    # later (10 of its 14 do).
    lean, acts = TM, []
    for e in bake_events:
        acts.append(len(e) == 2 or e[2] != lean)
        lean = e[2] if len(e) == 3 else lean
    acts = np.array(acts)
    assert np.sum(acts) == 22 + 5
    assert late[acts].max() < 0.021 and np.sum(late[acts] > 1e-9) <= 3
    assert late.max() < 0.041 and np.sum(late[~acts] > 1e-9) >= 8
    # The foot within 3 cm and the heading within 0.2 deg of the bake's over 30 s (measured
    # 1.2 cm, 0.02 deg; the bench's cyclist at 3.4-4 deg: at most 4.3 cm, 0.13 deg): with coarse
    # steps everywhere a run is 20 cm off.
    foot, heading = _off(preview, exact)
    assert foot < 0.03 and heading < 0.2
    assert _off(_run(dt=0.06), exact)[0] > 0.1


def test_a_coarse_steps_third_stage_carries_the_seconds_ground(monkeypatch):
    """A coarse step reads the ground once for RK4's two midpoint stages: the third stage's
    slopes are the second's carried to its foot (about a millimetre away) by the curvatures,
    within 1e-6 of the ground's there (measured 1.1e-7; 2.4e-5 held, not carried), and its
    curvatures the second's, within 2e-4 1/m of the ground's (9.6e-5, of up to 0.023); and the
    step's end takes the fourth stage's ground carried the same way (a few millimetres), within
    the same bounds (the next step's first stage, and the lean the controller sees there)."""
    given = _given_ground(monkeypatch, stride=3)
    exact = np.array([ROLLS.slopes_one(x, y) for x, y, _ in given])
    off = np.abs(np.array([dv for _, _, dv in given]) - exact)
    assert len(given) > 1900           # the first stages, the coarse steps' 2-4
    assert off[:, :2].max() < 1e-6 and off[:, 2:].max() < 2e-4


def test_a_run_finds_each_speeds_table_once(monkeypatch):
    """On terrain the speed crosses the feasibility tables' grid lines back and forth, and a
    preview's coarse steps ask at each one whether the table changes the law
    (:meth:`.PhaseEllipse.changes_between`): a run looks each table up once (13 look-ups for
    the 6 speeds this run passes, the table and its lean at the period; 52 when it looked
    them up at every crossing), and finds the tables at the bake's steps (above)."""
    looked = []
    find = ellipse.feasible_turns
    monkeypatch.setattr(ellipse, "feasible_turns", lambda b, lim: looked.append(b) or find(b, lim))
    preview = _run(stride=3)
    speeds = set(np.floor(preview.V_cm / ellipse.SPEED_GRID) * ellipse.SPEED_GRID)
    assert len(speeds) == 6 and len(looked) <= 2 * len(speeds) + 1


def test_the_bake_reads_the_ground_at_every_stage(monkeypatch):
    """The bake (``stride = 1``, the release of a drag) shares no read: every stage given the
    ground is given the ground's own numbers at its foot, bit for bit, so the release is the
    run the bake always made (``tests/test_terrain_fast.py`` holds that run to the array
    loop); a preview that carries them (the coarse steps' midpoints and ends) is checked above.
    """
    given = _given_ground(monkeypatch, duration=10.0)
    assert len(given) == 501                         # each step's first stage, read there
    assert all(tuple(dv) == ROLLS.slopes_one(x, y) for x, y, dv in given)


def test_a_step_bounds_the_rate_of_c_f_over_the_time_since_the_last():
    """Section 3's bound on the rate of ``C_f`` (0.3 1/(m s) here: it holds ``C_f`` over the
    first half second and at times after) relative to the last step's first stage: a coarse
    step after a step of dt allows dt's change, not three: the foot within 3 mm of the bake's
    over 20 s (measured 1.2 mm; 2.8 cm with a coarse step's own length)."""
    limits = replace(CYCLIST.limits, dC_f_max=0.3)
    exact = _run(limits=limits, duration=20.0)
    assert np.mean(np.abs(np.diff(exact.C_f)) > 0.999 * 0.3 * 0.02) > 0.03
    assert _off(_run(stride=3, limits=limits, duration=20.0), exact)[0] < 3e-3


@pytest.mark.parametrize("speed, coarse", [(8.0, False), (4.0, True)])
def test_a_coarse_step_moves_at_most_a_cell_and_a_quarter(speed, coarse):
    """On a field of 0.25 m cells (a Ground mesh of 1 m faces as Blender reads it) a coarse
    step of 0.06 s is taken below 5.2 m/s only: at 8 m/s the preview's states are the bake's,
    row for row (stepped coarsely, a snowboarder at 12 m/s on such ground ended 12 m away 20 s in)."""
    fine = ski_slope(length=60.0, width=60.0, slope_deg=0.0, cell=0.25)
    fig = replace(CYCLIST, body=replace(CYCLIST.body, V_cm=speed))

    def run(stride):
        return simulate(fig, PhaseEllipse(fig.body, W, TM, heading=0.0), 3.0, 0.02,
                        state0=(-25.0, 0.0, 0.0, 0.0, W * TM, speed), ground=fine,
                        resistance=RESISTANCE["cyclist"], stride=stride)

    exact, preview, longer = run(1), run(3), run(5)
    assert (exact.V_cm.min() > 5.2) == (not coarse)
    for run_ in (preview, longer):
        same = [np.array_equal(getattr(run_, k), getattr(exact, k))
                for k in ("t", "x", "y", "theta_dir", "theta_v", "omega_v", "V_cm", "C_f")]
        assert all(same) == (not coarse) and any(same) == (not coarse)
    # Up to 5 dt a step, as far as 1.25 cells at the step's start: 3-4 dt about 4 m/s.
    steps = np.round(np.diff(longer.t) / 0.02)
    assert (steps.max() > 1) == coarse and steps.max() <= 4
    assert np.all(longer.V_cm[:-1][steps > 1] * steps[steps > 1] * 0.02 <= 1.25 * 0.25)


@pytest.mark.parametrize("stride, keep", [(3, 7.3), (3, 7.26), (1, 4.01), (3, 0.0)])
def test_a_window_s_run_keeps_the_samples_from_the_last_at_or_before_its_first_frame(stride,
                                                                                    keep):
    """A drag step's window (``keep``, the first frame's time) keeps the whole run's samples from
    the last one at or before it, bit for bit (``s`` from the run's start), and so the frames
    resampled from there: what the window maps is the whole run's."""
    whole, part = _run(stride, duration=10.0), _run(stride, duration=10.0, keep=keep)
    k = len(whole.t) - len(part.t)
    assert part.t[0] <= keep and (keep == 0.0 or part.t[0] > keep - stride * 0.02)
    assert np.array_equal(part.data, whole.data[:, k:]) and (part.s[0] > 0) == (part.t[0] > 0)
    first = math.ceil(keep * 24)
    np.testing.assert_array_equal(part.resample(24, start=0.0, ground=ROLLS, first=first).data,
                                  whole.resample(24, start=0.0, ground=ROLLS, first=first).data)


def test_a_longer_stride_steps_up_to_it_and_resumes_on_the_grid_after_steps_of_dt(monkeypatch):
    """``stride=5`` (Live Preview's for 3 s turns): steps of up to 5 dt, and after steps of dt
    (about the zero crossings) the next coarse step from a step that 3 divides, as ``stride=3``
    steps there (resuming at once left a snowboarder on a 12 deg slope 2.6 m from the bake 30 s
    in, 0.8 m on the grid).  The foot within 3 cm and the heading within 0.2 deg of the bake's
    over 30 s (measured 1.1 cm, 0.04 deg; 8 cm at 6 dt a step, 17 cm resuming on 6 dt's grid),
    and the plans at the bake's steps."""
    exact, bake_events = _with_events(monkeypatch, 1)
    longer, events = _with_events(monkeypatch, 5)
    i = np.round(longer.t / 0.02).astype(int)
    k = np.diff(i)
    assert set(k) == {1, 5}                 # 1 m cells: 5 dt at 3 m/s is 0.3 cells
    after_fine = np.flatnonzero((k[1:] > 1) & (k[:-1] == 1)) + 1      # coarse after dt
    assert len(after_fine) > 20 and np.all(i[after_fine] % 3 == 0)
    plans = [e[0] for e in events if len(e) == 2]
    assert plans == [e[0] for e in bake_events if len(e) == 2]
    foot, heading = _off(longer, exact)
    assert foot < 0.03 and heading < 0.2


def test_live_previews_stride_keeps_30_steps_a_turn_and_the_grid():
    """5 dt a step for 3 s turns (Live Preview's cyclist), 3 (the grid) for 2 s and less, 6 at
    most; a longest step of 1 is the bake's."""
    assert [preview_stride(p, 0.02) for p in (1.0, 2.0, 2.4, 3.0, 3.6, 10.0)] == \
        [3, 3, 4, 5, 6, 6]
    assert preview_stride(3.0, 0.02, longest=1) == 1 and preview_stride(3.0, 0.01) == 6


def test_stride_is_checked():
    with pytest.raises(ValueError, match=r"stride = 0 is not 1 or a whole number of steps in "
                       r"\[3, 10\]"):
        _run(stride=0)
    with pytest.raises(ValueError, match=r"stride = 2 is not 1"):
        _run(stride=2)
    with pytest.raises(ValueError, match="stride > 1 steps the carved model only"):
        simulate(CYCLIST, PhaseEllipse(CYCLIST.body, W, TM, heading=0.0), 5.0, 0.02,
                 state0=START, ground=ROLLS, target_speed=3.0, stride=3)
    with pytest.raises(ValueError, match="the paper's model"):
        simulate(CYCLIST, PhaseEllipse(CYCLIST.body, W, TM), 5.0, 0.02, stride=3)
