"""Figures whose baked motion is another's: the same keys, later by whole frames and moved by a
constant translation, so that one action can play for all of them (docs/crowds.md, "Shared
motion").

A follower on the leader's track (``follow_leader`` without body, timing or period differences),
or a synchronized line in phase, runs the leader's simulation from another start or at a later
time: on flat ground the turning dynamics do not depend on where the figure is (Section 2's
equations hold no position) nor, with constant settings, on the time it starts.  Its pose track
is the leader's, the object's location moved by a constant and the rows later by the frames it
starts later.  :func:`plan` finds such figures by comparing the tracks themselves, every value of
every channel, not their settings: a figure shares only when what it would bake is what the
shared action plays.

The comparison is at the keys' own precision.  An F-curve holds float32: two values are the same
key when they are at most one float32 unit in the last place apart, measured at the channel's
largest magnitude over the run (at least 1: a quaternion's components and angles are parts of a
unit whose float32 resolution is 1.2e-7).  The location is compared as Blender plays it: the
shared key plus the figure's ``delta_location``, both float32, within the roundings of the four
(:func:`_translation`).  Measured on skiers from another start: the channels differ by at most
7e-16 and the locations, after the translation, by 1.25 units in the last place; a 1% heavier
body differs by about 1e-3 and does not share.

Section 7's ski tilt gain is the least-squares slope of the lean on the curvature over the run
the figure makes (:func:`.sports.snow.tilt_gain`), so a skier that starts later, on the same
track, runs a shorter part of it and its skis tilt a little differently (4e-5 rad in a foot's
rotation, measured): it bakes its own.  A follower strung out along the track (Add Crowd's
default staging) runs the whole shot and shares.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .base import PoseTrack

__all__ = ["Matcher", "Share", "order", "plan", "shares"]

#: Rows compared first, for every candidate at once (most candidates differ there).
_HEAD = 3


@dataclass(frozen=True)
class Share:
    """A figure that plays another's motion."""

    source: int
    """Index (in :func:`plan`'s list) of the figure whose bake it plays."""
    shift: int
    """Frames it plays it later (its first frame minus the source's)."""
    translation: tuple
    """(3,) m added to the source's location on every frame (float32 values)."""


def _channels(track: PoseTrack, rows: slice) -> np.ndarray:
    """Every value but the object's location, ``rows`` of them: float32, (rows, channels)."""
    parts = [track.rotation[rows]]
    for name in sorted(track.bones):
        ch = track.bones[name]
        parts += [a[rows] for a in (ch.location, ch.rotation) if a is not None]
    parts += [np.asarray(track.props[p])[rows, None] for p in sorted(track.props)]
    return np.concatenate([np.asarray(p, float).reshape(len(p), -1) for p in parts],
                          axis=1).astype(np.float32)


def _layout(track: PoseTrack) -> tuple:
    """What channels a track has: two tracks share only with the same ones."""
    return (tuple(sorted((b, ch.location is not None, ch.rotation is not None)
                         for b, ch in track.bones.items())), tuple(sorted(track.props)))


def _scale(*arrays) -> np.ndarray:
    """Per channel (column): the largest magnitude in ``arrays``, at least 1."""
    out = np.ones(arrays[0].shape[1], np.float32)
    for a in arrays:
        out = np.maximum(out, np.abs(a).max(axis=0))
    return out


def _same_keys(a: np.ndarray, b: np.ndarray) -> bool:
    """float32 ``a`` and ``b`` (rows, channels) the same keys: at most one unit in the last
    place of the channel's scale (:func:`_scale`) apart, everywhere."""
    return bool(np.all(np.abs(a - b) <= np.spacing(_scale(a, b))))


def _translation(source: PoseTrack, track: PoseTrack) -> np.ndarray | None:
    """The float32 translation taking ``source``'s location keys onto ``track``'s (its first
    ``len(track)`` rows), or ``None`` when no constant one does.  Blender plays the source's
    float32 key plus the float32 ``delta_location``: against the figure's own float32 key that
    is four roundings of half a unit in the last place (the two keys, the translation, the sum)
    at the largest of the values, so two units is the bound."""
    n = len(track)
    a = source.location[:n].astype(np.float32)
    b = track.location.astype(np.float32)
    d = (b[0] - a[0]).astype(np.float32)
    played = a + d
    tol = 2.0 * np.spacing(_scale(a, b, d[None]))
    return d if bool(np.all(np.abs(played - b) <= tol)) else None


