"""Retargeting: the built-in figure's motion on the user's own rig.  numpy only.

The built-in figure's mapping (Section 7) gives a :class:`~.base.PoseTrack` for its own rig
(``rigs/<sport>.json``).  :func:`retarget` carries it onto a :class:`~.user_rig.UserRig` (the
user's armature at rest, read by the Blender side) through a :class:`~.bone_map.BoneMap`:

* **Frames** (:func:`~.user_rig.fit_rig`).  The user's rig is measured, never assumed: its
  facing is ``left x up`` with ``left`` from the right hip joint to the left one (Blender
  characters face -Y, the built-in rigs +Y, the built-in snowboarder stands side-on facing +X,
  measured the same way); its size ``k`` is its leg length (hip joint to knee to ankle, world
  metres) over the built-in's.  A built-in armature-space point ``p`` goes to
  ``origin + (k / s) C p`` in the user's armature space (``C`` turns the built-in's facing onto
  the user's, ``s`` is the object's scale, ``origin`` the ankles' midpoint on ``z = 0``).
  Scaling the pose by ``k`` about the foot point keeps every angle (lean, knee bend, ski tilt)
  and the equipment on the ground; the trajectory (where the foot point goes) is not scaled.
* **Orientations.**  Each joint's world orientation relative to its rest carries over through
  the rest-pose difference of the two skeletons: ``R_user = D_builtin A R_user_rest`` with
  ``D_builtin`` the built-in bone's rotation from its rest (in the user's axes) and ``A`` the
  fixed rotation taking the user's rest segment (joint to next joint) onto the built-in's (a
  T-pose arm onto the built-in's hanging arm).  The feet keep ``A = I`` (both rigs stand flat).
* **Positions.**  Each ankle goes exactly on the built-in's (two-bone IK, the knee towards the
  same side as the built-in's); the hip joints' midpoint on the built-in's line from the ankles'
  midpoint to its hip joints, drawn from the user's ankles (so the body's lean is the
  built-in's), as far along it as bends the user's knees as much as the built-in's (thighs and
  shins of other proportions need another hip height for the same bend: an angle carries over,
  not a length).  The telemark skier (``ANCHOR``) puts the ball of each foot on the built-in's
  instead and turns each foot about it until that knee bends as the built-in's (the two legs
  differ too much for one pelvis); the cyclist (``SEATED``) keeps the hips where the
  built-in's are, on the saddle.  Wrists reach the built-in's by IK; the rest is carried.
* **Equipment** (:func:`.equipment.equipment_rest`) is rigid with its joint (``ATTACH``), placed
  at rest as on the built-in through the same ``A``: a ski under its foot lands exactly on the
  built-in's ski.  A pole is rigid in the hand, so the hand turns as the built-in's pole does
  and the wrist goes where that puts the grip on the built-in's: the pole lies where the
  built-in's lies, and the plants, planned for the user's size (``SkierOptions.plant_scale``),
  stay in their holes.  Where the arm falls short the hand turns the pole at the built-in's
  tip, so the tip rises along that line.
* **Stance** (:mod:`.stance`): a goofy snowboarder is the mirror image of the regular
  built-in on the mirrored run (``mirror=True``).
* **Channels.**  For a rig with controls (Rigify) the bake keys the controls, each moving rigidly
  with its joint (``bone_map.Control``); otherwise the mapped bones (FK) and, on the object, the
  root motion.  A bone's parent frame is taken to move rigidly with the nearest mapped joint
  above it (bones between stay at rest), and Blender's ``use_local_location = False`` (location
  in the parent's orientation) is honoured.
"""
from __future__ import annotations

import math

import numpy as np

from .. import bones as B
from ..base import BoneChannels, PoseTrack
from .bone_map import JOINT_PARENT, JOINTS, BoneMap
from ..sports.common import rot_z
from ..kinematics import (cross, on_sphere_within, quat_continuous, quat_from_matrix,
                          rigid_inverse, stack_dot, two_bone_ik)
