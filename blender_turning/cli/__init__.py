"""The command line: ``python -m blender_turning <command> ...``.  No bpy needed.

Each command is a module with ``register(subparsers)`` (adds its parser and sets
``func=run``) and ``run(args) -> int``; ``COMMANDS`` lists them in help order.  A domain error or a
bad value (``ValueError``, ``TurningError``, ``OSError``) becomes one line on stderr and exit 2; a
failed write (``WriteError``: a full disk, an unreadable result) or a lost worker one line and
exit 1; SIGINT or
SIGTERM one line and exit 130 or 143 (:mod:`..core.signals`).  No output is left half-written and no
hidden file is left behind (``common.Outputs``); docs/failures.md has the whole policy.
"""
from __future__ import annotations

import argparse
import importlib
import sys

from ..core.errors import TurningError, WorkerLost
from ..core.files import OutputLocked, WriteError
from ..core import signals
from ..core.registry import import_extension
from .common import Outputs, discard_pending

COMMANDS = ("simulate", "figures", "follow", "crowd")


class _Parser(argparse.ArgumentParser):
    def error(self, message):          # argparse's own errors: one line, exit 2
        self.exit(2, f"{self.prog}: error: {message}\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="python -m blender_turning",
                     description="Physically based turning (van de Panne, Fiume, Vranesic 1993).")
    parser.add_argument("--register", action="append", default=[], metavar="MODULE",
                        help="import a module (a .py file or a module name) that registers "
                             "your own sports, formations or controllers (docs/registry.md) "
                             "before the command; repeatable")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    for name in COMMANDS:
        try:
            module = importlib.import_module(f".{name}", __name__)
        except ModuleNotFoundError as exc:
            if exc.name != f"{__name__}.{name}":
                raise
            continue                  # a command whose module is not there yet
        module.register(sub)
    return parser


def _register_extensions(argv) -> None:
    """Import the ``--register`` modules first: the command's choices (``--preset``,
    ``--controller``) are the registries' when its parser is built."""
    pre = argparse.ArgumentParser(add_help=False)
    pre.add_argument("--register", action="append", default=[])
    known, _ = pre.parse_known_args(argv)
    for spec in known.register:
        import_extension(spec)


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    with signals.stop_on_signals():
        try:
            try:
                _register_extensions(argv)
            except ValueError as exc:
                print(f"python -m blender_turning: error: {exc}", file=sys.stderr)
                return 2
            parser = build_parser()
            args = parser.parse_args(argv)
        except signals.Interrupted as exc:
            print(signals.interrupted_line("python -m blender_turning", exc), file=sys.stderr)
            return exc.code
        prog = f"{parser.prog} {args.command}"
        Outputs.kept.clear()
        try:
            try:
                return int(args.func(args) or 0)
            except KeyboardInterrupt:          # raised by hand, or before the handler was in
                raise signals.Interrupted(signals.signal.SIGINT) from None
        except signals.Interrupted as exc:
            discard_pending()
            print(signals.interrupted_line(prog, exc, Outputs.kept), file=sys.stderr)
            return exc.code
        except (WriteError, WorkerLost) as exc:
            print(f"{prog}: error: {exc}", file=sys.stderr)
            return 1
        except (ValueError, TurningError, OSError, OutputLocked) as exc:
            print(f"{prog}: error: {exc}", file=sys.stderr)
            return 2
        finally:
            discard_pending()      # outputs a failed command reserved but did not write
