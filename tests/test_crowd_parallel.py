"""A crowd's result does not depend on the engine: this process, a process pool of 1 or 2
workers, a real Dask LocalCluster of 2 worker processes.  Exact equality."""
import io
import math
import sys

import numpy as np
import pytest

from blender_turning.cli.progress import Progress
from blender_turning.crowd import crowd_from_dict, run_crowd

PATH = {"path": {"points": [[0, 0], [15, 1.5], [30, 0]], "tangents": [[10, 0], [10, 0], [10, 0]]},
        "planner": {"stages": 4, "choices": 3, "stage_time": 0.3, "lean_bound_deg": 35}}
DOC = {"name": "mixed", "seed": 5, "duration": 6, "figures": [
    {"name": "guide", "preset": "skier", "body": {"V_cm": 8.0}, "limits": {"dC_f_max": 0.3},
     "follow": PATH},
    {"name": "lead", "preset": "snowboarder", "turns": {"period": 2.5, "lean_deg": 20}}],
    "formations": [{"type": "follow_leader", "leader": "guide", "count": 2, "gap_m": 5,
                    "lateral_m": [-1, 1], "body_jitter": 0.05},
                   {"type": "follow_leader", "leader": "lead", "count": 3, "gap_s": 1,
                    "body_jitter": 0.05, "period_jitter": 0.05}]}


@pytest.fixture(scope="module")
def serial():
    crowd = crowd_from_dict(DOC)
    res = run_crowd(crowd)
    assert [r.status for r in res.figures] == ["ok"] * 7
    return crowd, res


def _same(a, b):
    assert [r.name for r in a.figures] == [r.name for r in b.figures]
    for x, y in zip(a.figures, b.figures):
        assert x.status == y.status
        np.testing.assert_array_equal(x.trajectory.data, y.trajectory.data)


@pytest.mark.parametrize("workers", [1, 2])
def test_process_pool_gives_the_single_process_result(serial, workers):
    from concurrent.futures import ProcessPoolExecutor
    crowd, res = serial
    if workers == 1:
        with ProcessPoolExecutor(max_workers=1) as pool:
            _same(res, run_crowd(crowd, executor=pool))
    else:
        _same(res, run_crowd(crowd, workers=2))


def _worker_setup():
    import dask
    return (dask.config.get("distributed.worker.profile.enabled"),
            dask.config.get("distributed.admin.tick.interval"),
            "blender_turning.crowd.runner" in sys.modules)


@pytest.mark.slow
def test_dask_local_cluster_gives_the_single_process_result(serial):
    distributed = pytest.importorskip("dask.distributed")
    from blender_turning.crowd.dask_workers import local_cluster
    crowd, res = serial
    with local_cluster(2) as address:
        with distributed.Client(address) as client:
            # The workers run with the crowd's settings and have the runner before any task.
            assert list(client.run(_worker_setup).values()) == [(False, "1s", True)] * 2
            _same(res, run_crowd(crowd, executor=client.get_executor()))
        _same(res, run_crowd(crowd, scheduler=address))
    with pytest.raises(ValueError, match="workers = 0"):
        with local_cluster(0):
            pass


def test_dask_worker_environment_is_the_worker_config():
    dask = pytest.importorskip("dask")
    pytest.importorskip("dask.distributed")
    from blender_turning.crowd.dask_workers import WORKER_CONFIG, WORKER_ENVIRON

    def flat(d, pre=""):
        return {k2: v2 for k, v in d.items() for k2, v2 in
                (flat(v, f"{pre}{k}.").items() if isinstance(v, dict) else [(pre + k, v)])}
    # What Dask reads from the variables (hyphens and underscores are one to it) ...
    read = {k.replace("_", "-"): v for k, v in flat(dask.config.collect_env(WORKER_ENVIRON)).items()}
    wanted = {k: v for k, v in WORKER_CONFIG.items() if not k.endswith(".preload")}
    assert read == wanted
    for key in WORKER_CONFIG:                      # ... and each is a key Dask knows
        dask.config.get(key)


def test_progress_counts_every_figure_once(serial):
    crowd, _ = serial
    seen = []
    run_crowd(crowd, progress=lambda done, total: seen.append((done, total)))
    assert seen[-1] == (7, 7) and all(b > a for (a, _), (b, _) in zip(seen, seen[1:]))


def test_bad_engine_arguments_name_the_parameter(serial):
    crowd, _ = serial
    with pytest.raises(ValueError, match="workers = 0"):
        run_crowd(crowd, workers=0)
    with pytest.raises(ValueError, match="at most one of"):
        run_crowd(crowd, workers=2, scheduler="tcp://127.0.0.1:1")
    assert math.isfinite(run_crowd(crowd).wall_time)


class _Terminal(io.StringIO):
    def isatty(self):
        return True


@pytest.mark.parametrize("tqdm", [True, False])
def test_progress_draws_on_a_terminal_and_stays_quiet_in_a_pipe(tqdm, monkeypatch):
    if not tqdm:                                   # the plain counter when tqdm is missing
        monkeypatch.setitem(sys.modules, "tqdm", None)
    pipe, tty = io.StringIO(), _Terminal()
    for stream in (pipe, tty):
        with Progress(3, "figure", "crowd", stream) as bar:
            bar(1, 3)
            bar(3, 3)
    assert pipe.getvalue() == ""
    assert "3/3" in tty.getvalue() and tty.getvalue().endswith("\n")


def _same_tracks(a, b):
    assert a.keys() == b.keys()
    for name in a:
        x, y = a[name], b[name]
        for attr in ("frames", "location", "rotation"):
            np.testing.assert_array_equal(getattr(x, attr), getattr(y, attr))
        assert x.bones.keys() == y.bones.keys() and x.props.keys() == y.props.keys()
        for bone in x.bones:
            for attr in ("location", "rotation"):
                u, v = getattr(x.bones[bone], attr), getattr(y.bones[bone], attr)
                assert (u is None) == (v is None)
                if u is not None:
                    np.testing.assert_array_equal(u, v)
        for prop in x.props:
            np.testing.assert_array_equal(x.props[prop], y.props[prop])


def test_crowd_poses_are_on_the_crowds_frames_and_the_same_on_two_workers(serial):
    from blender_turning.crowd import map_crowd
    from blender_turning.mapping import map_trajectory
    crowd, res = serial
    here = map_crowd(res, 24.0)
    assert list(here) == [f.name for f in crowd.figures]
    lead1 = crowd["lead-1"]                                  # starts 1 s after the leader
    assert here["lead-1"].frames[0] == 1 + 24 and here["lead"].frames[0] == 1
    traj = res["lead-1"].trajectory
    alone = map_trajectory("snowboarder", traj.resample(24.0, start=lead1.time_offset),
                           frame_start=25)
    _same_tracks({"x": here["lead-1"]}, {"x": alone})
    _same_tracks(here, map_crowd(res, 24.0, workers=2))
