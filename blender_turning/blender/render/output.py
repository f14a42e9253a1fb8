"""What the render job puts out: its log lines and its files, every file written to a hidden name,
checked, then renamed (docs/failures.md)."""
from __future__ import annotations

import os
from pathlib import Path

from ...core import signals
from ...core.files import WriteError, disk_reason, file_size_limit, verify_file


def log(msg: str) -> None:
    print(f"render_job: {msg}", flush=True)


KEPT: list = []                 # the files this job has put in place (said when it is stopped)


def _staged(final: Path) -> Path:
    """The hidden name ``final`` is written under first (same folder, same suffix)."""
    return final.with_name(f".tmp-{os.getpid()}-{final.name}")


def _check_and_place(staged: Path, final: Path, what: str) -> None:
    try:
        verify_file(staged, final.suffix.lstrip("."))
    except WriteError as exc:
        raise WriteError(f"{what} {str(final)!r} was not written: {exc}") from None
    try:
        os.replace(staged, final)
    except OSError as exc:
        raise WriteError(f"{what} {str(final)!r} was not written: {disk_reason(final, exc)}") \
            from None


def save_blend(bpy, blend: Path) -> None:
    """Save the scene as ``blend``: to a hidden name, checked (Blender's header), renamed.  A
    save that fails (a full disk, a file too large) leaves no .blend, old or partial, behind:
    :class:`WriteError`."""
    staged = _staged(blend)
    try:
        try:
            # Blender writes ``<path>@`` and renames it itself; a failure can leave either.
            bpy.ops.wm.save_as_mainfile(filepath=str(staged), check_existing=False)
        except RuntimeError as exc:
            why = str(exc).strip().splitlines()[-1] if str(exc).strip() else ""
            why = disk_reason(blend) or why or "Blender could not save it"
            limit = file_size_limit()          # Blender's own words may not say it hit it
            if limit is not None and "too large" not in why:
                why += f" (files are limited to {limit} bytes here: ulimit -f)"
            raise WriteError(f"the .blend {str(blend)!r} was not written: {why}") from None
        _check_and_place(staged, blend, "the .blend")
    finally:
        staged.unlink(missing_ok=True)
        Path(f"{staged}@").unlink(missing_ok=True)


def render_frames(bpy, folder: Path, frames, count) -> None:
    """Render ``frames`` one by one, each to a hidden name, checked (a whole PNG) and renamed
    to ``folder/frame_####.png``.  The first frame that does not come out whole stops the job
    with :class:`WriteError` naming the frames not written and why (the ones before it are
    kept)."""
    scene = bpy.context.scene
    folder.mkdir(parents=True, exist_ok=True)
    for k, f in enumerate(frames):
        final = folder / f"frame_{f:04d}.png"
        staged = _staged(final)
        scene.frame_set(f)
        scene.render.filepath = str(staged)
        try:
            bpy.ops.render.render(write_still=True)
            try:
                _check_and_place(staged, final, "frame")
            except WriteError as exc:
                rest = frames[k:]
                span = f"{rest[0]}" if len(rest) == 1 else f"{rest[0]}-{rest[-1]}"
                why = str(exc).split(": ", 1)[-1]
                raise WriteError(f"{len(rest)} of {len(frames)} frames not written to "
                                 f"{str(folder)!r} (frames {span}; frame {f}: {why})") from None
        finally:
            staged.unlink(missing_ok=True)
        KEPT.append(final)
        count[0] += 1
        log(f"rendered frame {f} ({count[0]}/{count[1]})")
        signals.checkpoint()                   # a signal during the frame stops here


def render_video(bpy, final: Path) -> None:
    """Render the animation as one video to a hidden name, checked (not empty), renamed."""
    scene = bpy.context.scene
    staged = _staged(final)
    scene.render.filepath = str(staged)
    try:
        bpy.ops.render.render(animation=True)
        _check_and_place(staged, final, "the video")
    finally:
        staged.unlink(missing_ok=True)
    KEPT.append(final)
    signals.checkpoint()
