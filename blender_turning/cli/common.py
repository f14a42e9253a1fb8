"""Helpers shared by the CLI commands: optional matplotlib, and the outputs of a command, checked
before any work starts and written all together or not at all."""
from __future__ import annotations

import os
from pathlib import Path

from ..core.files import temp_beside
from ..core.ranges import MAX_SAMPLES, MAX_STEPS
from ..core.validate import FieldError


def require_matplotlib(flag: str) -> None:
    """Fail early, naming the flag, when the optional plotting extra is missing."""
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        raise FieldError(f"{flag} needs matplotlib (pip install 'blender-turning[plots]')") \
            from None


def check_steps(duration: float, dt: float, fps: float | None = None) -> None:
    """Refuse a run that would not fit in reasonable time and memory (``MAX_STEPS``)."""
    steps = duration / dt
    if steps < 1:
        raise FieldError(f"--duration = {duration:g} s is shorter than one step (--dt {dt:g} s)")
    if steps > MAX_STEPS:
        raise FieldError(f"--duration {duration:g} s / --dt {dt:g} s = {steps:.3g} steps; at "
                         f"most {MAX_STEPS:,} steps a run (about 10 s and 160 MB): shorten "
                         "--duration or lengthen --dt")
    if fps is not None and duration * fps > MAX_SAMPLES:
        raise FieldError(f"--duration {duration:g} s x --fps {fps:g} = {duration * fps:.3g} "
                         f"frames; at most {MAX_SAMPLES:,} frames a run")


def _why(exc: OSError) -> str:
    return exc.strerror or str(exc) or type(exc).__name__


class Outputs:
    """The files a command writes, named by their flags.

    :meth:`reserve` checks each path before the work starts (an empty or duplicate path, a
    missing or unwritable folder, a folder in place of a file) by creating a hidden file beside
    it; :meth:`write` fills one; :meth:`commit` renames them all into place.  A command that
    ends without :meth:`commit` (an error, an interrupt) leaves its hidden files to
    :func:`discard_pending`, which ``cli.main`` calls when every command ends, so the folders are
    as they were.  Every message names the flag and the path the user gave.
    """

    _pending: list = []

    def __init__(self):
        self._files: dict[str, tuple[Path, Path]] = {}     # flag -> (target, hidden file)
        Outputs._pending.append(self)

    def reserve(self, flag: str, path) -> None:
        if path is None:
            return
        if str(path).strip() == "":
            raise FieldError(f"{flag} = {str(path)!r} is not a file path")
        target = Path(path)
        for other, (known, _) in self._files.items():
            if known.resolve() == target.resolve():
                raise FieldError(f"{flag} = {str(path)!r} is the same file as {other}")
        if target.is_dir():
            raise FieldError(f"{flag} = {str(path)!r} is a folder, not a file")
        if target.exists() and not target.is_file():     # a device or a pipe: never replaced
            raise FieldError(f"{flag} = {str(path)!r} is not a regular file")
        folder = target.resolve().parent
        if not folder.is_dir():
            raise FieldError(f"{flag} = {str(path)!r}: the folder {str(folder)!r} does not "
                             "exist")
        if target.exists() and not os.access(target, os.W_OK):
            raise FieldError(f"{flag} = {str(path)!r} is read-only")
        try:
            hidden = temp_beside(target)
        except OSError as exc:
            raise FieldError(f"{flag} = {str(path)!r} cannot be written: {_why(exc)}") from None
        self._files[flag] = (target, hidden)

    def write(self, flag: str, fill) -> None:
        """``fill(path)`` writes the output of ``flag`` (to the hidden file)."""
        target, hidden = self._files[flag]
        try:
            fill(hidden)
        except OSError as exc:
            raise FieldError(f"{flag} = {str(target)!r} cannot be written: {_why(exc)}") \
                from None

    def commit(self, only=None) -> None:
        """Rename every hidden file (or those of the flags ``only``) over its target; if one
        rename fails, put back what the earlier ones replaced."""
        if only is not None:
            for flag in [f for f in self._files if f not in only]:
                self._files.pop(flag)[1].unlink(missing_ok=True)
        done = []                                  # (target, backup or None)
        try:
            for flag, (target, hidden) in self._files.items():
                backup = None
                if target.exists():
                    backup = temp_beside(target)
                    os.replace(target, backup)
                done.append((target, backup))
                os.replace(hidden, target)
        except OSError as exc:
            for target, backup in reversed(done):
                if backup is not None:
                    os.replace(backup, target)
                else:
                    target.unlink(missing_ok=True)
            raise FieldError(f"{flag} = {str(target)!r} cannot be written: {_why(exc)}") \
                from None
        for _, backup in done:
            if backup is not None:
                backup.unlink(missing_ok=True)
        self._files.clear()

    def discard(self) -> None:
        for _, hidden in self._files.values():
            hidden.unlink(missing_ok=True)
        self._files.clear()


def discard_pending() -> None:
    """Remove the hidden files of every :class:`Outputs` not committed."""
    while Outputs._pending:
        Outputs._pending.pop().discard()
