"""The paper's figures regenerated as PNGs (matplotlib, an optional extra, is imported here only).

``FIGURES`` maps a file stem to ``(module, function)``; each function takes the output
directory and writes ``<stem>.png``.  Modules are imported lazily so a missing one (or missing
matplotlib) fails only the figures that need it.
"""
from __future__ import annotations

FIGURES = {
    "fig03_phase_diagram": ("parametric", "fig03"),
    "fig05_typical_turn": ("parametric", "fig05"),
    "fig06_tracks": ("parametric", "fig06"),
    "fig10_parametric_tracks": ("parametric", "fig10"),
    "fig16_tree_skiing": ("planner", "fig16"),
    "fig17_slalom": ("planner", "fig17"),
    "fig18_cyclist_corner": ("planner", "fig18"),
    "photo5_potholes": ("planner", "photo5"),
    "crowd_ski_school": ("crowd", "ski_school"),
    "crowd_peloton": ("crowd", "peloton"),
}