from ...core.registry import SPORTS
from .stance import MirroredSkeleton, builtin_skeleton, mirror_poses, unmirror_props
from ..surface import euler_xyz
from .user_rig import RigFit, UserRig, fit_rig

__all__ = ["retarget", "path_length", "solve_joints", "swing", "ATTACH", "TRACKS", "SPIN",
           "SLIDE", "SEATED", "ANCHOR"]

# Each sport's retargeting data is its record's ``retarget`` (:class:`..core.sports.Retarget`);
# these are live views of the sport registry, by sport.
_HAS = (lambda s: s.retarget is not None)
#: Equipment bone of the built-in rig -> the joint it is rigid with on the user's rig.
ATTACH = SPORTS.view(lambda s: s.retarget.attach, _HAS)
#: Equipment that turns about its own axle to face another piece (Blender: Damped Track): the
#: crank follows the pedals round the crank circle.
TRACKS = SPORTS.view(lambda s: s.retarget.tracks, lambda s: _HAS(s) and s.retarget.tracks)
#: Equipment that rolls with the distance travelled (about its own Y axis, the axle): no bone of
#: the rider turns with it, so the bake keys the distance as ``turn_distance`` on the armature
#: and a driver turns the piece (:attr:`.equipment.EquipmentPiece.spin`).
SPIN = SPORTS.view(lambda s: s.retarget.spin, lambda s: _HAS(s) and s.retarget.spin)
#: Equipment that slides along another piece's own Y axis, by the distance the bake keys as a
#: state property (m, of the user's figure): the front wheel along the fork, which keeps the
#: steered and leaned tyre on the ground (:mod:`.cyclist`); a driver moves the piece.
SLIDE = SPORTS.view(lambda s: s.retarget.slide, lambda s: _HAS(s) and s.retarget.slide)
#: Sports where the pelvis sits on the equipment (the saddle): it goes exactly where the
#: built-in's goes, the knees bend as the pedals ask.
SEATED = SPORTS.view(lambda s: True, lambda s: _HAS(s) and s.retarget.seated)
#: Where a foot meets its equipment, when not at the ankle: the leg's IK puts that joint's head
#: exactly on the built-in's (the telemark's ball of the foot, which stays on the ski).
ANCHOR = SPORTS.view(lambda s: s.retarget.anchor, lambda s: _HAS(s) and s.retarget.anchor)
#: The next joint down a chain: a joint's rest "segment" runs from its head to this one's head.
CHAIN_CHILD = {B.HIPS: (B.SPINE, B.SPINE_2, B.CHEST), B.SPINE: (B.SPINE_2, B.CHEST),
               B.SPINE_2: (B.CHEST,), B.CHEST: (B.NECK, B.HEAD), B.NECK: (B.NECK_2, B.HEAD),
               B.NECK_2: (B.HEAD,)}
for _s in ("L", "R"):
    CHAIN_CHILD.update({B.side(a, _s): (B.side(b, _s),) for a, b in (
        ("shoulder", "upper_arm"), ("upper_arm", "forearm"), ("forearm", "hand"),
        ("thigh", "shin"), ("shin", "foot"))})
FLAT = {B.side(b, s) for b in ("foot", "toe") for s in ("L", "R")}     # A = I: stand flat
#: The share of the arm's length the wrist is put within when the pole turns about its tip (the
#: IK reaches 0.9999 of it, :func:`..kinematics.two_bone_ik`).
REACH = 0.999


