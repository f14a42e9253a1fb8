"""``figures``: regenerate the paper's figures as PNGs (needs matplotlib)."""
from __future__ import annotations

import importlib
from pathlib import Path

from ..figures import FIGURES
from ..core.validate import FieldError
from .common import require_matplotlib


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
    for stem in (args.only or FIGURES):
        module, func = FIGURES[stem]
        getattr(importlib.import_module(f"..figures.{module}", __package__), func)(out)
        print(f"figures: wrote {out / (stem + '.png')}")
    return 0
