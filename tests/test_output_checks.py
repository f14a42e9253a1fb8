"""Outputs written under a file-size limit (``RLIMIT_FSIZE``: the kernel cuts a write off with
EFBIG, as a quota or a too-small filesystem does): the command exits 1 with one line naming the
flag, the path and "File too large", and leaves neither a partial file nor a hidden one; an
earlier result is kept whole (docs/failures.md).  Also the check every written file passes
(:func:`~blender_turning.core.files.verify_file`) on files cut short."""
import json
import os
import resource
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from blender_turning.core.files import WriteError, verify_file
from cli_helpers import ROOT, one_line_error, snapshot


def run_limited(limit: int, *args):
    """``python -m blender_turning *args`` allowed files of at most ``limit`` bytes (Python
    ignores SIGXFSZ, so a write past it fails with EFBIG instead of killing the process)."""
    def cap():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    env = dict(os.environ, PYTHONPATH=str(ROOT), PYTHONDONTWRITEBYTECODE="1")
    return subprocess.run([sys.executable, "-m", "blender_turning", *map(str, args)],
                          capture_output=True, text=True, timeout=300, env=env, preexec_fn=cap)


def test_a_csv_too_large_for_the_limit_is_exit_1_and_leaves_the_old_one(tmp_path):
    old = tmp_path / "o.csv"
    old.write_text("old run\n")
    before = snapshot(tmp_path)
    # 2 s at dt 0.02: 101 rows of about 300 bytes, 30 KB > 8 KB
    r = run_limited(8192, "simulate", "--duration", "2", "--out", old)
    line = one_line_error(r, "--out", str(old), "File too large", code=1)
    assert "Traceback" not in line
    assert snapshot(tmp_path) == before and old.read_text() == "old run\n"


def test_a_summary_json_too_large_for_the_limit_writes_no_figure(tmp_path):
    """Many short figures: each CSV fits, the crowd's summary.json does not; the crowd writes
    all or nothing."""
    crowd = {"duration": 0.8, "figures": [{"name": "lead", "preset": "skier",
                                           "turns": {"period": 2, "lean_deg": 20}}],
             "formations": [{"type": "follow_leader", "leader": "lead", "count": 60,
                             "gap_s": 0.01, "lateral_m": [-2, 0, 2]}]}
    scene = tmp_path / "crowd.json"
    scene.write_text(json.dumps(crowd))
    out = tmp_path / "out"
    ok = run_limited(1 << 30, "crowd", scene, "--out", tmp_path / "probe")
    assert ok.returncode == 0, ok.stderr
    sizes = {p.name: p.stat().st_size for p in (tmp_path / "probe").iterdir()}
    biggest_csv = max(v for k, v in sizes.items() if k.endswith(".csv"))
    assert biggest_csv < 16384 < sizes["summary.json"], sizes
    r = run_limited(16384, "crowd", scene, "--out", out)
    one_line_error(r, "--out summary.json", "File too large", code=1)
    assert not out.exists()


def written(tmp_path, name, data: bytes) -> Path:
    p = tmp_path / name
    p.write_bytes(data)
    return p


PNG = (ROOT / "docs" / "demo.png").read_bytes()


@pytest.mark.parametrize("name, data, says", [
    ("f.png", b"", "empty"),
    ("f.png", PNG[: len(PNG) // 2], "the PNG is incomplete"),
    ("f.png", b"GIF89a" + PNG[6:], "the PNG is incomplete"),
    ("f.csv", b"t,x\n0,0\n1,", "the CSV ends mid-line"),
    ("f.json", b'{"figures": [1, 2', "does not read back"),
    ("f.blend", b"BLENDER-v404RENDH" + bytes(200), "the .blend is incomplete"),
    ("f.blend", b"\x00" * 300, "no Blender header"),
])
def test_a_file_cut_short_fails_its_check(tmp_path, name, data, says):
    with pytest.raises(WriteError, match=says):
        verify_file(written(tmp_path, name, data))


@pytest.mark.parametrize("name, data", [("f.png", PNG), ("f.csv", b"t,x\n0,0\n"),
                                        ("f.json", b'{"a": 1}'),
                                        ("f.blend", b"BLENDER-v404" + bytes(100) + b"ENDB" +
                                         bytes(20))])
def test_a_whole_file_passes_its_check(tmp_path, name, data):
    verify_file(written(tmp_path, name, data))


@pytest.mark.parametrize("where", ["open", "write"])
def test_a_signal_while_the_lock_is_made_leaves_no_lock(tmp_path, monkeypatch, where):
    """An interrupt (a signal's exception) after the lock file is made but before ``with``
    enters its block: ``__exit__`` never runs, so ``__enter__`` itself removes the lock (a
    crowd stopped then left its new --out folder behind)."""
    from blender_turning.core import files
    real_open, real_dump = os.open, json.dump

    def open_then_stop(*args, **kwargs):
        real_open(*args, **kwargs)
        raise KeyboardInterrupt

    def dump_then_stop(obj, fh):
        real_dump(obj, fh)
        fh.flush()
        raise KeyboardInterrupt

    if where == "open":
        monkeypatch.setattr(files.os, "open", open_then_stop)
    else:
        monkeypatch.setattr(files.json, "dump", dump_then_stop)
    with pytest.raises(KeyboardInterrupt):
        with files.OutputLock(tmp_path):
            pass
    monkeypatch.undo()
    assert not (tmp_path / files.OutputLock.NAME).exists()
    other = tmp_path / files.OutputLock.NAME                # another live job's lock stays
    other.write_text(json.dumps({"pid": 1, "host": "elsewhere"}))
    lock = files.OutputLock(tmp_path)
    lock._drop_if_ours()
    assert other.exists()
