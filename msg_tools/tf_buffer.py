"""A TF buffer in the plane: what /tf_static and /tf said over the last seconds, looked up at a time as tf2 does.

frames.TfTree keeps the newest transform of every edge (lookups at the latest time: goals in other frames, map ->
odom). TfBuffer is a TfTree that also keeps, per edge, whether it came on /tf_static (timeless: valid at every
time) and, for an edge on /tf, its transforms of the last `cache_time` seconds (tf2's buffer keeps 10 s).
lookup_at(target, source, stamp) composes the chain between the two frames through their nearest common
ancestor only (base_link -> laser needs no odom -> base_link), each dynamic edge interpolated between the two
transforms around `stamp` (position linearly, yaw along the shorter way); a stamp outside an edge's transforms
is not available (tf2 neither extrapolates), TfUnavailable saying which edge and why, in one line.

What a neighbour sends cannot grow it without bound or take older for newer: at most `max_frames` child frames
are kept (beyond, the least recently updated frame no lookup asked for is dropped), at most `max_history`
transforms per dynamic edge, and stamps count: a transform older than the edge's newest is history, never the
newest, also when it names another parent; given the node's clock (`now`), an edge whose newest stamp is unset
(zero, a real time too: tf2 keeps it so) ages from when it came, and a stamp further than `ahead` in the future
is refused (kept, it would stay the newest for ever). add_cdr reads a TFMessage's bytes (msg_tools.tf_cdr):
whole, or only the transforms of the frames lookups asked for (`needed`) and their parents, searched in the
bytes.
"""

from __future__ import annotations

import bisect
import collections
import math
from dataclasses import dataclass
from typing import Any, Sequence

from msg_tools import convert, tf_cdr
from msg_tools.frames import IDENTITY, Pose2D, TfTree, compose, inverse, planar_transform

__all__ = ['CACHE_TIME', 'FRAMES_MAX', 'HISTORY_MAX', 'NEEDED_MAX', 'STAMP_TOLERANCE', 'Taken', 'TfBuffer',
           'TfUnavailable']

CACHE_TIME = 10.0        # s of each dynamic edge kept (tf2_ros's default buffer length)
STAMP_TOLERANCE = 1e-6   # s: a stamp this close to an edge's newest or oldest transform is at it (stamps are ns)

FRAMES_MAX = 1000
"""Child frames a TfBuffer keeps: a fleet of 100 robots of 10 frames each. A neighbour's /tf of 20,000 frames
grew a planner by 444 MB; beyond the bound a new frame drops the least recently updated one that no lookup asked
for (counted in `dropped`; the node says so)."""

HISTORY_MAX = 500
"""Transforms kept per dynamic edge: CACHE_TIME of an edge at the plants' 50 Hz. A faster edge keeps a shorter
span (the oldest go first); lookups at a stamp before it are 'older than the buffer'."""

NEEDED_MAX = 64
"""Frames remembered as asked for by lookups (with their ancestors): a planner's few (map, odom, base_link, the
laser's, goal frames), never dropped for a new frame, and what add_cdr searches a message for when it is not read
whole. Beyond, the least recently asked for is forgotten."""


class TfUnavailable(LookupError):
    """No transform between two frames at a time (the message says which edge and why)."""


def _wrap(angle: float) -> float:
    return math.atan2(math.sin(angle), math.cos(angle))


class _History:
    """One dynamic edge's transforms, by stamp (s)."""

    def __init__(self) -> None:
        self.stamps: list[float] = []
        self.poses: list[Pose2D] = []

    def add(self, stamp: float, pose: Pose2D, cache_time: float, keep: int) -> None:
        i = bisect.bisect_left(self.stamps, stamp)
        if i < len(self.stamps) and self.stamps[i] == stamp:
            self.poses[i] = pose   # sent again: the newer word counts
        else:
            self.stamps.insert(i, stamp)
            self.poses.insert(i, pose)
        drop = max(bisect.bisect_left(self.stamps, self.stamps[-1] - cache_time), len(self.stamps) - keep)
        if drop > 0:
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


