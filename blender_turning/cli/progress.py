"""A progress bar on stderr for long commands, only when stderr is a terminal (quiet in
pipelines and logs).  tqdm draws it when installed (the ``progress`` extra); otherwise a plain
one-line counter does."""
from __future__ import annotations

import sys
import time


class Progress:
    """``update(done, total)`` after each piece of work (``note``: a short text shown after the
    count, e.g. the course time planned); ``close()`` at the end (or use ``with``).  Does nothing
    unless ``stream`` is a terminal.  ``unit="%"`` counts percent."""

    def __init__(self, total: int, unit: str, desc: str, stream=None):
        self.stream = sys.stderr if stream is None else stream
        self.on = bool(getattr(self.stream, "isatty", lambda: False)())
        self.total, self.unit, self.desc = total, unit, desc
        self._bar = None
        self._start = time.perf_counter()
        if self.on:
            try:
                from tqdm import tqdm
            except ImportError:
                return
            self._bar = tqdm(total=total, unit=unit, desc=desc, file=self.stream)

    def update(self, done: int, total: int | None = None, note: str = "") -> None:
        if not self.on:
            return
        if self._bar is not None:
            if note:
                self._bar.set_postfix_str(note, refresh=False)
            self._bar.update(done - self._bar.n)
            return
        spent = time.perf_counter() - self._start
        left = f"about {spent * (self.total - done) / done:.0f} s left" if done else "..."
        count = f"{done}%" if self.unit == "%" else f"{done}/{self.total} {self.unit}s"
        self.stream.write(f"\r{self.desc}: {count}{f', {note}' if note else ''}, "
                          f"{spent:.0f} s, {left} ")
        self.stream.flush()

    __call__ = update

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()
        elif self.on:
            self.stream.write("\n")
            self.stream.flush()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