def _unit(v):
    v = np.asarray(v, float)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def swing(a, b) -> np.ndarray:
    """(..., 3, 3) the smallest rotation taking direction ``a`` onto ``b`` (Rodrigues)."""
    a, b = np.broadcast_arrays(_unit(a), _unit(b))
    v = cross(a, b)
    c = np.sum(a * b, axis=-1)
    vx = np.zeros(a.shape + (3,))
    vx[..., 0, 1], vx[..., 0, 2], vx[..., 1, 2] = -v[..., 2], v[..., 1], -v[..., 0]
    vx[..., 1, 0], vx[..., 2, 0], vx[..., 2, 1] = v[..., 2], -v[..., 1], v[..., 0]
    eye = np.broadcast_to(np.eye(3), vx.shape)
    opp = c < -1.0 + 1e-9
    out = eye + vx + vx @ vx / np.where(opp, 1.0, 1.0 + c)[..., None, None]
    # Opposite directions: half a turn about any axis across a.
    if np.any(opp):
        ax = np.cross(a[opp], [1.0, 0.0, 0.0])
        ax[np.linalg.norm(ax, axis=-1) < 1e-6] = np.cross(a[opp], [0.0, 1.0, 0.0])[
            np.linalg.norm(ax, axis=-1) < 1e-6]
        ax = _unit(ax)
        out[opp] = 2.0 * ax[..., :, None] * ax[..., None, :] - np.eye(3)
    return out


def _matrix_xyz(euler) -> np.ndarray:
    """(n, 3, 3) Blender's Euler XYZ rotations ``Rz(c) Ry(b) Rx(a)`` of ``euler`` (n, 3)."""
    a, b, c = np.asarray(euler, float).T
    Rx, Ry = np.tile(np.eye(3), (2, len(a), 1, 1))
    Rx[:, 1, 1], Rx[:, 1, 2], Rx[:, 2, 1], Rx[:, 2, 2] = np.cos(a), -np.sin(a), np.sin(a), np.cos(a)
    Ry[:, 0, 0], Ry[:, 0, 2], Ry[:, 2, 0], Ry[:, 2, 2] = np.cos(b), np.sin(b), -np.sin(b), np.cos(b)
    return rot_z(c) @ Ry @ Rx


def _mapped(bm: BoneMap, rig: UserRig, joint: str):
    bone = bm.bone(joint)
    return bone if bone is not None and bone in rig._index else None


def _parent_joint(bm, rig, joint):
    p = JOINT_PARENT[joint]
    while p is not None and _mapped(bm, rig, p) is None:
        p = JOINT_PARENT[p]
    return p


def _chain_child(bm, rig, joint):
    for c in CHAIN_CHILD.get(joint, ()):
        if _mapped(bm, rig, c) is not None:
            return c
    return None


class _Builtin:
    """The built-in figure's posed bones (armature space) with its rest, in the user's axes."""

    def __init__(self, sport, track, fit, mirror=False):
        skel = builtin_skeleton(sport)
        self.n = len(track)
        self.P = skel.fk(track.bones, self.n)
        if mirror:
            self.P = mirror_poses(self.P)
        self.skel = MirroredSkeleton(skel) if mirror else skel
        self.fit = fit

    def delta(self, bone):
        """(n, 3, 3) the bone's rotation from rest, in the user's axes."""
        C = self.fit.C
        D = stack_dot(self.P[bone][:, :3, :3], self.skel.rest_of(bone)[:3, :3].T @ C.T)
        return np.swapaxes(stack_dot(np.swapaxes(D, 1, 2), C.T), 1, 2)     # C D C^T

    def head(self, bone):
        """(n, 3) the posed head, in the user's armature space."""
        return self.fit.point(self.P[bone][:, :3, 3])

    def rest_vec(self, a, b):
        """The rest vector from ``a``'s head to ``b``'s head, in the user's axes (built-in m)."""
        return self.fit.C @ (self.skel.rest_of(b)[:3, 3] - self.skel.rest_of(a)[:3, 3])


