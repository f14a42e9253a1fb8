"""Crowds in the headless job (scripts/render_job.py, :mod:`.job`): ``[[crowds]]`` tables, each a
formation of figures around a leader, and a shot of each crowd.

A crowd is a leader (``[crowds.leader]``, a figure table like ``[[figures]]``, on the
parametric controller) and the followers :func:`blender_turning.crowd.follow_leader` makes from
it: ``count`` of them, follower ``i`` ``i * gap_m`` behind the leader along its mean heading
(``gap_s``: that long at the leader's speed), ``lateral_m`` to its left (a number, or a list
cycled over the followers), with small random differences of body (``body_jitter``: ``m``,
``l``, ``I_v``), start (``timing_jitter_s``) and turn period (``period_jitter``) drawn from
``seed``.  Every member is an ordinary figure of the job: its own rig, baked by the same
operator as the others, on the leader's ground.

The followers are staged as Blender's Add Crowd stages them (:func:`blender_turning.crowd.stage`,
docs/crowds.md): with ``staging = "along_track"`` (the default) each figure moves from frame 1,
a follower's time behind the leader becoming a distance behind it along the leader's mean
heading (``gap_s`` x the leader's speed, the timing jitter likewise), at the leader's phase; with
``staging = "wait"`` each follower waits at the leader's start until its time, and the shot's
``seconds`` must let the last one start.
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ...core.physics.params import preset
from ...core.registry import SPORTS
from ...crowd import STAGINGS, CrowdFigure, Turns, stage
from ...crowd.formations import FORMATIONS
from ...crowd.registry import FormationRefused
from .terrain import follow_target, key_locations, tracking_camera

#: A crowd's own keys; its formation's keys are the formation record's (crowd/registry.py).
KNOWN = {"name", "formation", "leader", "followers", "count", "shot", "staging"}
#: What ``[crowds.followers]`` may set differently from the leader: how they brake (an
#: instructor skids while the pupils behind snowplough, docs/skidding.md).
FOLLOWER_KEYS = {"style", "target_speed", "stop_s"}


def _led_formations() -> tuple:
    """The registered formations made from a leader (the job's crowds have one)."""
    return tuple(n for n, r in FORMATIONS.items() if r.template == "leader")


def read_crowds(top, figures: list, paths, obstacles, terrains, read_figure,
                seconds: float | None = None) -> list:
    """Read the ``[[crowds]]`` of the config ``top``; append every member (leader first) to
    ``figures`` as a figure dict with ``crowd`` set to the crowd's name; return the crowds
    ``[{"name", "members", "shot"}]``.  ``read_figure`` reads and checks the leader's table as
    a ``[[figures]]`` one; ``seconds``, the shot's length, is checked against a waiting crowd's
    last start."""
    crowds = []
    known = KNOWN.union(*(FORMATIONS[n].keys for n in _led_formations()))
    for c in top.tables("crowds", known):
        name = c.string("name", f"Crowd {len(crowds) + 1}")
        if not name.strip() or any(ch in name for ch in "/\\\0") or name.startswith("."):
            c.fail("name", f"= {name!r} is not a plain name (it names the shot's folder)")
        if any(name == k["name"] for k in crowds):
            c.fail("name", f"= {name!r} is the name of an earlier crowd")
        kind = c.string("formation", "follow_leader", choices=_led_formations())
        record = FORMATIONS[kind]
        c.only(KNOWN | record.keys)
        lead = read_figure(c.table("leader", required=True), figures, paths, obstacles,
                           terrains)
        if lead["control"] != "turns":
            c.fail("leader.control", f"= {lead['control']!r}: a crowd's leader turns on the "
                                     "parametric controller ('turns')")
        c.number("count", "job_crowd_count")            # a job bakes every member: fewer
        leader = _leader(lead)
        try:
            followers = record.read(c, leader, 0, f"{name} ")
        except FormationRefused as exc:           # e.g. a timing jitter over half the gap
            c.fail("formation", f"{kind}: {exc}")
        staging = c.string("staging", "along_track", choices=STAGINGS)
        heading = lead["heading_deg"] if lead["heading_deg"] is not None \
            else lead["direction_deg"]
        followers = stage(leader, followers, math.radians(heading), staging)
        last = max(f.time_offset for f in followers)
        if seconds is not None and last >= seconds:
            c.fail("staging", f"= 'wait': the last follower starts at {last:.2f} s, not before "
                              f"the shot ends (job.seconds = {seconds:g}); give the shot more "
                              "seconds or stage the crowd 'along_track'")
        own = _follower_settings(c.table("followers", FOLLOWER_KEYS), lead)
        members = [dict(lead, crowd=name)]
        for f in followers:
            if any(f.name == g["name"] for g in figures + members):
                c.fail("name", f"= {name!r}: its follower {f.name!r} has the name of another "
                               "figure")
            members.append(dict(_member(lead, f, name), **own))
        figures.extend(members)
        crowds.append({"name": name, "members": [m["name"] for m in members],
                       "shot": c.boolean("shot", True)})
    return crowds


def _follower_settings(t, lead) -> dict:
    """``[crowds.followers]``: the followers' own style, target speed and stop (checked as a
    figure's, against the leader's sport); the keys not given are the leader's."""
    out = {}
    if t.has("style"):
        out["style"] = t.string("style", choices=SPORTS[lead["sport"]].styles)
    if t.has("target_speed"):
        out["target_speed"] = t.number("target_speed", "target_speed")
    if t.has("stop_s"):
        out["stop_s"] = t.number("stop_s", "stop_at")
    return out


def _leader(lead) -> CrowdFigure:
    """The leader as the core's crowd figure: its sport's body at its speed, its turns."""
    fig = preset(lead["sport"])
    if lead["speed"] is not None:
        fig = replace(fig, body=replace(fig.body, V_cm=lead["speed"]))
    heading = lead["heading_deg"]
    return CrowdFigure(lead["name"], fig, Turns(lead["period"], math.radians(lead["lean_deg"]),
                                               None if heading is None
                                               else math.radians(heading)),
                       position=lead["start"])


def _member(lead: dict, f: CrowdFigure, crowd: str) -> dict:
    """A staged follower as a figure of the job: the leader's settings, its own start, start
    offset, period and body."""
    b = f.figure.body
    return dict(lead, name=f.name, start=tuple(f.position), time_offset=f.time_offset,
                period=f.controller.period, body={"mass": b.m, "com_height": b.l,
                                                  "inertia": b.I_v}, crowd=crowd)


def make_crowd_cameras(bpy, crowds, figures, distance, height, lens):
    """One camera per crowd with ``shot``, framing the leader and the school from ahead and to
    the side (downhill of them, looking back up the line) as they come down; returns
    ``[(crowd name, camera)]``.  ``distance`` and ``height`` are the single figures' (the
    config's camera): the crowd's camera stands back by the line's length as well."""
    from .. import compat
    scene = bpy.context.scene
    frames = np.arange(scene.frame_start, scene.frame_end + 1)
    by_name = {o.name: o for o in figures}
    out = []
    for crowd in crowds:
        if not crowd["shot"]:
            continue
        locs = np.array([key_locations(compat, by_name[n], frames) for n in crowd["members"]])
        lead = locs[0]
        # The aim point: the middle of the school, a little towards the leader.
        target = follow_target(bpy, f"Camera Target {crowd['name']}",
                               0.1 * lead + 0.9 * locs.mean(axis=0), frames)
        d = lead[-1, :2] - lead[0, :2]
        d = d / np.linalg.norm(d) if np.linalg.norm(d) > 1e-6 else np.array([0.0, 1.0])
        side = np.array([-d[1], d[0]])
        # The line's length (the leader to the farthest follower, along the heading) at the
        # start: the camera stands back by part of it, ahead of the leader and to the side, so
        # the whole school is in the picture, the leader nearest.
        length = float(np.max(np.abs((locs[:, 0, :2] - lead[0, :2]) @ d)))
        reach = distance + 0.7 * length
        offset = 0.5 * reach * d + 0.85 * reach * side
        out.append((crowd["name"], tracking_camera(bpy, f"Camera {crowd['name']}", lens,
                                                   (offset[0], offset[1],
                                                    height + 0.1 * length), target)))
    return out
