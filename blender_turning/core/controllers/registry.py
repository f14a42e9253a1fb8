"""One record per controller (docs/registry.md): how the command line (and any reader that offers
a choice of controller) names, describes and makes it.

A :class:`ControllerType` says what the controller is called and how to make it for a figure from
the turn parameters of Section 5 (``omega0``, ``theta_max``, the heading ``theta_h``; each a
number or a schedule), and where a run starts (on the turning ellipse or straight ahead).  The
built-ins register at the end of their own modules; a user's own controller is one module that
defines a :class:`.base.Controller` and calls :func:`register_controller`.  Standard library only.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from ..registry import Registry

__all__ = ["ControllerType", "CONTROLLERS", "STARTS", "register_controller",
           "unregister_controller"]

#: Where a run under the controller starts: ``ellipse``: on the turning ellipse, centred on the
#: heading (``slalom_start``); ``straight``: upright, on the heading.
STARTS = ("ellipse", "straight")


@dataclass(frozen=True, eq=False)
class ControllerType:
    """A controller: one record, registered once (:func:`register_controller`)."""

    name: str
    """The command line's ``--controller`` (``"ellipse"``)."""
    label: str
    """A short name for menus."""
    description: str
    """What it does, with the paper's section."""
    make: Callable
    """``make(figure, omega0, theta_max, heading, law) -> Controller``: ``figure`` the core
    :class:`..params.Figure`, ``omega0``/``theta_max``/``heading`` schedules (callables of time),
    ``law`` the phase-ellipse law's name (``"smooth"``/``"paper"``, for those that have one)."""
    start: str = "ellipse"
    """One of :data:`STARTS`."""

    def __post_init__(self):
        for name in ("label", "description"):
            if not isinstance(getattr(self, name), str) or not getattr(self, name).strip():
                raise ValueError(f"controller {self.name!r}: {name} = {getattr(self, name)!r} "
                                 "is not a non-empty string")
        if not callable(self.make):
            raise ValueError(f"controller {self.name!r}: make is not callable")
        if self.start not in STARTS:
            raise ValueError(f"controller {self.name!r}: start = {self.start!r} is not one of "
                             f"{', '.join(STARTS)}")


#: The controllers, registered by their modules.
CONTROLLERS = Registry("controller")


def register_controller(record: ControllerType, replace: bool = False) -> ControllerType:
    """Register ``record`` (a name already taken is refused unless ``replace``)."""
    if not isinstance(record, ControllerType):
        raise ValueError(f"controller: {record!r} is not a ControllerType record")
    return CONTROLLERS.register(record, replace)


def unregister_controller(name: str) -> None:
    """Remove the controller ``name``."""
    CONTROLLERS.unregister(name)
