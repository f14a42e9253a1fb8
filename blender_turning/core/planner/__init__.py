"""Path-following control (Section 6): branch-and-bound planning over dC_f/dt around obstacles,
applied with a receding horizon.  Plain arrays in (path, obstacles), a trajectory out."""
from .problem import Problem, StageResult
from .receding import FollowResult, Replan, follow
from .search import Plan, SearchStats, branch_and_bound, exhaustive
from .settings import PlannerSettings, SpeedProfile

__all__ = ["Problem", "StageResult", "FollowResult", "Replan", "follow", "Plan", "SearchStats",
           "branch_and_bound", "exhaustive", "PlannerSettings", "SpeedProfile"]
