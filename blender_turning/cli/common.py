"""Helpers shared by the CLI commands: optional matplotlib, writes that leave no partial file."""
from __future__ import annotations

import os
import tempfile
from pathlib import Path


def require_matplotlib(flag: str) -> None:
    """Fail early, naming the flag, when the optional plotting extra is missing."""
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        raise ValueError(f"{flag} needs matplotlib (pip install 'blender-turning[plots]')") \
            from None


def atomic_plot(path, draw) -> None:
    """Call ``draw(tmp_path)`` and move the file into place only if it succeeded."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".tmp-", suffix=path.suffix or ".png")
    os.close(fd)
    try:
        draw(tmp)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def check_out_path(flag: str, path) -> None:
    """An output path whose folder exists (checked before any work is done)."""
    if path is not None:
        parent = Path(path).resolve().parent
        if not parent.is_dir():
            raise ValueError(f"{flag} = {str(path)!r}: the folder {str(parent)!r} does not exist")