def _rest_differences(bm, rig, skel, fit, joints) -> dict:
    """``A`` of each of ``joints``: the rotation taking the user's rest segment of the joint (to
    the next mapped joint down its chain, or the bone's Y) onto the built-in's (``skel``), in
    the user's axes; all in one :func:`swing`."""
    out, pairs = {}, {}
    for joint in joints:
        if joint in FLAT:
            out[joint] = np.eye(3)
            continue
        u_rest = rig.rest_of(bm.bone(joint))
        child = _chain_child(bm, rig, joint)
        if child is None:
            pairs[joint] = (u_rest[:3, 1], fit.C @ skel.rest_of(joint)[:3, 1])
        else:
            pairs[joint] = (rig.head(bm.bone(child)) - u_rest[:3, 3],
                            fit.C @ (skel.rest_of(child)[:3, 3] - skel.rest_of(joint)[:3, 3]))
    if pairs:
        turns = swing(np.array([a for a, _ in pairs.values()]),
                      np.array([b for _, b in pairs.values()]))
        out.update(zip(pairs, turns))
    return out


def _rest_difference(bm, rig, skel, fit, joint):
    """``A`` of one joint (:func:`_rest_differences`)."""
    return _rest_differences(bm, rig, skel, fit, (joint,))[joint]


def _pole(bi, upper, lower, end):
    """Where the built-in's middle joint bends (n, 3): off the upper-to-end line, user axes."""
    root, mid, tip = (bi.P[b][:, :3, 3] for b in (upper, lower, end))
    u = _unit(tip - root)
    off = mid - root
    off = off - np.sum(off * u, axis=-1, keepdims=True) * u
    return off @ bi.fit.C.T


def _ankle_target(bi, rest, rot, sport, s):
    """(n, 3) where the leg's IK puts the user's ankle: on the built-in's, or such that the
    sport's ``ANCHOR`` joint (turning with the foot) lands on the built-in's."""
    foot = f"foot.{s}"
    anchor = ANCHOR.get(sport)
    if anchor is None:
        return bi.head(foot)
    anchor = f"{anchor}.{s}"
    if anchor not in rest:
        raise ValueError(f"a {sport} figure needs joint {anchor!r} (the ball of the foot stays "
                         f"on the ski) in the bone map")
    lever = rest[anchor][:3, 3] - rest[foot][:3, 3]
    turn = rot[foot] @ rest[foot][:3, :3].T
    return bi.head(anchor) - np.einsum("nij,j->ni", turn, lever)


def _knee_distance(bi, rest, s):
    """(n,) the hip-to-ankle distance that bends the user's knee ``s`` as much as the
    built-in's (the law of cosines on the user's thigh and shin; at most 99.9% of its reach)."""
    thigh, shin, foot = (f"{b}.{s}" for b in ("thigh", "shin", "foot"))
    h, k, a = (bi.P[b][:, :3, 3] for b in (thigh, shin, foot))
    cos_bend = np.sum(_unit(k - h) * _unit(a - k), axis=-1)
    l1 = float(np.linalg.norm(rest[shin][:3, 3] - rest[thigh][:3, 3]))
    l2 = float(np.linalg.norm(rest[foot][:3, 3] - rest[shin][:3, 3]))
    return np.sqrt(np.minimum(l1 * l1 + l2 * l2 + 2 * l1 * l2 * cos_bend,
                              (0.999 * (l1 + l2)) ** 2))


