"""Forward and inverse kinematics of an armature, numpy only, in Blender's conventions.

* Quaternions are ``(w, x, y, z)``; arrays of them have shape ``(..., 4)``.
* A bone's rest frame follows Blender: Y from head to tail, X and Z from the roll by Blender's
  ``vec_roll_to_mat3`` (:func:`vec_roll_to_mat3`); its 4x4 rest matrix in armature space is
  ``bone.matrix_local``.
* Pose channels are local (``PoseBone.location``, ``PoseBone.rotation_quaternion``), composed as
  Blender does for bones with the default inherit flags::

      pose_arm = pose_arm_parent @ (rest_arm_parent^-1 @ rest_arm) @ T(location) @ R(quat)

  A connected bone's location is ignored by Blender, so :class:`PoseBuilder` never writes one.

:class:`PoseBuilder` holds the channels of all bones over ``n`` frames; a mapping sets local
rotations directly, or sets a bone's armature-space pose (from IK, or "stay on the ski") and lets
the builder derive the local channels from the parent's current pose.
"""
from __future__ import annotations

import numpy as np

__all__ = ["cross", "norm", "dot", "quat_mul", "quat_conj", "quat_from_axis_angle",
           "quat_to_matrix", "quat_from_matrix", "quat_continuous", "vec_roll_to_mat3",
           "rest_matrix", "translation", "rotation4", "rot_axis_angle", "stack_dot", "two_bone_ik",
           "frame_from_yx", "Skeleton", "PoseBuilder"]

IDENTITY_QUAT = np.array([1.0, 0.0, 0.0, 0.0])