@dataclass(frozen=True)
class Taken:
    """What add_cdr made of a TFMessage's bytes: the transforms it holds, those read (all of them when `whole`,
    else those of the `searched` frames it holds) and those kept (the rest: not finite, a cycle, older than the
    edge's newest in another parent's name, stamped too far ahead)."""

    count: int
    read: int
    kept: int
    whole: bool
    searched: tuple[str, ...] = ()


def _planar(edge: tf_cdr.Edge) -> tuple[str, str, Pose2D] | None:
    """frames.planar_transform of a transform read from bytes."""
    parent, child = edge[0].lstrip('/'), edge[1].lstrip('/')
    _, _, _, qx, qy, qz, qw = edge[3]
    norm = qx * qx + qy * qy + qz * qz + qw * qw
    if not parent or not child or parent == child or not (math.isfinite(norm) and norm > 0.0):
        return None
    pose = (edge[3][0], edge[3][1], math.atan2(2.0 * (qw * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz)))
    return (parent, child, pose) if all(math.isfinite(c) for c in pose) else None


class TfBuffer(TfTree):
    """A TfTree with each edge's kind (static or dynamic) and each dynamic edge's recent transforms, bounded
    (module docstring). `add` without `static` is /tf's; an edge that changes kind or parent starts afresh,
    unless the transform that would move it is older than the edge's newest."""

    def __init__(self, cache_time: float = CACHE_TIME, max_frames: int = FRAMES_MAX,
                 max_history: int = HISTORY_MAX) -> None:
        super().__init__()
        self.cache_time = cache_time
        self.max_frames = max_frames
        self.max_history = max_history
        self.static: set[str] = set()                                   # child frames of /tf_static's edges
        self.history: collections.defaultdict[str, _History] = collections.defaultdict(_History)
        self.updated: collections.OrderedDict[str, None] = collections.OrderedDict()   # children, oldest update first
        self.needed: collections.OrderedDict[str, None] = collections.OrderedDict()    # asked for, oldest first
        self.received: dict[str, float] = {}   # when each dynamic edge's last transform came (`now`)
        self.dropped = 0   # frames dropped for newer ones (max_frames)
        self.refused_ahead = 0   # transforms stamped further ahead of the clock than allowed
        self.refused_older = 0   # transforms older than their edge's newest, naming another parent

    def add(self, transforms: Sequence[Any], static: bool = False, now: float | None = None,
            ahead: float = math.inf) -> None:
        """geometry_msgs/TransformStamped messages; `now`: the node's clock (s) when they came, if known (module
        docstring), `ahead`: how far past it a stamp may be."""
        for t in transforms:
            edge = planar_transform(t)
            if edge is not None:
                self.put(*edge, convert.stamp_to_seconds(t.header.stamp), static, now, ahead)

    def add_cdr(self, data: bytes, static: bool = False, now: float | None = None, ahead: float = math.inf,
                whole: bool = True) -> Taken | None:
        """A TFMessage's CDR bytes (add's other arguments): every transform (`whole`) or only those of the frames
        lookups asked for and their parents (a search of the bytes per frame, whatever the message's size).
        None when the bytes are not little-endian CDR (deserialise and `add` them); ValueError (one line) when
        they are cut off."""
        count = tf_cdr.transform_count(data)
        if count is None:
            return None
        if whole:
            edges = tf_cdr.read_all(data) or []
            searched: tuple[str, ...] = ()
        else:
            edges, searched = self._search(data)
        kept = 0
        for raw in edges:
            edge = _planar(raw)
            if edge is not None:
                kept += self.put(*edge, raw[2], static, now, ahead)
        return Taken(count, len(edges), kept, whole, searched)

    def _search(self, data: bytes) -> tuple[list[tf_cdr.Edge], tuple[str, ...]]:
        """The transforms of the needed frames the message holds, and of their parents this buffer does not know
        (a chain that comes in one message), with the frames searched for."""
        found: dict[str, tf_cdr.Edge] = {}
        wanted = [f for f in self.needed if f]
        searched: list[str] = []
        for _ in range(self.MAX_DEPTH):
            if not wanted:
                break
            searched.extend(wanted)
            step = tf_cdr.read_children(data, wanted) or {}
            found.update(step)
            wanted = [p for p in {e[0].lstrip('/') for e in step.values()}
                      if p not in found and p not in self.parents and p not in searched]
        return list(found.values()), tuple(searched)

    def put(self, parent: str, child: str, pose: Pose2D, stamp: float, static: bool = False,
            now: float | None = None, ahead: float = math.inf) -> bool:
        """One edge (add's arguments); whether it was kept."""
        if child in self._ancestors(parent):
            return False
        if not static and now is not None:
            if stamp > now + ahead:
                self.refused_ahead += 1
                return False
            kept = self.history.get(child)
            if kept is not None and kept.stamps and kept.stamps[-1] > now + ahead:
                self.history.pop(child)   # stamped ahead of a clock that went back: from another run
        before = self.parents.get(child)
        if before is not None and (before[0] != parent or (child in self.static) != static):
            kept = self.history.get(child)
            if not static and before[0] != parent and kept is not None and kept.stamps and \
                    stamp < kept.stamps[-1] - STAMP_TOLERANCE:
                self.refused_older += 1
                return False   # another parent's word, but older than the edge's newest: not the newest
            self.history.pop(child, None)   # re-parented, or moved between /tf and /tf_static
        if static:
            self.static.add(child)
            self.parents[child] = (parent, pose)
        else:
            self.static.discard(child)
            history = self.history[child]
            history.add(stamp, pose, self.cache_time, self.max_history)
            if now is not None:
                self.received[child] = now
            # The newest transform of the edge is what lookups at the latest time take.
            self.parents[child] = (parent, history.poses[-1])
        self.updated[child] = None
        self.updated.move_to_end(child)
        if before is None and len(self.parents) > self.max_frames:
            self._drop()
        return True

    def _drop(self) -> None:
        """Drop the least recently updated frames no lookup asked for, down to max_frames."""
        while len(self.parents) > self.max_frames and self.updated:
            child = next(iter(self.updated))
            if child in self.needed:
                self.updated.move_to_end(child)   # kept: looked up (at most NEEDED_MAX of them pass here per round)
                continue
            del self.updated[child], self.parents[child]
            self.static.discard(child)
            self.history.pop(child, None)
            self.received.pop(child, None)
            self.dropped += 1

    def need(self, *frames: str) -> None:
        """Frames a lookup asked for: they and their ancestors are kept and searched for (NEEDED_MAX of them)."""
        for frame in frames:
            for f in self._ancestors(frame.lstrip('/')):
                self.needed[f] = None
                self.needed.move_to_end(f)
        while len(self.needed) > NEEDED_MAX:
            self.needed.popitem(last=False)

    def lookup(self, target: str, source: str) -> Pose2D | None:
        """TfTree.lookup, the frames remembered as needed."""
        self.need(target, source)
        return super().lookup(target, source)

    def lookup_stamped(self, target: str, source: str) -> tuple[Pose2D, float] | None:
        """lookup and the stamp it holds at: the oldest newest-stamp of the dynamic edges between the two frames
        (an unset one: when its transform came, if known), inf when they are all static (a static transform never
        ages); None when the frames are not in one tree."""
        pose = self.lookup(target, source)
        if pose is None:
            return None
        target, source = target.lstrip('/'), source.lstrip('/')
        up_source, up_target = self._path(source), self._path(target)
        in_target = set(up_target)
        common = next((f for f in up_source if f in in_target), None)
        chain = [*up_source[:up_source.index(common)], *up_target[:up_target.index(common)]] if common else []
        stamps = [self.history[f].stamps[-1] or self.received.get(f, 0.0) for f in chain
                  if f not in self.static and f in self.history and self.history[f].stamps]
        return pose, min(stamps, default=math.inf)

    def _path(self, frame: str) -> list[str]:
        return self._ancestors(frame)[: self.MAX_DEPTH + 1]

    def lookup_at(self, target: str, source: str, stamp: float | None) -> Pose2D:
        """The pose of frame `source` in frame `target` at `stamp` (s; None or 0: the newest of every edge, as
        tf2's time 0); TfUnavailable (one line) when the frames are not in one tree or an edge between them has
        no transform at that time."""
        target, source = target.lstrip('/'), source.lstrip('/')
        if target == source:
            return IDENTITY
        self.need(target, source)
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
