"""Shared by the command-line and render-job tests: run a command, snapshot a folder, a folder the
user cannot write."""
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def run(*args, cwd=None, umask=None, timeout=300):
    """``python -m blender_turning *args`` in a fresh interpreter (so stderr is exactly what a
    user sees), with this worktree's package."""
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    pre = (lambda: os.umask(umask)) if umask is not None else None
    return subprocess.run([sys.executable, "-m", "blender_turning", *map(str, args)],
                          capture_output=True, text=True, timeout=timeout, cwd=cwd, env=env,
                          preexec_fn=pre)


def snapshot(folder: Path) -> dict:
    """Every file under ``folder`` (hidden ones too) with its size and modification time."""
    return {p.relative_to(folder).as_posix(): (p.stat().st_size, p.stat().st_mtime_ns)
            for p in sorted(folder.rglob("*"))}


def one_line_error(r, *names, code=2):
    """Exit ``code``, one line on stderr naming each of ``names``, no traceback, no numpy warning,
    no hidden temporary name."""
    lines = r.stderr.strip().splitlines()
    assert r.returncode == code, r.stderr
    assert len(lines) == 1, r.stderr
    for name in names:
        assert name in lines[0], lines[0]
    assert "Traceback" not in r.stderr and "Warning" not in r.stderr and ".tmp-" not in r.stderr
    return lines[0]


def read_only_folder(tmp_path: Path) -> Path:
    """A folder this process cannot write: a 0o555 folder, or /sys for root (who writes
    anywhere else)."""
    if os.geteuid() == 0:
        return Path("/sys")
    ro = tmp_path / "RO"
    ro.mkdir()
    ro.chmod(0o555)
    return ro