def _heel_for_knee(bi, hip, ball, ankle, d, s):
    """Turn the foot about the ball of the foot (``ball``, on the ski) by the angle that puts
    the ankle at distance ``d`` (n,) from the hip joint, so the knee bends as the built-in's
    although the user's foot has other proportions: returns ``(ankle (n, 3), turn (n, 3, 3))``.
    The axis is the built-in's toe's lateral (X) axis; of the two angles the smaller, none
    where no angle reaches ``d``."""
    a = _unit(bi.P[f"toe.{s}"][:, :3, 0] @ bi.fit.C.T)
    v, w = ankle - ball, hip - ball
    aw, av = np.sum(a * w, -1), np.sum(a * v, -1)
    P = np.sum(w * v, -1) - aw * av
    Q = np.sum(w * cross(a, v), -1)
    r = 0.5 * (np.sum(w * w, -1) + np.sum(v * v, -1) - d * d) - aw * av
    amp = np.hypot(P, Q)
    base = np.arctan2(Q, P)
    off = np.arccos(np.clip(r / np.maximum(amp, 1e-12), -1.0, 1.0))
    phi = np.where(np.abs(base - off) < np.abs(base + off), base - off, base + off)
    phi = (phi + np.pi) % (2 * np.pi) - np.pi
    c, sn = np.cos(phi)[:, None, None], np.sin(phi)[:, None, None]
    K = np.zeros(a.shape + (3,))
    K[:, 0, 1], K[:, 0, 2], K[:, 1, 2] = -a[:, 2], a[:, 1], -a[:, 0]
    K[:, 1, 0], K[:, 2, 0], K[:, 2, 1] = a[:, 2], -a[:, 1], a[:, 0]
    turn = np.eye(3) + sn * K + (1 - c) * (K @ K)
    return ball + np.einsum("nij,nj->ni", turn, v), turn


def _knee_slide(bi, rest, DA, hips_b, hips_u, axis, s, ankle):
    """(n,) how far along ``axis`` the hip joints' midpoint must move from ``hips_b`` for the
    user's leg ``s`` to bend its knee as much as the built-in's (:func:`_knee_distance`)."""
    thigh = f"thigh.{s}"
    d = _knee_distance(bi, rest, s)
    w = hips_b + DA @ (rest[thigh][:3, 3] - hips_u) - ankle
    wu = np.sum(w * axis, axis=-1)
    return -wu + np.sqrt(np.maximum(wu * wu - np.sum(w * w, axis=-1) + d * d, 0.0))


def _at_rest(bi: _Builtin, rig: UserRig, bm: BoneMap, sport: str):
    """What :func:`solve_joints` and :func:`retarget` read of the two rigs at rest: the user's
    mapped joints' rest ``{joint: (4, 4)}``, their rest orientations turned by ``A``
    (:func:`_rest_differences`), the rest offset of each from its parent joint's frame
    ``{joint: (parent joint, (4,))}`` and the inverse rests.  Kept on ``rig`` for the bone map
    and fit it was made with (a Live Preview drag retargets onto one read of the rig)."""
    key = (id(bm), id(bi.fit), sport, type(bi.skel).__name__)
    kept = rig._at_rest.get(key)
    if kept is not None and kept[0] is bm and kept[1] is bi.fit:
        return kept[2]
    rest = {j: rig.rest_of(bm.bone(j)) for j in JOINTS if _mapped(bm, rig, j)}
    A = _rest_differences(bm, rig, bi.skel, bi.fit, rest)
    turned = {j: A[j] @ rest[j][:3, :3] for j in rest}
    carry = {}
    for j in rest:
        pj = _parent_joint(bm, rig, j)
        if pj is not None:
            carry[j] = (pj, rigid_inverse(rest[pj]) @ np.append(rest[j][:3, 3], 1.0))
    out = (rest, turned, carry, {j: rigid_inverse(rest[j]) for j in rest})
    rig._at_rest[key] = (bm, bi.fit, out)
    return out


