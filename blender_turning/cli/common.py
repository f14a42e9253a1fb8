"""Helpers shared by the CLI commands: optional matplotlib, and the outputs of a command, checked
before any work starts and written all together or not at all."""
from __future__ import annotations

import os
from pathlib import Path

from ..core.files import WriteError, disk_reason, temp_beside, verify_file
from ..core.ranges import MAX_SAMPLES, MAX_STEPS
from ..core.validate import FieldError
from ..core import signals


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


def _folder(path: Path, cache: dict) -> Path:
    """``path``'s folder, resolved (once per folder: a crowd reserves thousands of files in
    one)."""
    key = path.parent
    if key not in cache:
        cache[key] = key.resolve()
    return cache[key]


class Outputs:
    """The files a command writes, named by their flags.

    :meth:`reserve` checks each path before the work starts (an empty or duplicate path, a
    missing or unwritable folder, a folder in place of a file) by creating a hidden file beside
    it; :meth:`write` fills one and checks it (:func:`~..core.files.verify_file`);
    :meth:`commit` renames them all into place, with SIGINT and SIGTERM held until it is done
    (:func:`..core.signals.deferred`).  A command that ends without :meth:`commit` (an error, an
    interrupt) leaves its hidden files to :func:`discard_pending`, which ``cli.main`` calls when
    every command ends, so the folders are as they were.  Every message names the flag and the
    path the user gave; a failed write is :class:`~..core.files.WriteError` (exit 1).
    """

    _pending: list = []
    kept: list = []             # targets committed by any command of this process

    def __init__(self):
        self._files: dict[str, tuple[Path, Path]] = {}     # flag -> (target, hidden file)
        self._resolved: dict[Path, str] = {}               # resolved target -> flag
        self._folders: dict[Path, Path] = {}
        Outputs._pending.append(self)

    def reserve(self, flag: str, path) -> None:
        if path is None:
            return
        if str(path).strip() == "":
            raise FieldError(f"{flag} = {str(path)!r} is not a file path")
        target = Path(path)
        folder = _folder(target, self._folders)
        if not folder.is_dir():
            raise FieldError(f"{flag} = {str(path)!r}: the folder {str(folder)!r} does not "
                             "exist")
        real = (folder / target.name).resolve() if target.is_symlink() else folder / target.name
        if real in self._resolved:
            raise FieldError(f"{flag} = {str(path)!r} is the same file as "
                             f"{self._resolved[real]}")
        if target.is_dir():
            raise FieldError(f"{flag} = {str(path)!r} is a folder, not a file")
        if target.exists() and not target.is_file():     # a device or a pipe: never replaced
            raise FieldError(f"{flag} = {str(path)!r} is not a regular file")
        if target.exists() and not os.access(target, os.W_OK):
            raise FieldError(f"{flag} = {str(path)!r} is read-only")
        with signals.deferred():          # the hidden file is made and recorded, or neither
            try:
                hidden = temp_beside(target)
            except OSError as exc:
                raise FieldError(f"{flag} = {str(path)!r} cannot be written: "
                                 f"{_why(exc)}") from None
            self._files[flag] = (target, hidden)
            self._resolved[real] = flag

    def write(self, flag: str, fill, kind: str | None = None) -> None:
        """``fill(path)`` writes the output of ``flag`` (to the hidden file), which is then
        checked (``kind``: as :func:`~..core.files.verify_file`, default the suffix)."""
        target, hidden = self._files[flag]
        try:
            # Written afresh: ext4 flushes a file renamed over another (18 ms each measured
            # here), and a crowd's writer renames its own temporary file onto this name.
            hidden.unlink(missing_ok=True)
            fill(hidden)
            verify_file(hidden, kind or target.suffix.lstrip("."))
        except OSError as exc:
            raise WriteError(f"{flag} = {str(target)!r} cannot be written: "
                             f"{disk_reason(hidden, exc)}") from None
        except WriteError as exc:
            raise WriteError(f"{flag} = {str(target)!r} cannot be written: {exc}") from None

    def commit(self, only=None) -> None:
        """Rename every hidden file (or those of the flags ``only``) over its target; if one
        rename fails, put back what the earlier ones replaced."""
        if only is not None:
            for flag in [f for f in self._files if f not in only]:
                self._files.pop(flag)[1].unlink(missing_ok=True)
        done = []                                  # (target, backup or None)
        with signals.deferred():                   # all renamed, or none
            try:
                for flag, (target, hidden) in self._files.items():
                    backup = None
                    if target.exists():
                        backup = temp_beside(target)
                        os.replace(target, backup)
                    done.append((target, backup))
                    os.replace(hidden, target)
            except OSError as exc:
                for target_, backup in reversed(done):
                    if backup is not None:
                        os.replace(backup, target_)
                    else:
                        target_.unlink(missing_ok=True)
                raise WriteError(f"{flag} = {str(target)!r} cannot be written: "
                                 f"{_why(exc)}") from None
            for _, backup in done:
                if backup is not None:
                    backup.unlink(missing_ok=True)
            Outputs.kept.extend(target for target, _ in done)
            self._files.clear()
            self._resolved.clear()

    def discard(self) -> None:
        for _, hidden in self._files.values():
            hidden.unlink(missing_ok=True)
        self._files.clear()
        self._resolved.clear()


def discard_pending() -> None:
    """Remove the hidden files of every :class:`Outputs` not committed."""
    while Outputs._pending:
        Outputs._pending.pop().discard()
