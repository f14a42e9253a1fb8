"""``figures``: regenerate the paper's figures as PNGs (needs matplotlib).

Each figure is drawn into a hidden folder inside ``--out``, checked (a whole PNG) and renamed
into place when it is done, so an interrupted or failed run keeps the figures finished before
it and leaves no partial PNG or hidden file.
"""
from __future__ import annotations

import importlib
import os
import shutil
import tempfile
from pathlib import Path

from ..figures import FIGURES
from ..core.validate import FieldError
from .common import Outputs, require_matplotlib


def register(sub):
    p = sub.add_parser("figures", help="regenerate the paper's figures as PNGs")
    p.add_argument("--out", required=True, help="folder for the PNGs (created if missing)")
    p.add_argument("--only", nargs="*", choices=sorted(FIGURES), help="just these figures")
    p.set_defaults(func=run)


def run(args) -> int:
    require_matplotlib("figures")
    if not args.out.strip():
        raise FieldError(f"--out = {args.out!r} is not a folder path")
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise FieldError(f"--out = {args.out!r} is a file, not a folder")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise FieldError(f"--out = {args.out!r} cannot be created: "
                         f"{exc.strerror or exc}") from None
    stems = list(args.only or FIGURES)
    outputs = {}                              # one per figure: each kept when it is done
    for stem in stems:
        outputs[stem] = Outputs()
        outputs[stem].reserve(f"--out {stem}.png", out / f"{stem}.png")
    stage = Path(tempfile.mkdtemp(dir=out, prefix=".tmp-figures-"))
    try:
        for stem in stems:
            module, func = FIGURES[stem]
            getattr(importlib.import_module(f"..figures.{module}", __package__), func)(stage)
            drawn = stage / f"{stem}.png"
            outputs[stem].write(f"--out {stem}.png", lambda path: os.replace(drawn, path))
            outputs[stem].commit()
            print(f"figures: wrote {out / (stem + '.png')}")
    finally:
        shutil.rmtree(stage, ignore_errors=True)
    return 0
