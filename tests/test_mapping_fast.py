"""The mapping's fast paths give the numbers of the slow ones they replace: the arm's aiming
solver (mapping/sports/skier.py ``_Arm``) against the pose builder's IK, and ``stack_dot`` against
numpy's matmul."""
import numpy as np
import pytest

from blender_turning.mapping import bones as B
from blender_turning.mapping.sports.common import ik_limb
from blender_turning.mapping.kinematics import PoseBuilder, Skeleton, quat_from_axis_angle, stack_dot
from blender_turning.mapping.rig_spec import load_rig
from blender_turning.mapping.sports.skier import _Arm


def _builder(n, rng):
    """The skier rig with its spine, shoulders and hands turned at random."""
    b = PoseBuilder(Skeleton.from_spec(load_rig("skier")), n)
    for bone in B.SPINE_CHAIN[:4] + ("shoulder.L", "shoulder.R", "hand.L", "hand.R"):
        b.set_local(bone, rotation=quat_from_axis_angle(rng.normal(size=(n, 3)),
                                                        rng.uniform(-0.5, 0.5, n)))
    return b


@pytest.mark.parametrize("s", ["L", "R"])
def test_arm_solver_puts_grip_and_wrist_where_the_builder_does(s):
    rng = np.random.default_rng(3)
    n = 200
    b = _builder(n, rng)
    upper, lower, pole = B.side("upper_arm", s), B.side("forearm", s), B.side("pole", s)
    elbow = rng.normal(size=(n, 3))
    arm = _Arm(b, upper, lower, elbow, pole)
    # Targets in reach and beyond it (clamped), around the shoulder.
    target = arm.root + rng.uniform(-0.8, 0.8, (n, 3))
    grip, wrist = arm.reach(target)
    idx = np.arange(0, n, 3)                          # a subset of frames, as the aiming loop
    grip_k, wrist_k = arm.reach(target[idx], idx)
    ik_limb(b, upper, lower, target, elbow)
    fore = b.pose(lower)
    want_wrist = fore[:, :3, 3] + b.skel.length(lower) * fore[:, :3, 1]
    want_grip = b.unposed(pole)[:, :3, 3]
    # Measured: 4e-16 m (the builder goes through quaternions).
    assert np.max(np.abs(grip - want_grip)) < 1e-12
    assert np.max(np.abs(wrist - want_wrist)) < 1e-12
    # A subset of frames gives the same numbers to rounding (the products' vector lanes differ).
    assert np.max(np.abs(grip_k - grip[idx])) < 1e-14
    assert np.max(np.abs(wrist_k - wrist[idx])) < 1e-14


def test_two_arms_joined_reach_as_each_alone():
    """The aiming loop solves both arms in one IK over their frames (``_Arm.joined``): each
    frame as its own arm puts it, to rounding."""
    rng = np.random.default_rng(8)
    n = 120
    b = _builder(n, rng)
    arms = [_Arm(b, B.side("upper_arm", s), B.side("forearm", s), rng.normal(size=(n, 3)),
                 B.side("pole", s)) for s in "LR"]
    targets = [a.root + rng.uniform(-0.8, 0.8, (n, 3)) for a in arms]
    both = _Arm.joined(arms)
    idx = np.concatenate([np.arange(0, n, 2), n + np.arange(1, n, 3)])   # frames of both arms
    grip, wrist = both.reach(np.concatenate(targets)[idx], idx)
    want_grip = np.concatenate([a.reach(t)[0] for a, t in zip(arms, targets)])[idx]
    want_wrist = np.concatenate([a.reach(t)[1] for a, t in zip(arms, targets)])[idx]
    assert np.max(np.abs(grip - want_grip)) < 1e-14          # measured: 2.2e-16
    assert np.max(np.abs(wrist - want_wrist)) < 1e-14


def test_arms_aimed_together_as_each_alone():
    """``_aim`` runs both arms' passes together, but each arm stops on its own (within 2e-4 m
    of its targets, or settled): the wrists and grips of each are those it gets aimed alone."""
    from blender_turning.mapping.sports.skier import _aim, _Plants
    rng = np.random.default_rng(9)
    n = 60
    b = _builder(n, rng)
    arms = [_Arm(b, B.side("upper_arm", s), B.side("forearm", s), rng.normal(size=(n, 3)),
                 B.side("pole", s)) for s in "LR"]
    # Left: 0.1 mm off grips the arm reaches (within 2e-4 m after one pass, not settled: done
    # there, where a further pass would move it); right: many out of reach (all 12 passes).
    grip, wrist = arms[0].reach(arms[0].root + rng.uniform(-0.3, 0.3, (n, 3)))
    frees = [grip + rng.uniform(-1e-4, 1e-4, (n, 3)),
             arms[1].root + rng.uniform(-1.5, 1.5, (n, 3))]
    offsets = [grip - wrist, np.subtract(*arms[1].reach(frees[1]))]
    no = np.zeros(n, bool)
    plans = [_Plants(no, no, np.ones(n), f.copy(), f.copy(), np.full((n, 3), np.nan), no, no)
             for f in frees]
    together = _aim(arms, plans, frees, offsets, (1.2, 1.2))
    for k in range(2):
        alone = _aim([arms[k]], [plans[k]], [frees[k]], [offsets[k]], [1.2])[0]
        for got, want in zip(together[k], alone):
            assert np.max(np.abs(got - want)) < 1e-14               # measured: 0


