"""Blender enum items built from the registries (docs/registry.md): the Sport and Formation
enums, the Add menu and the presets menu list what is registered when they are drawn, so a sport
or formation registered after the add-on (a script, another add-on) shows up without
re-registering anything.

The items carry each record's fixed ``number`` (what a .blend file stores for an enum), so the
built-ins keep the values files saved before were written with.  Blender keeps pointers to the
strings of the items a callback returns: every list built is kept alive here (a few per
registry change).
"""
from __future__ import annotations

from ..core.registry import SPORTS
from ..crowd.formations import FORMATIONS

_BUILT: dict = {}          # (kind, registry version) -> items
_KEEP: list = []           # every items list handed to Blender, kept alive


def _items(kind: str, registry, build) -> list:
    key = (kind, registry.version)
    items = _BUILT.get(key)
    if items is None:
        items = build()
        _BUILT[key] = items
        _KEEP.append(items)
    return items


def sport_items(self=None, context=None) -> list:
    """``(identifier, label, description, icon, number)`` of every registered sport."""
    return _items("sport", SPORTS, lambda: [
        (s.key, s.label, s.description, s.icon, s.number) for s in SPORTS.values()])


def retargeted_sport_items(self=None, context=None) -> list:
    """The sports that go onto a user's own rig (their record has ``retarget``)."""
    return _items("retarget", SPORTS, lambda: [
        (s.key, s.label, s.description, s.icon, s.number) for s in SPORTS.values()
        if s.retarget is not None])


def formation_items(self=None, context=None) -> list:
    """``(identifier, label, description, icon, number)`` of every registered formation."""
    return _items("formation", FORMATIONS, lambda: [
        (f.key, f.label, f.description, f.icon, f.number) for f in FORMATIONS.values()])


def sport_label(sport: str) -> str:
    """The label of the sport ``sport`` (``'SKIER'`` or ``'skier'``); an unknown one's title."""
    record = SPORTS.get(sport.lower()) if isinstance(sport, str) else None
    return record.label if record is not None else str(sport).title()
