"""A TF buffer in the plane: what /tf_static and /tf said over the last seconds, looked up at a time as tf2 does.

frames.TfTree keeps the newest transform of every edge (lookups at the latest time: goals in other frames, map ->
odom). TfBuffer is a TfTree that also keeps, per edge, whether it came on /tf_static (timeless: valid at every
time) and, for an edge on /tf, its transforms of the last `cache_time` seconds (tf2's buffer keeps 10 s).
lookup_at(target, source, stamp) composes the chain between the two frames through their nearest common
ancestor only (base_link -> laser needs no odom -> base_link), each dynamic edge interpolated between the two
transforms around `stamp` (position linearly, yaw along the shorter way); a stamp outside an edge's transforms
is not available (tf2 neither extrapolates), TfUnavailable saying which edge and why, in one line.
"""

from __future__ import annotations

import bisect
import collections
import math
from typing import Any, Sequence

from msg_tools import convert
from msg_tools.frames import IDENTITY, Pose2D, TfTree, compose, inverse, planar_transform

__all__ = ['CACHE_TIME', 'STAMP_TOLERANCE', 'TfBuffer', 'TfUnavailable']

CACHE_TIME = 10.0        # s of each dynamic edge kept (tf2_ros's default buffer length)
STAMP_TOLERANCE = 1e-6   # s: a stamp this close to an edge's newest or oldest transform is at it (stamps are ns)


class TfUnavailable(LookupError):
    """No transform between two frames at a time (the message says which edge and why)."""


def _wrap(angle: float) -> float:
    return math.atan2(math.sin(angle), math.cos(angle))


class _History:
    """One dynamic edge's transforms, by stamp (s)."""

    def __init__(self) -> None:
        self.stamps: list[float] = []
        self.poses: list[Pose2D] = []

    def add(self, stamp: float, pose: Pose2D, cache_time: float) -> None:
        i = bisect.bisect_left(self.stamps, stamp)
        if i < len(self.stamps) and self.stamps[i] == stamp:
            self.poses[i] = pose   # sent again: the newer word counts
        else:
            self.stamps.insert(i, stamp)
            self.poses.insert(i, pose)
        drop = bisect.bisect_left(self.stamps, self.stamps[-1] - cache_time)
        if drop:
            del self.stamps[:drop], self.poses[:drop]

    def at(self, stamp: float) -> Pose2D | str:
        """The pose at `stamp`, or why not (the edge's span)."""
        stamps = self.stamps
        if stamp > stamps[-1] + STAMP_TOLERANCE:
            return f'not yet available (newest {stamps[-1]:.3f} s)'
        if stamp < stamps[0] - STAMP_TOLERANCE:
            return f'older than the buffer (oldest {stamps[0]:.3f} s)'
        i = bisect.bisect_left(stamps, stamp)
        if i >= len(stamps):
            return self.poses[-1]
        if i == 0 or stamps[i] - stamp <= STAMP_TOLERANCE:
            return self.poses[i]
        (t0, a), (t1, b) = (stamps[i - 1], self.poses[i - 1]), (stamps[i], self.poses[i])
        share = (stamp - t0) / (t1 - t0)
        return (a[0] + share * (b[0] - a[0]), a[1] + share * (b[1] - a[1]), _wrap(a[2] + share * _wrap(b[2] - a[2])))


class TfBuffer(TfTree):
    """A TfTree with each edge's kind (static or dynamic) and each dynamic edge's recent transforms (module
    docstring). `add` without `static` is /tf's; an edge that changes kind or parent starts afresh."""

    def __init__(self, cache_time: float = CACHE_TIME) -> None:
        super().__init__()
        self.cache_time = cache_time
        self.static: set[str] = set()                                   # child frames of /tf_static's edges
        self.history: collections.defaultdict[str, _History] = collections.defaultdict(_History)

    def add(self, transforms: Sequence[Any], static: bool = False) -> None:
        for t in transforms:
            edge = planar_transform(t)
            if edge is None or edge[1] in self._ancestors(edge[0]):
                continue
            parent, child, pose = edge
            before = self.parents.get(child)
            if before is not None and (before[0] != parent or (child in self.static) != static):
                self.history.pop(child, None)   # re-parented, or moved between /tf and /tf_static
            if static:
                self.static.add(child)
                self.parents[child] = (parent, pose)
                continue
            self.static.discard(child)
            history = self.history[child]
            stamp = convert.stamp_to_seconds(t.header.stamp)
            history.add(stamp, pose, self.cache_time)
            # The newest transform of the edge is what lookups at the latest time take.
            self.parents[child] = (parent, history.poses[-1])

    def _path(self, frame: str) -> list[str]:
        return self._ancestors(frame)[: self.MAX_DEPTH + 1]

    def lookup_at(self, target: str, source: str, stamp: float | None) -> Pose2D:
        """The pose of frame `source` in frame `target` at `stamp` (s; None or 0: the newest of every edge, as
        tf2's time 0); TfUnavailable (one line) when the frames are not in one tree or an edge between them has
        no transform at that time."""
        target, source = target.lstrip('/'), source.lstrip('/')
        if target == source:
            return IDENTITY
        if not stamp:
            pose = self.lookup(target, source)
            if pose is None:
                raise TfUnavailable(self._unconnected(target, source))
            return pose
        up_source, up_target = self._path(source), self._path(target)
        common = next((f for f in up_target if f in set(up_source)), None)
        if common is None:
            raise TfUnavailable(self._unconnected(target, source))
        in_common_s = self._chain(up_source[:up_source.index(common)], stamp)
        in_common_t = self._chain(up_target[:up_target.index(common)], stamp)
        return compose(inverse(in_common_t), in_common_s)

    def _chain(self, frames: list[str], stamp: float) -> Pose2D:
        """The pose of frames[0] in the parent of frames[-1] at `stamp` (frames: a frame and its ancestors)."""
        pose = IDENTITY
        for child in frames:
            parent, newest = self.parents[child]
            if child in self.static or child not in self.history:
                edge: Pose2D | str = newest
            else:
                edge = self.history[child].at(stamp)
            if isinstance(edge, str):
                raise TfUnavailable(f'transform {parent!r} -> {child!r} at {stamp:.3f} s is {edge}')
            pose = compose(edge, pose)
        return pose

    def _unconnected(self, target: str, source: str) -> str:
        known = self.frames()
        missing = [f for f in (target, source) if f not in known]
        if len(missing) == 2:
            return f'no transform from {target!r} to {source!r}: neither frame is on /tf or /tf_static'
        if missing:
            return f'no transform from {target!r} to {source!r}: {missing[0]!r} is on neither /tf nor /tf_static'
        return f'no transform from {target!r} to {source!r}: they are in two trees of /tf and /tf_static'
