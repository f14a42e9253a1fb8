"""Crowds in the scene: a template figure as the core's crowd member, a formation's
members back as figures (linked duplicates of the template), their paths as curve objects.

The formation itself is the core's (:mod:`..crowd.formations`): this module only translates.
A figure becomes a :class:`~..crowd.CrowdFigure` with its body and limits, its turns (period,
lean, heading) or its path (the scene Follow Path plans), its start and its start offset; each
member the formation makes is written back as a duplicate of the template with the member's
body, turn period, start, first turn, start offset and path.

Duplicates are linked (Alt+D): each figure has its own object, pose, settings and bake, and
shares the template's armature, mesh and equipment data, so a crowd of a hundred costs a hundred
objects, not a hundred meshes.  Children (the body, a user's character mesh) and a user rig's
equipment collection are duplicated with it, their parents, modifiers, constraints and drivers
pointed at the new figure.  A template that is baked gives figures without its bake (each bakes
its own); an action of the user's (keyed settings) is shared.
"""
from __future__ import annotations

import bpy

from ...core.course.path import HermitePath
from ...crowd import CrowdFigure, FollowPath, Turns
from ..anim import bake
from . import retarget_adapter
from ..anim.export_state import CARRIES
from ..anim.foot_track import OWNER as FOOT_TRACK_OWNER
from .figure_context import CROWD_TAG
from .scene_adapters import figure_from_settings
from ..anim.user_action import REST, STASHED


def template_member(context, fig, path: bool) -> CrowdFigure:
    """The core's crowd member of the figure ``fig``: with ``path``, the scene Follow Path
    plans for it (:func:`.follow_scene.prepare`); else its turns (Section 5) from its Start.
    Raises ``ValueError`` naming the bad setting."""
    s = fig.turning
    offset = float(s.crowd.time_offset)
    if path:
        from ..jobs.crowd_job import figure_scene
        from .follow_scene import prepare
        job = prepare(context, fig)
        return CrowdFigure("m", job.figure, FollowPath(figure_scene("m", job)),
                           time_offset=offset)
    turns = Turns(float(s.period), float(s.lean), float(s.heading) if s.use_heading else None)
    return CrowdFigure("m", figure_from_settings(s), turns, (float(s.start[0]), float(s.start[1])),
                       s.crowd.first_turn.lower(), offset)


# -- paths ------------------------------------------------------------------------------------

def path_from(path: HermitePath, s_along: float = 0.0) -> HermitePath:
    """``path`` from ``s_along`` m along it (:meth:`~..core.course.path.HermitePath.split`),
    starting at the point the core's formation starts the figure
    (:func:`..crowd.formations.point_at_distance`, on 64 chords a segment)."""
    if s_along <= 0.0:
        return path
    if s_along >= path.length():
        raise ValueError(f"{s_along:g} m along the path is beyond its length "
                         f"({path.length():.1f} m)")
    return path.split(s_along)[1]


def curve_object(path: HermitePath, name: str, z: float, collection):
    """A Bezier curve object through ``path`` (world coordinates, at height ``z``): the knots
    with handles a third of the Hermite tangents away, which is exactly the same curve
    (:meth:`~..core.course.path.HermitePath.from_bezier` reads it back)."""
    curve = bpy.data.curves.new(name, "CURVE")
    curve.dimensions = "3D"
    sp = curve.splines.new("BEZIER")
    n = len(path.knots)
    sp.bezier_points.add(n - 1)
    for k, bp in enumerate(sp.bezier_points):
        bp.handle_left_type = bp.handle_right_type = "FREE"
        bp.co = (*path.knots[k], z)
        t_in = path.t_in[k - 1] if k > 0 else path.t_out[0]
        t_out = path.t_out[k] if k < n - 1 else path.t_in[n - 2]
        bp.handle_left = (*(path.knots[k] - t_in / 3.0), z)
        bp.handle_right = (*(path.knots[k] + t_out / 3.0), z)
    obj = bpy.data.objects.new(name, curve)
    collection.objects.link(obj)
    return obj


