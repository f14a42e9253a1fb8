"""Writing files so that a failure leaves nothing behind: a hidden temporary file in the target's
folder, renamed over the target only once it is complete.  The file gets the mode any other new
file would get (``0o666`` less the umask), not ``mkstemp``'s private ``0o600``.
"""
from __future__ import annotations

import os
import tempfile
from pathlib import Path

__all__ = ["new_file_mode", "temp_beside", "atomic_write_text"]


def new_file_mode() -> int:
    """``0o666 & ~umask``: the mode ``open(path, "w")`` would give a new file."""
    try:
        with open("/proc/self/status") as fh:         # Linux: read without changing it
            for line in fh:
                if line.startswith("Umask:"):
                    return 0o666 & ~int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return 0o666 & ~mask


def temp_beside(path) -> Path:
    """Create an empty hidden file next to ``path`` (same folder, same suffix, so tools that go
    by the suffix still work) with :func:`new_file_mode`, and return its path."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent if str(path.parent) else ".", prefix=".tmp-",
                               suffix=path.suffix)
    try:
        os.fchmod(fd, new_file_mode())
    finally:
        os.close(fd)
    return Path(tmp)


def atomic_write_text(path, text: str) -> None:
    """Write ``text`` to ``path`` completely or not at all (a device or pipe, which a rename
    would replace, is written to directly)."""
    path = Path(path)
    if path.exists() and not path.is_file():
        with open(path, "w", newline="") as fh:
            fh.write(text)
        return
    tmp = temp_beside(path)
    try:
        with open(tmp, "w", newline="") as fh:
            fh.write(text)
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
