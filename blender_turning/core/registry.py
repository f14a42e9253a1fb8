"""Registries of the add-on's extension points: one record per sport, per formation, per
controller (docs/registry.md).

A :class:`Registry` is an explicit dictionary filled by registration (``register``), never by
scanning a folder: the built-in records register when their module is imported, a user's own
records when their module calls ``register`` (a script, a notebook, another add-on).  Every
reader, command-line choice list, Blender enum, menu and validator asks the registry at the
moment it needs the list, so a record registered later is seen by all of them.

``SPORTS`` lives here, apart from its record type (:class:`.sports.Sport`), so that the core's
modules that read it (``params.PRESETS``, ``model.RESISTANCE``) need not import the
sports.  Standard library only.
"""
from __future__ import annotations

import importlib
import importlib.util
import re
import sys
from collections.abc import Mapping
from pathlib import Path

__all__ = ["Registry", "RegistryView", "ChainView", "SPORTS", "SPORT_PRESETS", "import_extension"]

_NAME = re.compile(r"^[a-z][a-z0-9_-]*$")


class Registry(Mapping):
    """Records of one ``kind`` by their ``name``, in the order they were registered.

    A read-only :class:`~collections.abc.Mapping` (``name in reg``, ``reg[name]``, iteration in
    registration order); :meth:`register` and :meth:`unregister` change it, :meth:`lookup` is
    the readers' ``reg[name]`` with an error that names the kind and the choices.  A record
    validates itself when it is made (a frozen dataclass's ``__post_init__``); the registry
    checks that its name and its ``unique`` attributes (a Blender enum's stored number) are
    not taken."""

    def __init__(self, kind: str, unique: tuple = ()):
        self.kind = kind
        self._unique = tuple(unique)
        self._records: dict = {}
        self.version = 0
        """Counts the changes (a cache of a list built from the registry compares it)."""

    def register(self, record, replace: bool = False):
        """Add ``record`` under ``record.name`` and return it.  A name already registered is
        refused unless ``replace`` (re-running a module that registers, e.g. a script)."""
        name = getattr(record, "name", None)
        if not isinstance(name, str) or not _NAME.match(name):
            raise ValueError(f"{self.kind} name = {name!r} is not a lowercase identifier "
                             "(a letter, then letters, digits, '_' or '-')")
        if name in self._records and not replace:
            raise ValueError(f"{self.kind} = {name!r} is already registered (pass "
                             "replace=True to replace it)")
        for attr in self._unique:
            v = getattr(record, attr)
            other = next((r.name for r in self._records.values()
                          if r.name != name and getattr(r, attr) == v), None)
            if other is not None:
                raise ValueError(f"{self.kind} {name!r}: {attr} = {v!r} is taken by {other!r}")
        self._records[name] = record
        self.version += 1
        return record

    def unregister(self, name: str) -> None:
        """Remove the record ``name`` (``ValueError`` when there is none)."""
        self.lookup(name)
        del self._records[name]
        self.version += 1

    def lookup(self, name: str):
        """The record ``name``; ``ValueError`` naming the kind and the registered names."""
        try:
            return self._records[name]
        except (KeyError, TypeError):
            raise ValueError(f"{self.kind} = {name!r} is not one of "
                             f"{', '.join(self._records) or '(none registered)'}") from None

    def __getitem__(self, name):
        return self._records[name]

    def __iter__(self):
        return iter(tuple(self._records))

    def __len__(self) -> int:
        return len(self._records)

    def __repr__(self) -> str:
        return f"Registry({self.kind!r}: {', '.join(self._records)})"

    def view(self, attr, where=None) -> "RegistryView":
        """A live read-only mapping ``name -> attr`` of the records (``attr``: an attribute
        name or a function of the record), of those where ``where(record)`` is true."""
        return RegistryView(self, attr, where)


class RegistryView(Mapping):
    """``name -> a part of the record``, always of the registry's current records."""

    def __init__(self, registry: Registry, attr, where=None):
        self._registry = registry
        self._get = attr if callable(attr) else (lambda r, a=attr: getattr(r, a))
        self._where = where or (lambda r: True)

    def __getitem__(self, name):
        record = self._registry[name]
        if not self._where(record):
            raise KeyError(name)
        return self._get(record)

    def __iter__(self):
        return (n for n, r in self._registry.items() if self._where(r))

    def __len__(self) -> int:
        return sum(1 for _ in self)

    def __repr__(self) -> str:
        return f"{{{', '.join(f'{k!r}: {v!r}' for k, v in self.items())}}}"


class ChainView(Mapping):
    """Several live mappings read as one: the first that has a name answers for it."""

    def __init__(self, *maps):
        self._maps = maps

    def __getitem__(self, name):
        for m in self._maps:
            if name in m:
                return m[name]
        raise KeyError(name)

    def __iter__(self):
        seen = set()
        for m in self._maps:
            for name in m:
                if name not in seen:
                    seen.add(name)
                    yield name

    def __len__(self) -> int:
        return sum(1 for _ in self)

    def __repr__(self) -> str:
        return f"{{{', '.join(f'{k!r}: {v!r}' for k, v in self.items())}}}"


#: The sports (:class:`.sports.Sport`), registered by their modules (``mapping/sports/<sport>.py``);
#: ``number`` is the value a Blender file stores for the sport's enum item.
SPORTS = Registry("sport", unique=("number",))

#: Presets of a registered sport with their own body, limits and equipment
#: (:class:`.equipment.SportPreset`: the racers, the carver), by their names.
SPORT_PRESETS = Registry("preset")


def import_extension(spec: str, flag: str = "--register"):
    """Import the user's module that registers records: ``spec`` a ``.py`` file or a module name
    on ``sys.path`` (the command line's and the render job's ``--register``).  Importing twice
    runs it once.  ``ValueError`` naming ``flag`` when it cannot be imported."""
    path = Path(spec)
    try:
        if spec.endswith(".py"):
            name = f"turning_extension_{path.stem}"
            if name in sys.modules:
                return sys.modules[name]
            if not path.is_file():
                raise ValueError(f"{flag} = {spec!r}: no such file")
            module_spec = importlib.util.spec_from_file_location(name, path)
            module = importlib.util.module_from_spec(module_spec)
            sys.modules[name] = module
            try:
                module_spec.loader.exec_module(module)
            except BaseException:
                del sys.modules[name]
                raise
            return module
        return importlib.import_module(spec)
    except ValueError as exc:
        raise ValueError(str(exc) if str(exc).startswith(flag) else
                         f"{flag} = {spec!r}: {exc}") from None
    except (ImportError, SyntaxError, OSError) as exc:
        raise ValueError(f"{flag} = {spec!r} cannot be imported ({exc})") from None
