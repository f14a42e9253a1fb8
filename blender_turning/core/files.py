"""Writing files so that a failure leaves nothing behind: a hidden temporary file in the target's
folder, checked (:func:`verify_file`: not empty, readable, complete for its kind) and renamed over
the target only then.  The file gets the mode any other new file would get (``0o666`` less the
umask), not ``mkstemp``'s private ``0o600``.  :class:`OutputLock` keeps a second job from writing
the same output folder at the same time (docs/failures.md).
"""
from __future__ import annotations

import errno
import json
import os
import socket
import tempfile
import time
from pathlib import Path

from . import signals

__all__ = ["new_file_mode", "temp_beside", "atomic_write_text", "verify_file", "WriteError",
           "OutputLock", "OutputLocked", "disk_reason", "file_size_limit"]


class WriteError(Exception):
    """An output could not be written (the disk is full, the write was cut short, the file
    came out unreadable): the message names the path and the reason.  Commands exit 1 on it
    (bad input is 2)."""


def disk_reason(path, exc: BaseException | None = None) -> str:
    """Why writing beside ``path`` failed: the OS's words for ``exc``, else "no space left on
    device" when the disk is full, else ``""``."""
    if isinstance(exc, OSError) and (exc.strerror or exc.errno):
        return exc.strerror or os.strerror(exc.errno)
    try:
        folder = Path(path).parent
        st = os.statvfs(folder if str(folder) else ".")
        if st.f_bavail * st.f_frsize < 64 * 1024:
            return os.strerror(errno.ENOSPC)
    except OSError:
        pass
    return "" if exc is None else (str(exc) or type(exc).__name__)


# The first bytes of a complete file of each kind, and (PNG) its last chunk.
_PNG_HEAD, _PNG_TAIL = b"\x89PNG\r\n\x1a\n", b"IEND\xaeB`\x82"
_BLEND_HEADS = (b"BLENDER", b"\x28\xb5\x2f\xfd", b"\x1f\x8b")   # plain, zstd, gzip


def verify_file(path, kind: str | None = None) -> None:
    """Check a file just written: it exists, is not empty and reads back; a ``.png`` starts
    with the PNG signature and ends with its ``IEND`` chunk (a truncated frame does not), a
    ``.blend`` starts with Blender's header (plain or compressed), a ``.json`` parses, a
    ``.csv`` ends with a whole line.  ``kind`` defaults to the suffix.  Raises
    :class:`WriteError` saying what is wrong (not naming ``path``: the caller names the
    output the user asked for)."""
    path = Path(path)
    kind = (kind or path.suffix.lstrip(".")).lower()
    try:
        size = path.stat().st_size
        if size == 0:
            raise WriteError(f"the file came out empty{_why_suffix(path)}")
        with open(path, "rb") as fh:
            head = fh.read(16)
            fh.seek(max(0, size - 64))
            tail = fh.read()
            if kind == "json":
                fh.seek(0)
                json.loads(fh.read().decode("utf-8"))
    except WriteError:
        raise
    except (OSError, ValueError) as exc:
        raise WriteError(f"the file does not read back ({disk_reason(path, exc)})") from None
    why = _why_suffix(path, size)
    if kind == "png" and not (head.startswith(_PNG_HEAD) and tail.endswith(_PNG_TAIL)):
        raise WriteError(f"the PNG is incomplete ({size} bytes){why}")
    if kind == "blend" and not head.startswith(_BLEND_HEADS):
        raise WriteError(f"the .blend has no Blender header ({size} bytes){why}")
    if kind == "blend" and not _blend_complete(head, tail):
        raise WriteError(f"the .blend is incomplete ({size} bytes){why}")
    if kind == "csv" and not tail.endswith(b"\n"):
        raise WriteError(f"the CSV ends mid-line ({size} bytes){why}")


def _blend_complete(head: bytes, tail: bytes) -> bool:
    """A plain .blend ends with its ``ENDB`` block; a zstd one (Blender's compression) with the
    seek table of zstd's seekable format, whose footer ends with ``0x8F92EAB1``; gzip (older
    Blenders) is taken on its header."""
    if head.startswith(b"BLENDER"):
        return b"ENDB" in tail
    if head.startswith(b"\x28\xb5\x2f\xfd"):
        return tail.endswith(b"\xb1\xea\x92\x8f")
    return True


def _why_suffix(path, size: int = 0) -> str:
    why = disk_reason(path) or _size_limit_reason(size)
    return f": {why}" if why else ""