def solve_joints(bi: _Builtin, rig: UserRig, bm: BoneMap, sport: str) -> dict:
    """Armature-space poses (n, 4, 4) of the user's mapped joints (see the module doc)."""
    fit, n = bi.fit, bi.n
    rest, turned, carry, _ = _at_rest(bi, rig, bm, sport)
    rot = {j: bi.delta(j) @ turned[j] for j in rest}
    poses = {}

    def place(j, head, R=None):
        m = np.zeros((n, 4, 4))
        m[:, :3, :3] = rot[j] if R is None else R
        m[:, :3, 3] = head
        m[:, 3, 3] = 1.0
        poses[j] = m

    def carried(j):
        pj, offset = carry[j]
        return (poses[pj] @ offset)[:, :3]

    def aimed(j, target_vec, rest_vec):
        """``rot[j]`` swung so the rest vector ``rest_vec`` (armature space) points along
        ``target_vec`` (n, 3)."""
        now = np.einsum("nij,j->ni", rot[j] @ rest[j][:3, :3].T, rest_vec)
        return swing(now, target_vec) @ rot[j]

    # The pelvis: the hip joints' midpoint goes on the built-in's line from the ankles' midpoint
    # to its hip joints, drawn from the user's ankles (the lean carries over), as far along it
    # as gives the knees the built-in's bend (an angle: thighs and shins of other proportions
    # need another distance).  With an ANCHOR (the telemark) the two legs differ too much for
    # one pelvis: each foot then turns about the ball of the foot until its own knee bends as
    # the built-in's, and the pelvis follows the ankles that gives (a few passes converge).
    hips_u = 0.5 * (rest["thigh.L"][:3, 3] + rest["thigh.R"][:3, 3])
    lean_b = 0.5 * (bi.head("thigh.L") + bi.head("thigh.R") - bi.head("foot.L")
                    - bi.head("foot.R"))
    axis = _unit(lean_b)
    DA = rot[B.HIPS] @ rest[B.HIPS][:3, :3].T
    anchor = ANCHOR.get(sport)
    first = {s: _ankle_target(bi, rest, rot, sport, s) for s in "LR"}
    ankles, turns = dict(first), {}
    for _ in range(6 if anchor else 1):
        hips_b = 0.5 * (ankles["L"] + ankles["R"]) + lean_b     # from the user's own ankles
        slide = np.zeros(n) if sport in SEATED else np.mean(
            [_knee_slide(bi, rest, DA, hips_b, hips_u, axis, s, ankles[s]) for s in "LR"], axis=0)
        place(B.HIPS, hips_b + slide[:, None] * axis - DA @ (hips_u - rest[B.HIPS][:3, 3]))
        if anchor:
            for s in "LR":
                ankles[s], turns[s] = _heel_for_knee(
                    bi, carried(f"thigh.{s}"), bi.head(f"{anchor}.{s}"), first[s],
                    _knee_distance(bi, rest, s), s)
    for s, turn in turns.items():
        rot[f"foot.{s}"] = turn @ rot[f"foot.{s}"]
    for j in rest:
        if j == B.HIPS or j in poses:
            continue
        side = j[-1]
        if j.startswith("thigh"):
            chain = (j, f"shin.{side}", f"foot.{side}")
            target = ankles[side]
        elif j.startswith("upper_arm"):
            chain = (j, f"forearm.{side}", f"hand.{side}")
            target = bi.head(chain[2])
        else:
            place(j, carried(j))
            continue
        a, b, c = chain
        root = carried(a)
        l1 = float(np.linalg.norm(rest[b][:3, 3] - rest[a][:3, 3]))
        l2 = float(np.linalg.norm(rest[c][:3, 3] - rest[b][:3, 3]))
        pole = f"pole.{side}"
        if ATTACH[sport].get(pole) == c and c in rest:
            # The pole is rigid in the user's hand: the hand turns as the built-in's pole does,
            # and the wrist goes where that puts the grip on the built-in's (the pole's rest
            # offset from the wrist, k times the built-in's), so the pole lies where the
            # built-in's lies and its planted tip stays in its hole; where the arm is too short
            # for that, the pole turns about its tip instead.
            turn = bi.delta(pole)
            grip = (fit.k / fit.scale) * bi.rest_vec(c, pole)
            target, S = _turn_about_tip(bi, pole, root,
                                        bi.head(pole) - np.einsum("nij,j->ni", turn, grip),
                                        REACH * (l1 + l2))
            rot[c] = S @ turn @ turned[c]
        mid, end = two_bone_ik(root, target, l1, l2, _pole(bi, a, b, c))
        place(a, root, aimed(a, mid - root, rest[b][:3, 3] - rest[a][:3, 3]))
        place(b, mid, aimed(b, end - mid, rest[c][:3, 3] - rest[b][:3, 3]))
        place(c, end)
    return poses


