"""Steering controllers, by the names the CLI and the add-on use: ``CONTROLLERS`` is the registry
of their records (:mod:`.registry`), each registered at the end of its own module.  The folder
also holds what they steer by: the phase and the lean law, the heading table, schedules over
time, braking by turning and the presets' speed habits."""
from .base import Controller
from .ellipse import PhaseEllipse, ellipse_alpha
from .feasible import FeasibleTurn
from .open_loop import OpenLoop
from .registry import CONTROLLERS, ControllerType, register_controller, unregister_controller
from .straight import Straight

__all__ = ["Controller", "OpenLoop", "PhaseEllipse", "ellipse_alpha", "FeasibleTurn", "Straight",
           "CONTROLLERS", "ControllerType", "register_controller", "unregister_controller"]