def shares(source: PoseTrack, track: PoseTrack, channels=None) -> Share | None:
    """``Share(0, shift, translation)`` when ``track`` is ``source``'s motion, later by whole
    frames (its first ``len(track)`` rows) and moved by a constant translation; else ``None``.
    ``channels``: both tracks' :func:`_channels` (all rows), when the caller has them."""
    n = len(track)
    if n > len(source) or _layout(source) != _layout(track):
        return None
    shift = float(track.frames[0]) - float(source.frames[0])
    if shift != round(shift) or \
            not np.array_equal(np.asarray(track.frames, float) - shift, source.frames[:n]):
        return None
    a, b = channels if channels is not None else (_channels(source, slice(None)),
                                                  _channels(track, slice(None)))
    if not _same_keys(a[:n], b):
        return None
    d = _translation(source, track)
    return None if d is None else Share(0, int(shift), tuple(float(v) for v in d))


class _Sources:
    """The sources of one channel layout: their first rows and channel scales, stacked (in a
    buffer that doubles), so a new track's candidates are found for all of them at once."""

    def __init__(self, width: int):
        self.index = []
        self.heads = np.empty((8, width), np.float32)
        self.tols = np.empty((8, width), np.float32)

    def add(self, i: int, head: np.ndarray, scale: np.ndarray) -> None:
        k = len(self.index)
        if k == len(self.heads):
            self.heads = np.concatenate([self.heads, np.empty_like(self.heads)])
            self.tols = np.concatenate([self.tols, np.empty_like(self.tols)])
        self.heads[k] = head.ravel()
        self.tols[k] = np.tile(scale, len(head))      # the source's whole run's scale
        self.index.append(i)

    def candidates(self, head: np.ndarray) -> list:
        """Sources whose first rows are ``head``'s keys."""
        k = len(self.index)
        flat = head.ravel()
        tol = np.spacing(np.maximum(self.tols[:k], np.abs(flat)))
        near = np.all(np.abs(self.heads[:k] - flat) <= tol, axis=1)
        return [self.index[m] for m in np.nonzero(near)[0]]


class Matcher:
    """Tracks met one at a time, the earliest-starting first: :meth:`match` finds a source met
    before whose motion a track is, :meth:`add` makes a track a source.  Only the sources'
    tracks are kept (a crowd baked figure by figure holds no more)."""

    def __init__(self):
        self._groups = {}                # (channel layout, head's shape) -> _Sources
        self._tracks = {}                # source key -> its track
        self._channels = {}              # source key -> its _channels, once compared whole
        self._last = None                # (track, its _channels): the last one matched

    def match(self, track: PoseTrack) -> Share | None:
        """The :class:`Share` (``source``: the key it was added with) of ``track``, or
        ``None``.  Candidates are narrowed on their first rows, for all sources at once, then
        compared whole (:func:`shares`)."""
        full = _channels(track, slice(None))
        self._last = (track, full)
        head = full[:_HEAD]
        sources = self._groups.get((_layout(track), head.shape))
        for key in (sources.candidates(head) if sources is not None else ()):
            source = self._tracks[key]
            if key not in self._channels:
                self._channels[key] = _channels(source, slice(None))
            share = shares(source, track, (self._channels[key], full))
            if share is not None:
                return Share(key, share.shift, share.translation)
        return None

    def add(self, key, track: PoseTrack) -> None:
        full = self._last[1] if self._last is not None and self._last[0] is track \
            else _channels(track, slice(None))
        head = full[:_HEAD]
        sources = self._groups.setdefault((_layout(track), head.shape), _Sources(head.size))
        sources.add(key, head, _scale(full))
        self._tracks[key] = track


def order(tracks) -> list:
    """Indices of ``tracks`` in the order to meet them: the earliest start first (a source
    starts no later than the figures sharing its motion), then as given."""
    return sorted(range(len(tracks)), key=lambda i: (float(tracks[i].frames[0]), i))


def plan(tracks) -> list:
    """For each of ``tracks`` (:class:`.base.PoseTrack`), ``None`` (it is baked on its own) or
    the :class:`Share` of an earlier-starting one whose motion it is (see :func:`shares`).  The
    figure that starts first (then: comes first) of a group is its source; a source shares
    nobody's."""
    out = [None] * len(tracks)
    matcher = Matcher()
    for i in order(tracks):
        out[i] = matcher.match(tracks[i])
        if out[i] is None:
            matcher.add(i, tracks[i])
    return out