def _turn_about_tip(bi, pole, root, wrist, reach):
    """Where the user's arm cannot reach ``wrist`` (n, 3) (the wrist that puts the pole where
    the built-in's lies; the arm is shorter than the built-in's, scaled): the hand and the pole,
    rigid, turn about the pole's tip by the smallest angle that brings the wrist within
    ``reach`` of the shoulder ``root``.  The tip stays on the built-in's (in its hole while
    planted) and only the pole's angle changes.  Where no turn does (the tip is farther from the
    shoulder than the pole and the arm together) the wrist goes on the line from the tip to the
    shoulder, and the tip as near its place as the arm allows, up that line.  Returns the wrist
    target (n, 3) and the turn (n, 3, 3)."""
    P = bi.P[pole]
    tip = bi.fit.point(P[:, :3, 3] + bi.skel.length(pole) * P[:, :3, 1])
    S = np.broadcast_to(np.eye(3), P.shape[:1] + (3, 3)).copy()
    short = np.linalg.norm(wrist - root, axis=1) > reach
    if not short.any():
        return wrist, S
    w, t = wrist[short], tip[short]
    W = np.linalg.norm(w - t, axis=1, keepdims=True)
    u0 = (w - t) / W
    u, _ = on_sphere_within(t, W, u0, root[short], 0.0, reach)
    S[short] = swing(u0, u)
    out = wrist.copy()
    out[short] = t + W * u
    return out, S


def _channels(rig: UserRig, bones, poses, parent_deltas):
    """Local channels ``(location (m, n, 3), rotation (m, n, 4))`` giving each of the ``m``
    ``bones`` its armature-space pose (``poses`` (m, n, 4, 4)) when its parent frame has moved
    by ``parent_deltas[i]`` ((n, 4, 4), or ``None``: not at all); all bones in one pass."""
    idx = [rig.i(b) for b in bones]
    eye = np.eye(4)
    moved = np.stack([np.broadcast_to(eye if d is None else d, poses.shape[1:])
                      for d in parent_deltas])
    base = np.stack([stack_dot(m, rig.rest[i]) for m, i in zip(moved, idx)])
    rot = np.einsum("mnji,mnjk->mnik", base[..., :3, :3], poses[..., :3, :3])
    loc = np.einsum("mnji,mnj->mni", base[..., :3, :3], poses[..., :3, 3] - base[..., :3, 3])
    far = [k for k, i in enumerate(idx) if not rig.local_location[i]]
    if far:       # Blender: the location is in the parent's posed orientation (armature.cc)
        par = np.stack([eye if rig.parents[idx[k]] is None else rig.rest_of(rig.parents[idx[k]])
                        for k in far])
        par = moved[far] @ par[:, None]
        loc[far] = np.einsum("mnji,mnj->mni", par[..., :3, :3],
                             poses[far][..., :3, 3] - base[far][..., :3, 3])
    q = quat_from_matrix(rot)
    return loc, np.swapaxes(quat_continuous(np.swapaxes(q, 0, 1)), 0, 1)


def _fk_ancestor(rig, bm, bone):
    """The nearest mapped joint above ``bone`` in the user's hierarchy (or ``None``)."""
    owner = {b: j for j, b in bm.joints.items()}
    p = rig.parents[rig.i(bone)]
    while p is not None and p not in owner:
        p = rig.parents[rig.i(p)]
    return None if p is None else owner[p]


