"""One-lane passages on a route, and who waits before one (FAStep-Route; issue 12).

Why: two robots that meet head-on where only one fits can neither pass nor keep right. They stand face to face
until one goes round the other, the long way: multi_robot:1000010's r1 drove 1.128 x its optimum round the upper
U-shape while r2 came through the gap between the two (docs/clutter.md, "Where FAStep-Route is worst"). Traffic's
rule is older: whoever comes later waits before the narrow part until the other is through.

- A point of the route is *narrow* when neither side of it has room for another robot beside this one: the
  points `radius + other_radius + margin` away along the route's normal, on both sides, are nearer than
  `other_radius` to an obstacle or to the workspace border (`World.room`). A *passage* is a run of narrow
  points, the route sampled every STEP metres (`passages`, once per route and other robots' radius).
- The robot waits before a passage ahead (`Passage.conflict`) while another robot comes through it towards
  this one (in it and moving this way), or comes towards its far end and is nearer to it than this robot is
  to its entry (the one whose name sorts first goes on a tie within TIE metres). Robots standing still are
  not waited for: the route goes round them (planning/fastep_route.py, BLOCK_TIME).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from fastep_core.planning.others import OtherRobot
from fastep_core.world import World

__all__ = ['Passage', 'STEP', 'TIE', 'passages']

FloatArray = NDArray[np.float64]
STEP = 0.25   # m between the route's samples tested for room beside it
TIE = 0.5     # m: two robots this close to equally far from a passage go in the order of their names


@dataclass(frozen=True)
class Passage:
    """A stretch of route another robot cannot pass beside: from `entry` to `exit` metres along the route."""

    entry: float
    exit: float
    points: FloatArray   # (k, 2) the route's samples in it, entry to exit

    @property
    def far_end(self) -> FloatArray:
        end: FloatArray = self.points[-1]
        return end

    def conflict(self, position: FloatArray, name: str, others: Sequence[OtherRobot], moving_speed: float,
                 reach: float) -> OtherRobot | None:
        """The robot to wait for before this passage, for a robot at `position` (before the entry) named `name`;
        None when it may go in. `reach`: this robot's radius plus the clearance margin.

        Both distances are straight lines (this robot's to the entry, the other's to the far end), as the other
        robot measures them on its own route through the same passage: the two come to the same answer.
        """
        ahead = math.hypot(float(self.points[0][0]) - float(position[0]), float(self.points[0][1]) - float(position[1]))
        direction = self.points[0] - self.points[-1]          # the way a robot coming through drives
        for other in others:
            vx, vy = other.velocity
            if math.hypot(vx, vy) < moving_speed or not (math.isfinite(other.position[0]) and
                                                         math.isfinite(other.position[1])):
                continue
            position = np.asarray(other.position, dtype=float)
            inside = float(np.hypot(*(self.points - position).T).min()) < other.radius + reach
            if inside:
                if vx * direction[0] + vy * direction[1] > 0.0:   # in it, coming this way
                    return other
                continue
            to_end = self.far_end - position
            gap = math.hypot(to_end[0], to_end[1])
            if vx * to_end[0] + vy * to_end[1] <= 0.0 or gap > ahead + TIE:
                continue                                        # not coming, or this robot is nearer
            if gap < ahead - TIE or other.name < name:
                return other
        return None


def passages(world: World, points: FloatArray, radius: float, other_radius: float, margin: float,
             start: float = 0.0, stop: float = math.inf) -> list[Passage]:
    """The passages of the polyline `points` (n, 2) between `start` and `stop` metres along it, for a robot of
    `radius` and others of `other_radius`; entries and exits in metres from the polyline's start. A passage
    going on past `stop` ends there (the caller looks further when it needs to: a whole route of kilometres
    among a thousand obstacles took seconds)."""
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    if len(points) < 2:
        return []
    legs = np.diff(points, axis=0)
    lengths = np.hypot(*legs.T)
    starts = np.concatenate([[0.0], np.cumsum(lengths)])
    total = float(starts[-1])
    start, stop = max(0.0, start), min(total, stop)
    if total <= 0.0 or stop < start:
        return []
    s = np.arange(start, stop + 0.5 * STEP, STEP)
    s[-1] = min(s[-1], stop)
    leg = np.clip(np.searchsorted(starts, s, side='right') - 1, 0, len(legs) - 1)
    unit = legs[leg] / np.where(lengths[leg] > 0.0, lengths[leg], 1.0)[:, None]
    samples = points[leg] + unit * (s - starts[leg])[:, None]
    normal = np.stack([-unit[:, 1], unit[:, 0]], axis=1) * (radius + other_radius + margin)
    room = world.room(np.concatenate([samples + normal, samples - normal]))
    narrow = (room[:len(s)] < other_radius + 2.0 * margin) & (room[len(s):] < other_radius + 2.0 * margin)
    out: list[Passage] = []
    edges = np.flatnonzero(np.diff(np.concatenate([[0], narrow.astype(np.int8), [0]])))
    for first, end in zip(edges[::2], edges[1::2]):
        out.append(Passage(float(s[first]), float(s[end - 1]), samples[first:end].copy()))
    return out
