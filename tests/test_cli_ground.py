"""``simulate --ground FILE`` through the real command line (docs/TERRAIN.md, "The ground from a
file"): a ``.npy`` height grid with ``--ground-cell`` and ``--ground-origin``, a scene's
``terrain`` table as JSON (or a whole scene), and bad files and values (one line naming the flag,
exit 2, no output)."""
import json
import math

import numpy as np
import pytest

from blender_turning.core import Trajectory, preset
from blender_turning.core.ground.terrain import HeightField
from blender_turning.core.ground.terrain_gen import ski_slope
from cli_helpers import one_line_error, run

SLOPE = ski_slope(length=160.0, width=80.0, cell=2.0)     # x in [-40, 40], y in [-80, 80]
HEIGHTS = SLOPE._h[2:-2, 2:-2]
RUN = ("--start", "0", "60", "--heading-deg", "-90", "--duration", "6")


@pytest.fixture()
def data(tmp_path):
    """``data/slope.npy`` and ``data/slope.json`` (its ``file`` relative to the JSON file)."""
    folder = tmp_path / "data"
    folder.mkdir()
    np.save(folder / "slope.npy", HEIGHTS)
    (folder / "slope.json").write_text(json.dumps({
        "type": "height_field", "file": "slope.npy", "cell": 2.0,
        "origin": [SLOPE.x0, SLOPE.y0]}))
    return tmp_path


def test_a_height_grid_runs_the_same_from_npy_and_from_json(data):
    """The same grid given as .npy flags and as a JSON terrain table (run from another folder:
    the table's file is found next to it) gives the same trajectory, byte for byte; its ``z``
    is the height field under the foot, and the figure speeds up down the slope."""
    npy = run("simulate", "--ground", "data/slope.npy", "--ground-cell", "2", "--ground-origin",
              SLOPE.x0, SLOPE.y0, *RUN, "--out", "npy.csv", cwd=data)
    assert npy.returncode == 0, npy.stderr
    elsewhere = data / "elsewhere"
    elsewhere.mkdir()
    js = run("simulate", "--ground", "../data/slope.json", *RUN, "--out", "json.csv",
             cwd=elsewhere)
    assert js.returncode == 0, js.stderr
    assert (data / "npy.csv").read_bytes() == (elsewhere / "json.csv").read_bytes()
    traj = Trajectory.from_csv(data / "npy.csv")
    field = HeightField(HEIGHTS, SLOPE.x0, SLOPE.y0, 2.0)
    np.testing.assert_allclose(traj.z, field.derivatives(traj.x, traj.y)[0], rtol=0, atol=1e-12)
    assert traj.y[0] == pytest.approx(60.0) and traj.y[-1] < -20.0
    assert traj.V_cm[-1] > traj.V_cm[0] + 5.0
    assert "speed 10.0-" in npy.stdout


def test_a_scene_file_gives_its_terrain_and_flags_override_its_resistance(tmp_path):
    """A whole scene file as --ground is its ``terrain`` table: an 18 deg plane there is the
    same run as ``--slope-deg 18``; ``--friction 0 --drag-area 0`` override the table's (or the
    sport's) resistance: a straight run is then free fall along the slope."""
    scene = tmp_path / "scene.json"
    scene.write_text(json.dumps({"figure": {"preset": "skier"}, "terrain": {
        "type": "plane", "slope_deg": 18, "downhill_deg": -90, "friction": 0.05}}))
    args = ("--controller", "straight", "--heading-deg", "-90", "--duration", "4")
    a = run("simulate", "--ground", scene, *args, "--out", tmp_path / "a.csv")
    b = run("simulate", "--slope-deg", "18", *args, "--out", tmp_path / "b.csv")
    assert a.returncode == 0 and b.returncode == 0, a.stderr + b.stderr
    assert (tmp_path / "a.csv").read_bytes() == (tmp_path / "b.csv").read_bytes()
    free = run("simulate", "--ground", scene, *args, "--friction", "0", "--drag-area", "0",
               "--out", tmp_path / "f.csv")
    assert free.returncode == 0, free.stderr
    traj = Trajectory.from_csv(tmp_path / "f.csv")
    body = preset("skier").body
    np.testing.assert_allclose(traj.V_cm, body.V_cm + body.g * math.sin(math.radians(18))
                               * traj.t, rtol=1e-12)


def _write(folder, name, content):
    path = folder / name
    if isinstance(content, np.ndarray):
        np.save(path, content, allow_pickle=True)
    else:
        path.write_text(content if isinstance(content, str) else json.dumps(content))
    return path.name


GRID = {"type": "height_field", "heights": [[0, 1, 2], [0, 1, 2], [0, 1, 2]], "cell": 2}


@pytest.mark.parametrize("file, args, names", [
    ("g.npy", (), ("--ground-cell",)),                            # no spacing for a grid
    ("g.npy", ("--ground-cell", "-1"), ("--ground-cell", "-1")),
    ("g.npy", ("--ground-cell", "2", "--ground-origin", "nan", "0"), ("--ground-origin X",)),
    ("flat.npy", ("--ground-cell", "1"), ("--ground", "shape (5,)")),
    ("holey.npy", ("--ground-cell", "1"), ("--ground", "nan")),
    ("objects.npy", ("--ground-cell", "1"), ("--ground", "cannot be read")),
    ("missing.npy", ("--ground-cell", "1"), ("--ground", "missing.npy")),
    ("missing.json", (), ("--ground", "missing.json")),
    ("broken.json", (), ("--ground", "not valid JSON")),
    ("list.json", (), ("--ground", "list")),
    ("zero_cell.json", (), ("--ground", "cell = 0")),
    ("typo.json", (), ("--ground", "celll", "cell")),
    ("g.json", ("--ground-cell", "2"), ("--ground-cell", ".npy")),
    ("g.txt", (), ("--ground", ".json", ".npy")),
    ("g.json", ("--slope-deg", "10"), ("--ground", "--slope-deg")),
    ("g.json", ("--start", "9", "0"), ("--start", "off")),
])
def test_bad_ground_files_and_values(tmp_path, file, args, names):
    rng = np.random.default_rng(0)
    contents = {"g.npy": rng.normal(size=(6, 7)), "flat.npy": np.zeros(5),
                "holey.npy": np.array([[0.0, 1.0], [np.nan, 2.0]]),
                "objects.npy": np.array([{"a": 1}, None], dtype=object),
                "broken.json": "{\"type\": ", "list.json": [GRID],
                "zero_cell.json": {**GRID, "cell": 0}, "typo.json": {**GRID, "celll": 2},
                "g.json": GRID, "g.txt": "0 1\n2 3\n"}
    if file in contents:
        _write(tmp_path, file, contents[file])
    out = tmp_path / "o.csv"
    r = run("simulate", "--ground", tmp_path / file, *args, "--duration", "1", "--out", out)
    one_line_error(r, *names)
    assert not out.exists()


def test_the_ground_cell_and_origin_need_a_ground(tmp_path):
    one_line_error(run("simulate", "--ground-cell", "2", "--duration", "1"), "--ground-cell",
                   "--ground")