# -- quaternions ---------------------------------------------------------------------------------
def quat_mul(a, b):
    """Hamilton product ``a * b`` (rotate by ``b`` first, then ``a``)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    if a.shape != b.shape:
        a, b = np.broadcast_arrays(a, b)
    w1, x1, y1, z1 = a[..., 0], a[..., 1], a[..., 2], a[..., 3]
    w2, x2, y2, z2 = b[..., 0], b[..., 1], b[..., 2], b[..., 3]
    return np.stack([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
                     w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                     w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
                     w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2], axis=-1)


def quat_conj(q):
    return np.asarray(q, float) * np.array([1.0, -1.0, -1.0, -1.0])


def quat_from_axis_angle(axis, angle):
    """Rotation by ``angle`` (rad, right-handed) about ``axis`` (normalised here)."""
    axis = np.asarray(axis, float)
    axis = axis / norm(axis, keepdims=True)
    half = 0.5 * np.asarray(angle, float)[..., None]
    return np.concatenate([np.cos(half), np.sin(half) * axis], axis=-1)


def quat_to_matrix(q):
    """(..., 4) unit quaternions -> (..., 3, 3) rotation matrices."""
    q = np.asarray(q, float)
    q = q / norm(q, keepdims=True)
    w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    xx, yy, zz, xy, xz, yz = x * x, y * y, z * z, x * y, x * z, y * z
    wx, wy, wz = w * x, w * y, w * z
    m = np.empty(q.shape[:-1] + (3, 3))
    m[..., 0, 0], m[..., 0, 1], m[..., 0, 2] = 1 - 2 * (yy + zz), 2 * (xy - wz), 2 * (xz + wy)
    m[..., 1, 0], m[..., 1, 1], m[..., 1, 2] = 2 * (xy + wz), 1 - 2 * (xx + zz), 2 * (yz - wx)
    m[..., 2, 0], m[..., 2, 1], m[..., 2, 2] = 2 * (xz - wy), 2 * (yz + wx), 1 - 2 * (xx + yy)
    return m


def quat_from_matrix(m):
    """(..., 3, 3) rotation matrices -> (..., 4) unit quaternions with ``w >= 0``.

    Shepperd's method: of the four candidate formulas the one with the largest pivot is used,
    so the result is accurate for every rotation (including 180 deg).
    """
    m = np.asarray(m, float)
    shape = m.shape[:-2]
    m = m.reshape(-1, 3, 3)
    d = np.empty((len(m), 4))                       # the pivots: trace and diagonal
    d[:, 1], d[:, 2], d[:, 3] = m[:, 0, 0], m[:, 1, 1], m[:, 2, 2]
    d[:, 0] = d[:, 1] + d[:, 2] + d[:, 3]
    k = d.argmax(axis=1)
    q = np.empty((len(m), 4))
    for case in range(4):
        s = k == case
        if not s.any():
            continue
        full = s.all()                              # one case for every frame: no copies
        a, v = (m, q) if full else (m[s], np.empty((int(s.sum()), 4)))
        if case == 0:
            r = np.sqrt(1.0 + (d[:, 0] if full else d[s, 0])) * 2.0
            v[:, 0] = 0.25 * r
            v[:, 1] = (a[:, 2, 1] - a[:, 1, 2]) / r
            v[:, 2] = (a[:, 0, 2] - a[:, 2, 0]) / r
            v[:, 3] = (a[:, 1, 0] - a[:, 0, 1]) / r
        else:
            i, j, kk = case - 1, case % 3, (case + 1) % 3
            r = np.sqrt(1.0 + a[:, i, i] - a[:, j, j] - a[:, kk, kk]) * 2.0
            v[:, 0] = (a[:, kk, j] - a[:, j, kk]) / r
            v[:, 1 + i] = 0.25 * r
            v[:, 1 + j] = (a[:, j, i] + a[:, i, j]) / r
            v[:, 1 + kk] = (a[:, kk, i] + a[:, i, kk]) / r
        if not full:
            q[s] = v
    q[q[:, 0] < 0] *= -1.0
    q /= norm(q, keepdims=True)
    return q.reshape(shape + (4,))


def quat_continuous(q):
    """Flip signs along axis 0 so consecutive quaternions have a non-negative dot product
    (``q`` (n, ..., 4): several tracks side by side are made continuous each on its own).

    ``q`` and ``-q`` are the same rotation, but F-curves interpolate the components: a sign jump
    between two keys would spin the bone the long way round.
    """
    q = np.array(q, float)
    if len(q) < 2:
        return q
    flip = dot(q[1:], q[:-1]) < 0
    sign = np.concatenate([np.ones((1,) + flip.shape[1:]),
                           np.where(np.cumsum(flip, axis=0) % 2 == 1, -1.0, 1.0)])
    return q * sign[..., None]


# -- rest frames (Blender's armature.cc) ---------------------------------------------------------
def rot_axis_angle(axis, angle):
    """(3, 3) rotation matrix by ``angle`` about unit ``axis`` (Rodrigues)."""
    x, y, z = axis
    c, s = np.cos(angle), np.sin(angle)
    t = 1.0 - c
    return np.array([[t * x * x + c, t * x * y - s * z, t * x * z + s * y],
                     [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
                     [t * x * z - s * y, t * y * z + s * x, t * z * z + c]])


def vec_roll_to_mat3(vec, roll: float) -> np.ndarray:
    """Blender's ``vec_roll_to_mat3``: the bone rotation for direction ``vec`` and ``roll`` (rad).

    A transcription of ``vec_roll_to_mat3_normalized`` (blenkernel/intern/armature.cc), including
    its thresholds near the singular direction -Y.  Columns are the bone's X, Y, Z axes.
    """
    nor = np.asarray(vec, float)
    nor = nor / np.linalg.norm(nor)
    x, y, z = nor
    safe, critical = 6.1e-3, 2.5e-4
    theta = 1.0 + y
    theta_alt = x * x + z * z
    b = np.zeros((3, 3))   # row-major here: b[row, col]; Blender's bMatrix[col][row]
    if theta > safe or theta_alt > critical * critical:
        b[0, 1], b[1, 0], b[1, 1], b[2, 1], b[1, 2] = x, -x, y, z, -z
        if theta <= safe:
            # Series expansion of theta from x, z where 1 + y has lost its precision.
            theta = theta_alt * 0.5 + theta_alt * theta_alt * 0.125
        b[0, 0] = 1.0 - x * x / theta
        b[2, 2] = 1.0 - z * z / theta
        b[0, 2] = b[2, 0] = -x * z / theta
    else:
        b = np.eye(3)
        b[0, 0] = b[1, 1] = -1.0
    return rot_axis_angle(nor, roll) @ b


def rest_matrix(head, tail, roll: float) -> np.ndarray:
    """4x4 ``bone.matrix_local``: rotation from (tail - head, roll), translation ``head``."""
    m = np.eye(4)
    m[:3, :3] = vec_roll_to_mat3(np.subtract(tail, head), roll)
    m[:3, 3] = head
    return m


def translation(v):
    """(..., 3) -> (..., 4, 4) translation matrices."""
    v = np.asarray(v, float)
    m = np.broadcast_to(np.eye(4), v.shape[:-1] + (4, 4)).copy()
    m[..., :3, 3] = v
    return m


def rotation4(r):
    """(..., 3, 3) -> (..., 4, 4)."""
    r = np.asarray(r, float)
    m = np.broadcast_to(np.eye(4), r.shape[:-2] + (4, 4)).copy()
    m[..., :3, :3] = r
    return m


#: The most multiply-adds of one BLAS call that OpenBLAS runs on one thread (its default
#: GEMM_MULTITHREAD_THRESHOLD of 4: a matrix-vector product of m x n with m n < 2304 x 4, a
#: matrix product of m x k x n with m k n <= 65536 x 4).  Above them it wakes its other
#: threads, which then spin waiting for more work: a 60 s run's poses (1,441 frames) times a
#: vector did, measured by the worker thread's CPU ticks.
BLAS_ONE_THREAD = {1: 2304 * 4 - 1, 2: 65536 * 4}


def stack_dot(a, k):
    """``a @ k`` for a stack ``a`` (..., r, c) and one matrix (c, m) or vector (c,) ``k``, as 2-D
    products over the whole stack: numpy's matmul loops over a stack of small matrices, about
    8x slower than this at a thousand frames.  A long stack goes in pieces that OpenBLAS runs
    on the calling thread alone (:data:`BLAS_ONE_THREAD`); each row is the same sum either way."""
    a = np.asarray(a, float)
    k = np.asarray(k, float)
    flat = a.reshape(-1, a.shape[-1])
    rows = max(BLAS_ONE_THREAD[k.ndim] // k.size, 1)
    if len(flat) <= rows:
        out = flat @ k
    else:
        out = np.empty((len(flat),) + k.shape[1:])
        for i in range(0, len(flat), rows):
            np.matmul(flat[i:i + rows], k, out=out[i:i + rows])
    return out.reshape(a.shape[:-1] + k.shape[1:])


def rigid_inverse(m):
    """Inverse of rigid transforms (..., 4, 4) (a rotation and a translation, as every pose here
    is): ``[R^T, -R^T t]``, exact where a general 4x4 inverse is ~20x slower per frame, and
    elementwise: LAPACK's inverse wakes OpenBLAS's threads, which on a loaded machine costs
    milliseconds a call (measured in Blender: 14.7 ms wall against 0.1 ms CPU for one 4x4)."""
    r = np.swapaxes(m[..., :3, :3], -1, -2)
    out = np.zeros(m.shape)
    out[..., :3, :3] = r
    out[..., :3, 3] = -np.einsum("...ij,...j->...i", r, m[..., :3, 3])
    out[..., 3, 3] = 1.0
    return out


def cross(a, b, out=None) -> np.ndarray:
    """``np.cross`` of (..., 3) vectors, the same numbers at half its cost on the mapping's short
    arrays (``np.cross`` moves axes about first: 67 against 34 us for 73 frames, measured);
    into ``out`` when given (a (..., 3) view: a frame's column)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    if a.shape != b.shape:
        a, b = np.broadcast_arrays(a, b)
    if out is None:
        out = np.empty(a.shape)
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    np.subtract(a1 * b2, a2 * b1, out=out[..., 0])
    np.subtract(a2 * b0, a0 * b2, out=out[..., 1])
    np.subtract(a0 * b1, a1 * b0, out=out[..., 2])
    return out


def norm(v, keepdims: bool = False):
    """``np.linalg.norm(v, axis=-1)``: the same numbers (the square root of the same sum)
    without its argument checks, a third of its cost on the mapping's short arrays."""
    return np.sqrt(np.add.reduce(v * v, axis=-1, keepdims=keepdims))


def dot(a, b, keepdims: bool = False):
    """``np.sum(a * b, axis=-1)`` (row-wise dot products), the same numbers."""
    return np.add.reduce(a * b, axis=-1, keepdims=keepdims)


def _unit(v):
    v = np.asarray(v, float)
    return v / norm(v, keepdims=True)


def frame_from_yx(y_axis, x_hint):
    """(..., 3, 3) rotations whose Y column is ``y_axis`` and X column lies along ``x_hint``
    (made orthogonal to Y); Z = X x Y."""
    y = _unit(y_axis)
    x = _unit(x_hint - dot(x_hint, y, keepdims=True) * y)
    out = np.empty(y.shape + (3,))
    out[..., 0], out[..., 1] = x, y
    cross(x, y, out[..., 2])
    return out


def on_sphere_within(centre, radius, u0, other, lo, hi):
    """The point of the sphere of ``radius`` (a number or (n, 1)) about ``centre`` (n, 3) nearest
    to ``centre + radius u0`` (``u0`` (n, 3) unit) among those ``lo``..``hi`` from ``other``
    (n, 3): a pole pivoting about its tip whose grip a hand at ``other`` can hold.  On the
    sphere the distance from ``other`` grows with the angle from the direction towards it (law
    of cosines), so the allowed points are a band about that direction and the nearest one is
    on the great circle from ``u0`` to it.  Returns ``(u (n, 3), ok (n,))``: the unit direction
    from the centre, and whether any point is within the band (else ``u`` points at ``other``,
    or away from it where the whole sphere is nearer than ``lo``)."""
    to = np.asarray(other, float) - centre
    D = np.maximum(norm(to, keepdims=True), 1e-12)
    c = to / D
    law = lambda r: (radius * radius + D * D - r * r) / (2.0 * radius * D)     # noqa: E731
    near, far = law(hi), law(lo)            # cos(angle) bounds of the band
    cos0 = dot(u0, c, keepdims=True)
    cos = np.clip(cos0, np.maximum(near, -1.0), np.clip(far, -1.0, 1.0))
    cos = np.minimum(cos, 1.0)
    across = u0 - cos0 * c
    across /= np.maximum(norm(across, keepdims=True), 1e-12)
    ok = (near[..., 0] <= 1.0) & (far[..., 0] >= -1.0)
    return cos * c + np.sqrt(np.maximum(1.0 - cos * cos, 0.0)) * across, ok


def two_bone_ik(root, target, l1: float, l2: float, pole, reach: float = 0.9999):
    """Analytic two-bone IK: the middle joint for a chain ``root -> mid -> target``.

    ``root``, ``target``, ``pole`` have shape (..., 3); ``pole`` is a direction (not a point)
    towards which the middle joint bends (a knee forward, an elbow back).  Targets farther than
    ``reach * (l1 + l2)`` or nearer than ``|l1 - l2|`` are clamped along the same line.  The
    lengths are numbers or (..., 1) arrays (one per chain).  Returns ``(mid, end)``: the middle
    joint and the end actually reached.
    """
    root = np.asarray(root, float)
    d = np.asarray(target, float) - root
    dist = norm(d, keepdims=True)
    u = d / np.maximum(dist, 1e-12)
    dist = np.minimum(np.maximum(dist, abs(l1 - l2) + 1e-9), reach * (l1 + l2))
    # Law of cosines: distance of the middle joint's projection along u, and its offset.
    a = (l1 * l1 - l2 * l2 + dist * dist) / (2.0 * dist)
    h = np.sqrt(np.maximum(l1 * l1 - a * a, 0.0))
    p = np.asarray(pole, float)
    p = p - dot(p, u, keepdims=True) * u
    p = _unit(p)
    return root + a * u + h * p, root + dist * u


# -- skeleton and pose ----------------------------------------------------------------------------
#: id(spec) -> (spec, its Skeleton): :meth:`Skeleton.from_spec`'s cache (the spec is kept, so
#: its id is not reused while the entry stands).
_SKELETONS = {}


class Skeleton:
    """Bones in parent-before-child order with their rest matrices (armature space)."""

    def __init__(self, names, parents, rest, connected, lengths=None):
        self.names = tuple(names)
        self.lengths = None if lengths is None else tuple(float(v) for v in lengths)
        self.index = {n: i for i, n in enumerate(self.names)}
        self.parents = tuple(parents)   # parent name or None
        self.rest = np.asarray(rest, float)            # (k, 4, 4)
        self.connected = tuple(bool(c) for c in connected)
        self._relative = {}                             # (name, frame) -> rest_in (4, 4)
        for n, p in zip(self.names, self.parents):
            if p is not None and self.index.get(p, len(self.names)) >= self.index[n]:
                raise ValueError(f"bone {n!r}: parent {p!r} must come before it")

    @classmethod
    def from_spec(cls, spec) -> "Skeleton":
        """The skeleton of the rig ``spec``, built once per spec object (the rigs are loaded
        once per file): its rest matrices are read-only and shared, and so is its cache of
        :meth:`rest_relative`."""
        hit = _SKELETONS.get(id(spec))
        if hit is not None and hit[0] is spec:
            return hit[1]
        skel = cls([b.name for b in spec.bones], [b.parent for b in spec.bones],
                   [rest_matrix(b.head, b.tail, b.roll) for b in spec.bones],
                   [b.connected for b in spec.bones], [b.length for b in spec.bones])
        skel.rest.setflags(write=False)
        if len(_SKELETONS) >= 64:                      # specs made on the fly (tests, rigs)
            _SKELETONS.clear()
        _SKELETONS[id(spec)] = (spec, skel)
        return skel

    def i(self, name: str) -> int:
        try:
            return self.index[name]
        except KeyError:
            from .bones import MissingBoneError
            raise MissingBoneError(f"bone {name!r} is not in the rig") from None

    def length(self, name: str) -> float:
        """Rest length (head to tail), m."""
        if self.lengths is None:
            raise ValueError("this skeleton was built without bone lengths")
        return self.lengths[self.i(name)]

    def rest_of(self, name: str) -> np.ndarray:
        return self.rest[self.i(name)]

    def rest_relative(self, name: str) -> np.ndarray:
        """``rest_arm_parent^-1 @ rest_arm`` (the rest matrix itself for a root bone)."""
        return self.rest_in(name, self.parents[self.i(name)])

    def rest_in(self, name: str, frame: str | None) -> np.ndarray:
        """``rest_arm_frame^-1 @ rest_arm``: bone ``name``'s rest matrix in the rest frame of the
        bone ``frame`` (the rest matrix itself for ``None``); computed once per skeleton and
        shared, read-only."""
        rel = self._relative.get((name, frame))
        if rel is None:
            rest = self.rest_of(name)
            rel = np.array(rest if frame is None else rigid_inverse(self.rest_of(frame)) @ rest)
            rel.setflags(write=False)                  # shared by every caller
            self._relative[(name, frame)] = rel
        return rel

    def carry(self, poses: dict, bone: str, p_rest) -> np.ndarray:
        """Where bone ``bone``'s pose (from :meth:`fk`) carries the armature-space rest point
        ``p_rest``: (n, 3)."""
        rel = rigid_inverse(self.rest_of(bone)) @ np.append(np.asarray(p_rest, float), 1.0)
        return (poses[bone] @ rel)[:, :3]

    def fk(self, channels: dict, n: int) -> dict:
        """Armature-space pose matrices (n, 4, 4) of all bones from local channels.

        ``channels`` maps a bone name to an object with ``location`` (n, 3) or None and
        ``rotation`` (n, 4) or None (a :class:`~blender_turning.mapping.base.BoneChannels`).
        """
        turned = [b for b in self.names
                  if channels.get(b) is not None and channels[b].rotation is not None]
        turns = dict(zip(turned, rotation4(quat_to_matrix(
            np.stack([channels[b].rotation for b in turned]))))) if turned else {}
        out = {}
        for i, name in enumerate(self.names):
            p = self.parents[i]
            m = np.broadcast_to(self.rest_relative(name), (n, 4, 4))
            if p is not None:
                m = out[p] @ m
            ch = channels.get(name)
            if ch is not None and ch.location is not None and not self.connected[i]:
                m = m @ translation(ch.location)
            if name in turns:             # every bone's turn in one pass
                m = m @ turns[name]
            out[name] = np.array(m)
        return out


class PoseBuilder:
    """Local channels of every bone over ``n`` frames, filled in parent-before-child order."""

    def __init__(self, skeleton: Skeleton, n: int):
        self.skel = skeleton
        self.n = n
        self.loc = {}
        self.rot = {}
        self._poses = {}          # bone -> pose (n, 4, 4), dropped when it or an ancestor changes

    def _changed(self, name):
        """Forget the cached poses of ``name`` and its descendants."""
        skel = self.skel
        gone = {name}
        for child, parent in zip(skel.names[skel.i(name) + 1:], skel.parents[skel.i(name) + 1:]):
            if parent in gone:
                gone.add(child)
        for bone in gone:
            self._poses.pop(bone, None)

    def set_local(self, name, rotation=None, location=None):
        self.skel.i(name)
        if rotation is not None:
            self.rot[name] = np.broadcast_to(np.asarray(rotation, float), (self.n, 4)).copy()
        if location is not None:
            self.loc[name] = np.broadcast_to(np.asarray(location, float), (self.n, 3)).copy()
        self._changed(name)

    def pose(self, name) -> np.ndarray:
        """Current armature-space pose (n, 4, 4) of ``name``, from its ancestors' channels."""
        return self._pose(name).copy()

    def _pose(self, name) -> np.ndarray:
        """:meth:`pose`, the cached array itself (not to be changed)."""
        cached = self._poses.get(name)
        if cached is not None:
            return cached
        i = self.skel.i(name)
        m = self._unposed(name)
        loc = self.loc.get(name) if not self.skel.connected[i] else None
        rot = self.rot.get(name)
        if loc is not None or rot is not None:       # T(location) @ R(quaternion), one matrix
            local = translation(np.zeros((self.n, 3)) if loc is None else loc)
            if rot is not None:
                local[:, :3, :3] = quat_to_matrix(rot)
            m = m @ local
        self._poses[name] = m
        return m

    def _unposed(self, name) -> np.ndarray:
        p = self.skel.parents[self.skel.i(name)]
        m = self.skel.rest_relative(name)
        return np.array(np.broadcast_to(m, (self.n, 4, 4))) if p is None else \
            stack_dot(self._pose(p), m)

    def unposed(self, name) -> np.ndarray:
        """The pose ``name`` would have with identity channels (its parent as now posed)."""
        return self._unposed(name)

    def set_pose(self, name, rotation, head=None):
        """Give ``name`` the armature-space rotation (n, 3, 3) and head (n, 3) (or keep its head).

        The local channels follow from the parent's current pose.  A connected bone gets no
        location (Blender ignores it: its head is its parent's tail), so pass ``head=None``.
        """
        i = self.skel.i(name)
        if head is not None and self.skel.connected[i]:
            raise ValueError(f"bone {name!r} is connected: its head follows its parent's tail")
        base = self._unposed(name)
        # base^-1 @ [rotation, head] of rigid transforms: [R^T rotation, R^T (head - t)].
        back = np.swapaxes(base[:, :3, :3], 1, 2)
        if head is not None:
            self.loc[name] = np.einsum("nij,nj->ni", back, head - base[:, :3, 3])
        self.rot[name] = quat_from_matrix(np.matmul(back, rotation))
        self._changed(name)

    def head(self, name) -> np.ndarray:
        return self.pose(name)[:, :3, 3]
