"""Frame output: every row of a trajectory at a frame rate is a state of the
model.  The state comes from RK4's dense output (cubic Hermite with the model's derivatives at
both ends of a step), ``C_f`` from the chord between samples, and every other column from the
row's own state and control (``Trajectory.resample`` explains the choices)."""
import math

import numpy as np
import pytest

from blender_turning.cli import main
from blender_turning.core import OpenLoop, PhaseEllipse, Trajectory, preset, simulate, slalom_start
from blender_turning.core.physics.dynamics import foot_speed, forward_alpha, leg_force
from blender_turning.core.controllers.phase import phase

FIG = preset("skier")
BODY = FIG.body
W, TM = math.pi, math.radians(23)          # the 2 s / 23 deg turn
FPS = (24, 30, 60, 120)
DT, REF_DT = 0.02, 1 / 1200                # every frame of FPS and every step of DT is on REF_DT's grid
ROUND_OFF = 1e-13                          # relative to a column's scale (~500 ulp; measured 2e-15)


def wrapped(a):
    return np.abs(np.angle(np.exp(1j * np.asarray(a))))


def assert_rows_obey_the_model(r: Trajectory, body=BODY):
    """Eq. (2), Eq. (21) and Appendix A hold in every row to round-off, and the phase lies in
    the quadrant of the row's own ``(theta_v, omega_v)``."""
    th, om, cf = r.theta_v, r.omega_v, r.C_f
    for name, want in (("alpha_v", forward_alpha(body, th, cf)),
                       ("V_f", foot_speed(body, th, cf)),
                       ("F_leg", leg_force(body, th, om, r.alpha_v, cf)[0])):
        got = getattr(r, name)
        assert np.abs(got - want).max() <= ROUND_OFF * np.abs(want).max(), name
    assert_phase_quadrants(r)


def assert_phase_quadrants(r: Trajectory):
    """Section 4: phase 0..90 deg has theta_v > 0, omega_v > 0, and so on; rows on an axis say
    nothing."""
    th, om = r.theta_v, r.omega_v
    q = np.floor(r.phi / (math.pi / 2)).astype(int)
    off_axis = (np.abs(th) > 1e-9) & (np.abs(om) > 1e-9)
    want_q = np.where(th > 0, np.where(om > 0, 0, 1), np.where(om < 0, 2, 3))
    assert np.array_equal(q[off_axis], want_q[off_axis])


@pytest.fixture(scope="module")
def open_loop_runs():
    """The open-loop turn (smooth: no bound is reached) at the default step and at a 1200 Hz
    reference."""
    s0 = (0.0, 0.0, 0.0, 0.0, W * TM)
    return tuple(simulate(FIG, OpenLoop(BODY, W, TM), 8.0, dt=dt, state0=s0)
                 for dt in (DT, REF_DT))


@pytest.mark.parametrize("fps", FPS)
def test_open_loop_rows_are_states_of_the_model(open_loop_runs, fps):
    r = open_loop_runs[0].resample(fps)
    assert len(r) == 8 * fps + 1
    assert_rows_obey_the_model(r)
    # The open-loop ellipse is fixed, so every row's phase is Section 4's of its own state.
    assert wrapped(r.phi - phase(r.theta_v, r.omega_v, TM, W)).max() < 1e-12


def _d4(y, h):
    for _ in range(4):
        y = np.gradient(y, h)
    return np.abs(y[8:-8]).max()


@pytest.mark.parametrize("fps", FPS)
def test_dense_output_matches_a_fine_reference(open_loop_runs, fps):
    """The state at a frame errs by no more than the samples it is built from plus the Hermite
    remainder: ``|H[data] - y| <= E_y + (h / 4) E_y' + h^4 max|y''''| / 384`` (the value weights
    of the cubic Hermite basis sum to 1, the slope weights to at most ``h / 4``).  ``C_f``, the
    chord, errs by at most ``E + h^2 max|C_f''| / 8``.  Linear interpolation of the state (the
    old output) misses by ``h^2 max|y''| / 8``, ~2e-4 rad of lean here: 3000x the bound."""
    coarse, ref = open_loop_runs
    r = coarse.resample(fps)
    k = np.round(r.t / REF_DT).astype(int)
    at = np.round(coarse.t / REF_DT).astype(int)
    slope = {"x": ref.V_f * np.cos(ref.theta_dir), "y": ref.V_f * np.sin(ref.theta_dir),
             "theta_dir": ref.V_f * ref.C_f, "theta_v": ref.omega_v, "omega_v": ref.alpha_v}
    coarse_slope = {"x": coarse.V_f * np.cos(coarse.theta_dir),
                    "y": coarse.V_f * np.sin(coarse.theta_dir),
                    "theta_dir": coarse.V_f * coarse.C_f, "theta_v": coarse.omega_v,
                    "omega_v": coarse.alpha_v}
    for col, dy in slope.items():
        y = getattr(ref, col)
        e_val = np.abs(getattr(coarse, col) - y[at]).max()
        e_slope = np.abs(coarse_slope[col] - dy[at]).max()
        bound = e_val + DT / 4 * e_slope + DT ** 4 / 384 * _d4(y, REF_DT)
        assert np.abs(getattr(r, col) - y[k]).max() <= bound, col
    e_cf = np.abs(coarse.C_f - ref.C_f[at]).max()
    c2 = np.abs(np.gradient(np.gradient(ref.C_f, REF_DT), REF_DT)[4:-4]).max()
    assert np.abs(r.C_f - ref.C_f[k]).max() <= e_cf + DT ** 2 / 8 * c2


