"""Steering controllers, by the names the CLI and the add-on use."""
from .base import Controller
from .ellipse import PhaseEllipse, ellipse_alpha
from .feasible import FeasibleTurn
from .open_loop import OpenLoop
from .straight import Straight

CONTROLLERS = {"open-loop": OpenLoop, "ellipse": PhaseEllipse, "straight": Straight}

__all__ = ["Controller", "OpenLoop", "PhaseEllipse", "ellipse_alpha", "FeasibleTurn", "Straight",
           "CONTROLLERS"]