def file_size_limit() -> int | None:
    """This process's file-size limit in bytes (``ulimit -f``, ``RLIMIT_FSIZE``, which a farm
    may set), or None where there is none."""
    try:
        import resource
        limit = resource.getrlimit(resource.RLIMIT_FSIZE)[0]
    except (ImportError, OSError, ValueError):       # no such limit (Windows)
        return None
    return None if limit == resource.RLIM_INFINITY else int(limit)


def _size_limit_reason(size: int) -> str:
    """"File too large" when a file cut short stopped at :func:`file_size_limit`: the writer
    (Blender's, for a .blend or a frame) may not say why it stopped."""
    limit = file_size_limit()
    if limit is None or size < limit:
        return ""
    return f"{os.strerror(errno.EFBIG)} (the file-size limit is {limit} bytes)"


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
    tmp = None
    try:
        with signals.deferred():      # made and handed back whole, or not at all
            fd, tmp = tempfile.mkstemp(dir=path.parent if str(path.parent) else ".",
                                       prefix=".tmp-", suffix=path.suffix)
            try:
                os.fchmod(fd, new_file_mode())
            finally:
                os.close(fd)
    except BaseException:             # a signal held meanwhile, a failed chmod: never handed back
        if tmp is not None:
            os.unlink(tmp)
        raise
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
        if os.path.getsize(tmp) != len(text.encode("utf-8")):
            raise OSError(errno.EIO, f"{os.strerror(errno.EIO)} (the file came out short)")
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


class OutputLocked(Exception):
    """Another job holds the lock of an output folder (the message names it: pid, host,
    since when, and the lock file)."""


class OutputLock:
    """``with OutputLock(folder, flag):`` -- the folder is this job's until the block ends.

    The lock is the file ``folder/.turning.lock``, made with ``O_EXCL`` and holding the
    owner's pid, host and start time as JSON.  A lock whose pid is gone on this host (a job
    killed with SIGKILL) is stale and taken over; one held by a live process, or by another
    host (which this host cannot check), is refused with :class:`OutputLocked`."""

    NAME = ".turning.lock"

    def __init__(self, folder, flag: str = "--out", job: str = ""):
        self.folder, self.flag, self.job = Path(folder), flag, job
        self.path = self.folder / self.NAME
        self._held = False

    def __enter__(self):
        me = {"pid": os.getpid(), "host": socket.gethostname(), "job": self.job,
              "since": time.strftime("%Y-%m-%d %H:%M:%S")}
        for _ in range(3):
            try:
                return self._take(me)
            except FileExistsError:
                other = self._owner()
                if other is not None and self._alive(other):
                    raise OutputLocked(
                        f"{self.flag} = {str(self.folder)!r} is being written by another job "
                        f"(pid {other.get('pid')} on {other.get('host')}"
                        f"{', ' + other['job'] if other.get('job') else ''}, since "
                        f"{other.get('since')}); wait for it to end, or remove "
                        f"{str(self.path)!r} if that job is gone") from None
                self.path.unlink(missing_ok=True)       # stale: its owner is gone
                continue
            except BaseException:         # a signal while the lock was being made
                self._drop_if_ours()
                raise
        raise OutputLocked(f"{self.flag} = {str(self.folder)!r}: cannot take the lock "
                           f"{str(self.path)!r}")

    def _take(self, me):
        fd = os.open(self.path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
        with os.fdopen(fd, "w") as fh:
            json.dump(me, fh)
        self._held = True
        return self

    def _drop_if_ours(self) -> None:
        """Remove a lock this process made but did not finish (empty, or naming this pid):
        ``with`` never enters its block then, so ``__exit__`` would not."""
        try:
            text = self.path.read_text()
        except OSError:
            return
        try:
            ours = not text or json.loads(text).get("pid") == os.getpid()
        except (ValueError, AttributeError):
            ours = False
        if ours:
            self.path.unlink(missing_ok=True)
        self._held = False

    def _owner(self):
        try:
            return json.loads(self.path.read_text())
        except FileNotFoundError:
            return None
        except (OSError, ValueError):
            return {"pid": "?", "host": "?", "since": "?"}     # unreadable: keep refusing

    @staticmethod
    def _alive(owner) -> bool:
        if owner.get("host") != socket.gethostname() or not isinstance(owner.get("pid"), int):
            return True                     # another host's job: this one cannot tell
        try:
            os.kill(owner["pid"], 0)
        except ProcessLookupError:
            return False
        except PermissionError:
            return True
        return True

    def __exit__(self, *exc):
        if self._held:
            self._held = False
            self.path.unlink(missing_ok=True)