# -- figures ----------------------------------------------------------------------------------

def _retarget(obj, made: dict) -> None:
    """Point ``obj``'s parent, modifiers, constraints and drivers at the copies in ``made``."""
    if obj.parent in made:
        obj.parent = made[obj.parent]
    for mod in getattr(obj, "modifiers", ()):
        if getattr(mod, "object", None) in made:
            mod.object = made[mod.object]
    for con in getattr(obj, "constraints", ()):
        if getattr(con, "target", None) in made:
            con.target = made[con.target]
    adt = obj.animation_data
    for fc in (adt.drivers if adt is not None else ()):
        for var in fc.driver.variables:
            for t in var.targets:
                if t.id in made:
                    t.id = made[t.id]


def duplicate_figure(template, name: str, collection, children=None):
    """A linked duplicate of the figure ``template`` named ``name`` in ``collection``: its
    children and (a user's rig) equipment with it; no bake, no foot track, no state Empties.
    ``children``: the template's ``children_recursive`` when the caller has it (it costs
    O(objects): a crowd takes it once for all its members)."""
    made = {template: template.copy()}
    new = made[template]
    new.name = name
    collection.objects.link(new)
    baked = bake.find_bake(template)[0] is not None
    if baked:                                 # the template's bake is the template's
        new.animation_data_clear()
        for key in (REST, STASHED):
            if key in new.keys():
                del new[key]
    new.turning.foot_track = None
    for child in template.children_recursive if children is None else children:
        if child.get(FOOT_TRACK_OWNER) is not None or CARRIES in child:   # the template's
            continue
        made[child] = child.copy()
        collection.objects.link(made[child])
    equipment = template.turning.rig.equipment if retarget_adapter.is_user_rig(template) \
        else None
    if equipment is not None:
        coll = bpy.data.collections.new(f"{new.name} Equipment")
        collection.children.link(coll)
        for eq in equipment.objects:
            if eq not in made:
                made[eq] = eq.copy()
                coll.objects.link(made[eq])
        new.turning.rig.equipment = coll
    for obj in made.values():
        _retarget(obj, made)
    return new


def place(obj, member: CrowdFigure, template_start, path_obj=None) -> None:
    """Set the figure ``obj`` to the crowd member: body, turn period, start, first turn, start
    offset (and its path curve), and stand it at its start."""
    from ..anim.figure_bake import reset_pose
    s = obj.turning
    body = member.figure.body
    s.mass, s.com_height, s.inertia = body.m, body.l, body.I_v
    s.crowd.time_offset = member.time_offset
    s.crowd.first_turn = member.first_turn.upper()
    z = float(template_start[2])
    if member.is_path:
        x, y, heading = member.state0()[:3]
        s.path = path_obj
    else:
        s.period = member.controller.period
        (x, y), heading = member.position, s.start_heading
    s.start = (x, y, z)
    s.start_heading = heading
    reset_pose(obj)


def set_aside(template) -> None:
    """Hide the template of a formation it is not a member of (a synchronised line, a peloton)
    in the viewport and the render, with its children and (a user's rig) its equipment: a
    pattern, as a crowd file's ``template`` is, not a figure standing among the crowd it made
    (Alt+H shows it again)."""
    equipment = template.turning.rig.equipment if retarget_adapter.is_user_rig(template) \
        else None
    for obj in [template, *template.children_recursive,
                *(equipment.all_objects if equipment is not None else ())]:
        obj.hide_set(True)
        obj.hide_render = True


def new_crowd_collection(context, name: str = "Crowd"):
    coll = bpy.data.collections.new(name)
    coll[CROWD_TAG] = True
    context.scene.collection.children.link(coll)
    return coll


def remove_crowd(coll, keep=None) -> None:
    """Take back a half-made crowd: every object in ``coll`` (but ``keep``, linked in, not
    made) and the collections."""
    for obj in [o for o in coll.all_objects if o is not keep]:
        bpy.data.objects.remove(obj)
    for child in list(coll.children_recursive):
        bpy.data.collections.remove(child)
    bpy.data.collections.remove(coll)