def path_length(location) -> np.ndarray:
    """(n,) how far the foot point ``location`` ((n, 3), m) has gone from its first row: the
    chords of one frame, summed."""
    step = np.linalg.norm(np.diff(np.asarray(location)[:, :2], axis=0), axis=1)
    return np.concatenate([[0.0], np.cumsum(step)])


def retarget(track: PoseTrack, sport: str, rig: UserRig, bm: BoneMap,
             fit: RigFit | None = None, mirror: bool = False, rows: tuple | None = None,
             distance: float = 0.0) -> PoseTrack:
    """The built-in figure's ``track`` (from ``map_trajectory(sport, ...)``) on the user's rig:
    a :class:`PoseTrack` of the user's bones (or controls) and the object's root motion.  With
    ``mirror`` the track is of the mirrored trajectory and the user's rig takes its mirror
    image (a goofy snowboarder); the state properties are given back unmirrored.

    ``rows`` ``(a, b)``: only frames ``a:b`` of ``track`` (a window of it; the frames around were
    the mapping's context), each frame's pose being its own; ``distance``: how far the foot
    point had gone before ``track``'s first frame (a part of a run: the wheels turn on)."""
    if sport not in ATTACH:
        raise ValueError(f"sport = {sport!r}: retargeting supports {', '.join(ATTACH)}")
    a, b = (0, len(track)) if rows is None else rows
    travelled = distance + path_length(track.location)[a:b] if sport in SPIN else None
    track = track.rows(a, b) if rows is not None else track
    fit = fit_rig(rig, bm, sport, mirror) if fit is None else fit
    bi = _Builtin(sport, track, fit, mirror)
    poses = solve_joints(bi, rig, bm, sport)
    moved = {None: None}          # joint -> its pose's change from rest (n, 4, 4)
    inverse = _at_rest(bi, rig, bm, sport)[3]
    for j in poses:
        moved[j] = poses[j] @ inverse[j]
    if bm.controls:     # (bone, pose, parent joint, location keyed)
        keyed = [(c.bone, moved[c.joint] @ rig.rest_of(c.bone), c.parent,
                  c.parent is None or c.location) for c in bm.controls]
    else:
        keyed = [(bm.bone(j), poses[j], a, a is None) for j in poses
                 for a in (_fk_ancestor(rig, bm, bm.bone(j)),)]
    names = [b for b, _, _, _ in keyed]
    loc, q = _channels(rig, names, np.stack([p for _, p, _, _ in keyed]),
                       [moved[a] for _, _, a, _ in keyed])
    bones = {b: BoneChannels(location=loc[k] if keys_loc else None, rotation=q[k])
             for k, (b, _, _, keys_loc) in enumerate(keyed)}
    # Root motion: the object turns the user's facing onto the heading and puts `origin` on
    # the foot point (the built-in's object carries the foot point and theta_dir - 90 deg, and
    # on terrain stands in the local surface, mapping/surface.py).  The user's armature point
    # p is the built-in's (s / k) C^T (p - origin), scaled by k about the foot point, so the
    # object's rotation is R_builtin C^T: tilted with the surface exactly as the built-in's.
    R = _matrix_xyz(track.rotation) @ fit.C.T
    psi = track.rotation[:, 2] + math.pi / 2 - fit.travel
    location = track.location - fit.scale * np.einsum("nij,j->ni", R, fit.origin)
    rotation = euler_xyz(R, psi)
    props = unmirror_props(track.props) if mirror else dict(track.props)
    if sport in SPIN:       # the foot point's path length, m
        props["turn_distance"] = travelled
    for piece, (along, prop) in SLIDE.get(sport, {}).items():
        # The built-in keys the slide as the piece's location along the axis (a unit vector in
        # the piece's rest frame); the user's figure is k times the size.
        axis = bi.skel.rest_of(piece)[:3, :3].T @ bi.skel.rest_of(along)[:3, 1]
        props[prop] = fit.k * (track.bones[piece].location @ axis)
    return PoseTrack(track.frames, location, rotation, bones, props)
