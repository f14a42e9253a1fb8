"""The physics and control core: numpy and the standard library only (no bpy, no mathutils)."""
from .controllers import CONTROLLERS, OpenLoop, PhaseEllipse, Straight
from .errors import FellOver, RunEnded, TurningError
from .physics.model import RESISTANCE, Flat, HeightField, Plane, Resistance
from .physics.params import PRESETS, BodyParams, Figure, Limits, preset
from .controllers.schedule import Schedule, TurnSchedule, read_schedule_csv
from .physics.simulate import DEFAULT_DT, run, simulate, slalom_start
from .controllers.braking import TargetSpeed
from .physics.trajectory import COLUMNS, Trajectory

__all__ = ["CONTROLLERS", "OpenLoop", "PhaseEllipse", "Straight", "TargetSpeed", "FellOver",
           "RunEnded", "TurningError", "Flat", "Plane", "HeightField", "Resistance", "RESISTANCE",
           "PRESETS", "BodyParams", "Figure", "Limits", "preset", "Schedule", "TurnSchedule",
           "read_schedule_csv", "DEFAULT_DT", "run", "simulate", "slalom_start", "COLUMNS",
           "Trajectory"]
