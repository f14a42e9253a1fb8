"""Crowds: many figures in one shot, as data; formations that generate them from a
seed; a runner that batches the parametric figures and fans path planning out per figure to
local processes or a Dask cluster.  numpy and the standard library only (Dask is optional)."""
from .formations import follow_leader, offset_path, peloton, point_at_distance, synchronized
from .model import Crowd, CrowdFigure, FollowPath, Turns
from ..core.course.moving import MovingBodies, closest_approach
from .poses import map_crowd
from .reader import crowd_from_dict, load_crowd
from .runner import CrowdResult, FigureResult, crowd_tasks, run_crowd, run_task
from .staging import STAGINGS, shot_length, stage

__all__ = ["Crowd", "CrowdFigure", "FollowPath", "Turns", "follow_leader", "synchronized",
           "peloton", "offset_path", "point_at_distance", "load_crowd", "crowd_from_dict",
           "CrowdResult", "FigureResult", "run_crowd", "crowd_tasks", "run_task",
           "MovingBodies", "closest_approach", "map_crowd", "STAGINGS", "stage", "shot_length"]