class _Recording(PhaseEllipse):
    """The phase-ellipse controller, logging the ellipse frequency of every step."""

    def __init__(self, *a, **kw):
        super().__init__(*a, **kw)
        self.omega0_log = []

    def begin_step(self, t, state):
        super().begin_step(t, state)
        self.omega0_log.append(self.target(t)[0])


@pytest.mark.parametrize("fps", FPS)
def test_phase_under_heading_control_uses_the_step_s_ellipse(fps):
    """With heading control the ellipse (omega0 / beta) changes from half-turn to half-turn at a
    step's start; a frame's phase is Section 4's on the ellipse of the step it falls in."""
    ctl = _Recording(BODY, W, TM, heading=math.radians(10.0))
    traj = simulate(FIG, ctl, 12.0, dt=DT, state0=slalom_start(BODY, W, TM))
    log = np.array(ctl.omega0_log)
    assert np.ptp(log) > 0.05 * W                          # the ellipse did change
    r = traj.resample(fps)
    assert_rows_obey_the_model(r)
    step = np.minimum(np.floor(r.t / DT + 1e-9).astype(int), len(log) - 1)
    # A frame on a sample that sits on the omega_v axis (a crossing, where the controller switches
    # ellipse inside the step) may take either ellipse: their phases differ there by at most
    # |theta_v| |d omega0| / |omega_v| (measured 7.6e-8 rad at theta_v = 4.9e-8 rad).
    axis = np.abs(r.theta_v) * np.ptp(log) / np.abs(r.omega_v)
    assert np.all(wrapped(r.phi - phase(r.theta_v, r.omega_v, TM, log[step])) < 1e-12 + axis)


@pytest.mark.parametrize("fps", FPS)
def test_cli_frame_output_obeys_the_model(tmp_path, fps):
    """``simulate --fps`` (phase-ellipse with heading control, the CLI default) writes rows that
    are states of the model, phases in the right quadrant."""
    out = tmp_path / "f.csv"
    assert main(["simulate", "--duration", "8", "--fps", str(fps), "--out", str(out)]) == 0
    r = Trajectory.from_csv(out)
    assert len(r) == 8 * fps + 1
    assert_rows_obey_the_model(r)


def test_frames_on_samples_are_the_samples(open_loop_runs):
    traj = open_loop_runs[0]
    r = traj.resample(25)                 # every other 0.02 s sample, to round-off in the time
    for name in ("x", "theta_v", "omega_v", "C_f", "phi", "s"):
        np.testing.assert_allclose(getattr(r, name), getattr(traj, name)[::2], rtol=0,
                                   atol=1e-14 * max(1.0, np.abs(getattr(traj, name)).max()))
    for name in ("alpha_v", "V_f", "F_leg"):                # recomputed: round-off
        want = getattr(traj, name)[::2]
        np.testing.assert_allclose(getattr(r, name), want, rtol=0,
                                   atol=ROUND_OFF * np.abs(want).max())


def test_resample_needs_a_body_and_increasing_times(open_loop_runs):
    traj = open_loop_runs[0]
    bare = Trajectory(traj.data)                          # as read from a CSV: no meta
    with pytest.raises(ValueError, match="body"):
        bare.resample(24)
    assert np.array_equal(bare.resample(24, body=BODY).data, traj.resample(24).data)
    back = Trajectory(traj.data[:, ::-1], traj.meta)
    with pytest.raises(ValueError, match="increasing"):
        back.resample(24)
    one = Trajectory(traj.data[:, :1], traj.meta).resample(24)
    assert len(one) == 1 and np.array_equal(one.data[:, 0], traj.data[:, 0])


def test_a_planned_run_with_varying_speed_resamples_to_states_of_the_model():
    """The path follower's trajectory (Section 6, phase from Section 6.2's estimate) records its
    body too; with a speed that varies along the path, each row's ``V_cm`` is the one Eq. (21)
    gives its own ``V_f``, and Eq. (2) and Appendix A hold with it."""
    from blender_turning.core.course.scene import scene_from_dict
    scene = scene_from_dict({
        "name": "corridor", "figure": {"preset": "cyclist", "limits": {"dC_f_max": 0.4}},
        "path": {"polyline": [[0, 0], [40, 0]]}, "clearance": 0.3,
        "obstacles": [{"type": "segment", "from": [-5, -3], "to": [80, -3]},
                      {"type": "segment", "from": [-5, 3], "to": [80, 3]}],
        "speed": {"by": "distance", "at": [0, 20, 40], "V_cm": [6, 4, 7]},
        "planner": {"stages": 6, "choices": 3}})
    body = scene.figure.body
    traj = scene.run().trajectory
    r = traj.resample(24)
    th, om, cf = r.theta_v, r.omega_v, r.C_f
    V = r.V_f * (1.0 - cf * body.l * np.sin(th))
    # The profile's speed at the row's distance (to the planner's 0.05 m/s, see
    # test_planner_scenes), which between samples is the chord of the samples' V_cm.
    np.testing.assert_allclose(V, np.interp(r.s, [0, 20, 40], [6, 4, 7]), atol=0.05)
    V_samples = traj.V_f * (1.0 - traj.C_f * body.l * np.sin(traj.theta_v))
    np.testing.assert_allclose(V, np.interp(r.t, traj.t, V_samples), rtol=1e-14)
    for name, want in (("alpha_v", forward_alpha(body, th, cf, V_cm=V)),
                       ("F_leg", leg_force(body, th, om, r.alpha_v, cf, V)[0])):
        assert np.abs(getattr(r, name) - want).max() <= ROUND_OFF * np.abs(want).max(), name
    assert_phase_quadrants(r)
