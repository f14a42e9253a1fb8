"""Bake Turns as a job: the figures (by name) computed one at a time, nothing written, then all
written at once, so that a failure or Esc between figures leaves the scene as it was.  What
``turning.bake_turns`` runs (modal or not) and what the bake benchmarks time."""
from __future__ import annotations

import bpy

from ...mapping.keys import KeyTolerance
from ..anim import bake
from ..anim import export_ready as export_ready_mod
from ..anim.figure_bake import BakeWriter, write_bakes
from ..scene.figure_context import check_figure
from ..scene.scene_adapters import FrameRange, start_from_object
from .pipeline import figure_pose_track, ground_of


class BakeJob:
    """Bake figures (by name) over ``frames``: :meth:`compute_next` one at a time (nothing is
    written), then :meth:`write` all of them."""

    def __init__(self, names, frames: FrameRange, step: int = 1, export_ready: bool = True,
                 root_motion: bool = False, fewer_keys: KeyTolerance | None = None,
                 export_turn_state: bool = False, share: bool = True):
        self.names, self.frames, self.step = list(names), frames, step
        self.export_ready, self.root_motion = export_ready, root_motion
        self.export_turn_state = export_turn_state
        self.fewer_keys = fewer_keys              # None: a key on every (step-th) frame
        self.share = share                    # figures with another's motion play its bake
        self.key_reports = {}                 # name -> fewer_keys.KeyReport
        self.shared = {}                      # name -> the figure whose bake it plays
        self.stash_notes = {}                 # name -> a user's action the bake stashed
        self.results = []                     # (name, start or None, traj, track)
        self.grounds = {}                     # ground mesh name -> MeshGround

    @property
    def done(self) -> bool:
        return len(self.results) == len(self.names)

    @property
    def current(self) -> str:
        """The figure :meth:`compute_next` works on."""
        return self.names[min(len(self.results), len(self.names) - 1)]

    def compute_next(self) -> None:
        """Simulate and map the next figure (raises ``ValueError`` or ``TurningError``)."""
        name = self.current
        fig = bpy.data.objects.get(name)
        if fig is None:
            raise ValueError("the figure was deleted while baking")
        check_figure(fig)
        # Not baked yet: start where the user put the figure; baked: from its Start settings.
        start = start_from_object(fig) if bake.figure_action(fig) is None else None
        height = None if start is None else float(fig.location[2])
        traj, track = figure_pose_track(fig, self.frames, start=start, height=height,
                                        ground=self._ground(fig))
        if self.root_motion:
            track = export_ready_mod.root_motion(fig, track)
        bake.check_track(fig, track)
        self.results.append((name, start, traj, track))

    def _ground(self, fig):
        """The figure's Ground mesh, read once per job for all figures on it."""
        mesh = fig.turning.ground
        if mesh is None:
            return None
        if mesh.name not in self.grounds:
            self.grounds[mesh.name] = ground_of(fig)
        return self.grounds[mesh.name]

    def write(self) -> list:
        """Write every computed figure (:func:`.figure_bake.write_bakes`: a figure with
        another's motion plays its bake); ``[(name, BakeResult)]``."""
        figs = [bpy.data.objects[name] for name, *_ in self.results]
        for fig, (_, start, _, _) in zip(figs, self.results):
            if start is not None:                 # the height where the user put it stays
                fig.turning.start = (start[0], start[1], float(fig.location[2]))
                fig.turning.start_heading = start[2]
        writer = BakeWriter(self.step, self.export_ready, self.export_turn_state,
                            self.fewer_keys, self.share)
        written = write_bakes(figs, [r[2] for r in self.results], [r[3] for r in self.results],
                              writer)
        self.key_reports, self.shared = writer.key_reports, writer.shared
        self.stash_notes = writer.stash_notes
        return [(r[0], w) for r, w in zip(self.results, written)]
