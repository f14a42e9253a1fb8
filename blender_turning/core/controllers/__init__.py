"""Steering controllers, by the names the CLI and the add-on use."""
from .base import Controller
from .ellipse import PhaseEllipse, ellipse_alpha
from .feasible import FeasibleTurn
from .open_loop import OpenLoop

CONTROLLERS = {"open-loop": OpenLoop, "ellipse": PhaseEllipse}

__all__ = ["Controller", "OpenLoop", "PhaseEllipse", "ellipse_alpha", "FeasibleTurn",
           "CONTROLLERS"]
