"""One record per formation (docs/registry.md): how a crowd file, a render job and Blender's Add
Crowd read and make it.

A :class:`Formation` says what it is (label, description, the number a .blend file stores for
its enum item), what it is made from (``template``: a leader figure named in the crowd, a turns
template, a path template, or either), which keys its table in a crowd file has and how to read
them (``read``), and how Blender's Add Crowd makes it from its settings (``build``, ``fields``,
``start_along``).  The built-ins register in :mod:`.formations`; a user's own formation is one
module that makes its record and calls :func:`register_formation`.  numpy-free.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from ..core.registry import Registry

__all__ = ["Formation", "FormationRefused", "FORMATIONS", "TEMPLATES", "register_formation",
           "unregister_formation"]

#: What a formation is made from: ``leader``: a figure defined before it in the crowd (named by
#: the ``leader`` key), one of the crowd itself; ``turns`` / ``path``: a ``template`` table of a
#: figure on the parametric controller / following a path; ``any``: a template of either.
TEMPLATES = ("leader", "turns", "path", "any")


class FormationRefused(ValueError):
    """A formation refuses a combination of its settings (the message says which); a reader
    reports it against the formation's table."""


def _no_start(k: int, values) -> float:
    return 0.0


@dataclass(frozen=True, eq=False)
class Formation:
    """A formation: one record, registered once (:func:`register_formation`)."""

    name: str
    """The crowd file's ``type`` (``"follow_leader"``)."""
    label: str
    """What Blender shows (the Formation enum, Add > Turning Figure > Add Crowd)."""
    description: str
    """The enum item's tooltip."""
    number: int
    """The value Blender stores for the enum item (the built-ins are 0-2)."""
    template: str
    """One of :data:`TEMPLATES`."""
    keys: frozenset
    """The keys of its table in a crowd file besides ``type``, ``name`` and (by ``template``)
    ``leader`` / ``template``."""
    read: Callable
    """``read(table, member, seed, name) -> members``: the formation of the crowd file's
    ``table`` (:class:`..core.validate.Fields`; a bad value fails naming its key) made from
    ``member`` (the leader or the template, a :class:`.model.CrowdFigure`), the crowd's
    ``seed`` the default of its own, ``name`` the members' name prefix (``None``: its default).
    A combination the formation refuses raises :class:`FormationRefused`."""
    build: Callable
    """``build(member, values, name) -> members``: the formation Add Crowd makes from its
    settings ``values`` (an object with the operator's settings as attributes, checked)."""
    fields: Callable
    """``fields(values) -> names``: the Add Crowd settings it draws, in order."""
    start_along: Callable = _no_start
    """``start_along(k, values) -> s``: how far (m) along its path member ``k`` (1-based) starts
    (Add Crowd draws that member's path curve from there)."""
    icon: str = "NONE"
    """A Blender icon name for the enum item."""

    def __post_init__(self):
        for name in ("label", "description"):
            if not isinstance(getattr(self, name), str) or not getattr(self, name).strip():
                raise ValueError(f"formation {self.name!r}: {name} = {getattr(self, name)!r} "
                                 "is not a non-empty string")
        if self.template not in TEMPLATES:
            raise ValueError(f"formation {self.name!r}: template = {self.template!r} is not "
                             f"one of {', '.join(TEMPLATES)}")
        if not isinstance(self.number, int) or isinstance(self.number, bool) or \
                not 0 <= self.number < 2 ** 20:
            raise ValueError(f"formation {self.name!r}: number = {self.number!r} is not a "
                             "whole number in [0, 2^20)")
        for name in ("read", "build", "fields", "start_along"):
            if not callable(getattr(self, name)):
                raise ValueError(f"formation {self.name!r}: {name} is not callable")
        object.__setattr__(self, "keys", frozenset(self.keys))

    @property
    def key(self) -> str:
        """The Blender enum identifier (``"FOLLOW_LEADER"``)."""
        return self.name.upper()

    @property
    def file_keys(self) -> frozenset:
        """Every key its table in a crowd file may have."""
        made_from = {"leader"} if self.template == "leader" else {"template"}
        return self.keys | {"type", "name"} | made_from


#: The formations, registered by their modules (the built-ins: :mod:`.formations`).
FORMATIONS = Registry("formation", unique=("number",))


def register_formation(record: Formation, replace: bool = False) -> Formation:
    """Register ``record`` (a name or number already taken is refused unless ``replace``)."""
    if not isinstance(record, Formation):
        raise ValueError(f"formation: {record!r} is not a Formation record")
    return FORMATIONS.register(record, replace)


def unregister_formation(name: str) -> None:
    """Remove the formation ``name``."""
    FORMATIONS.unregister(name)