def test_stack_dot_is_matmul():
    rng = np.random.default_rng(4)
    a = rng.normal(size=(7, 5, 4, 3))
    k = rng.normal(size=(3, 2))
    v = rng.normal(size=3)
    assert np.allclose(stack_dot(a, k), a @ k, rtol=0, atol=1e-14)
    assert np.allclose(stack_dot(a, v), a @ v, rtol=0, atol=1e-14)
    assert stack_dot(a, k).shape == (7, 5, 4, 2) and stack_dot(a, v).shape == (7, 5, 4)


def test_settled_arms_leaving_the_aiming_loop_change_nothing(monkeypatch):
    """The skier's poses with settled frames leaving the loop equal those of every frame going
    round every pass (SETTLED below zero: none leaves), to rounding; and most frames do leave."""
    import math

    from blender_turning.core import PhaseEllipse, preset, simulate
    from blender_turning.mapping import map_trajectory
    from blender_turning.mapping.sports import skier

    fig = preset("skier")
    traj = simulate(fig, PhaseEllipse(fig.body, omega0=math.pi, theta_max=math.radians(23),
                                      heading=0.0), duration=8.0).resample(24)
    passes = []
    reach = skier._Arm.reach

    def counted(self, wrist, idx=slice(None)):
        passes.append(len(wrist))
        return reach(self, wrist, idx)

    monkeypatch.setattr(skier._Arm, "reach", counted)
    fast = map_trajectory("skier", traj)
    fast_work = sum(passes)
    passes.clear()
    monkeypatch.setattr(skier, "SETTLED", -1.0)
    slow = map_trajectory("skier", traj)
    assert fast_work < 0.6 * sum(passes)             # measured: 0.45 of the frame-passes
    for name, ch in slow.bones.items():
        for a, b in ((ch.rotation, fast.bones[name].rotation),
                     (ch.location, fast.bones[name].location)):
            if a is not None:
                assert np.max(np.abs(a - b)) < 1e-12, name      # measured 4e-15


def test_norm_and_dot_are_numpys_numbers():
    """kinematics.norm and dot give np.linalg.norm's and np.sum's numbers bit for bit (the
    poses of every sport are unchanged by them)."""
    from blender_turning.mapping.kinematics import dot, norm
    rng = np.random.default_rng(5)
    for shape in ((73, 3), (7, 5, 4), (3,)):
        a, b = rng.normal(size=shape), rng.normal(size=shape)
        assert np.array_equal(norm(a), np.linalg.norm(a, axis=-1))
        assert np.array_equal(norm(a, keepdims=True), np.linalg.norm(a, axis=-1, keepdims=True))
        assert np.array_equal(dot(a, b), np.sum(a * b, axis=-1))
        assert np.array_equal(dot(a, b, keepdims=True), np.sum(a * b, axis=-1, keepdims=True))


def test_a_long_stack_gives_the_one_products_numbers():
    """Past OpenBLAS's one-thread size stack_dot goes in pieces: the same numbers as one 2-D
    product (each row is its own sum)."""
    rng = np.random.default_rng(6)
    a = rng.normal(size=(20000, 4, 4))
    k, v = rng.normal(size=(4, 4)), rng.normal(size=4)
    assert np.array_equal(stack_dot(a, k), (a.reshape(-1, 4) @ k).reshape(a.shape))
    assert np.array_equal(stack_dot(a, v), (a.reshape(-1, 4) @ v).reshape(20000, 4))
    assert np.array_equal(stack_dot(a[:, :3, :3], v[:3]),
                          (a[:, :3, :3].reshape(-1, 3) @ v[:3]).reshape(20000, 3))


def _other_threads_ticks():
    import os
    me, ticks = str(os.getpid()), 0
    for t in os.listdir("/proc/self/task"):
        if t != me:
            with open(f"/proc/self/task/{t}/stat") as fh:
                fields = fh.read().rsplit(")", 1)[1].split()
            ticks += int(fields[11]) + int(fields[12])        # utime + stime, clock ticks
    return ticks


def test_a_long_stack_leaves_openblas_threads_asleep():
    """stack_dot on a long run's poses keeps OpenBLAS on the calling thread: its other threads
    use no CPU (one 2-D product of the whole stack wakes them: 16-23 ticks a second measured;
    awake they spin, a second core busy for nothing).  Linux only; skipped where numpy's
    OpenBLAS runs one thread."""
    import os
    import time
    if not os.path.isdir("/proc/self/task") or len(os.listdir("/proc/self/task")) < 2:
        pytest.skip("no other thread to watch")
    rng = np.random.default_rng(7)
    a = rng.normal(size=(20000, 4, 4))
    k, v = rng.normal(size=(4, 4)), rng.normal(size=4)
    time.sleep(0.5)                              # any thread woken before this test sleeps
    before = _other_threads_ticks()
    for _ in range(100):
        stack_dot(a, k)
        stack_dot(a, v)
    time.sleep(0.2)
    assert _other_threads_ticks() - before == 0


def test_a_rigs_skeleton_is_built_once():
    """Skeleton.from_spec keeps one skeleton per rig (read-only rest matrices, shared)."""
    spec = load_rig("skier")
    skel = Skeleton.from_spec(spec)
    assert Skeleton.from_spec(load_rig("skier")) is skel
    assert Skeleton.from_spec(load_rig("telemark")) is not skel
    with pytest.raises(ValueError):
        skel.rest[0, 0, 0] = 2.0
