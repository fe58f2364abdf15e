"""One-lane passages on a route, and who waits before one (FAStep-Route).

Why: two robots that meet head-on where only one fits can neither pass nor keep right; they stand face to face
until one goes the long way round. Traffic's rule is older: whoever comes later waits before the narrow part.

- A point of the route is *narrow* when neither side of it has room for the other robot beside this one
  (`World.room`, judged with the larger radius so both robots agree). A *passage* is a run of narrow points,
  the route sampled every STEP metres on a grid fixed along it (`passages`).
- The robot waits before a passage ahead (`Passage.conflict`) while another robot comes through it towards this
  one, or comes towards its far end nearer to it than this robot is to its entry (within TIE metres the name
  that sorts first goes first), or already stands waiting at its far end with a name that sorts first (else two
  robots could both stand, both go and stand again). Robots standing still are not waited for: the route goes
  round them (planning/navigators/fastep_route.py, BLOCK_TIME).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from fastep_core.planning.others import OtherRobot
from fastep_core.world import World

__all__ = ['Passage', 'STEP', 'TIE', 'passages', 'waiting_room']

FloatArray = NDArray[np.float64]
STEP = 0.25   # m between the route's samples tested for room beside it
TIE = 0.5     # m: two robots this close to equally far from a passage go in the order of their names


def waiting_room(radius: float, other_radius: float, margin: float) -> float:
    """How far before a passage's entry a robot stands to wait (the other comes out past it)."""
    return other_radius + 2.0 * (radius + margin)


@dataclass(frozen=True)
class Passage:
    """A stretch of route another robot cannot pass beside: from `entry` to `exit` metres along the route."""

    entry: float
    exit: float
    points: FloatArray   # (k, 2) the route's samples in it, entry to exit
    box: tuple[float, float, float, float] = field(init=False)   # the points' bounds (x0, y0, x1, y1)

    def __post_init__(self) -> None:
        low, high = self.points.min(axis=0), self.points.max(axis=0)
        object.__setattr__(self, 'box', (float(low[0]), float(low[1]), float(high[0]), float(high[1])))

    @property
    def far_end(self) -> FloatArray:
        end: FloatArray = self.points[-1]
        return end

    def conflict(self, position: FloatArray, name: str, others: Sequence[OtherRobot], moving_speed: float,
                 radius: float, margin: float, waiting: bool = False) -> OtherRobot | None:
        """The robot to wait for before this passage, for a robot of `radius` at `position` (before the entry)
        named `name`, `waiting` already; None when it may go in. A robot standing at the far end is waited for
        only by a robot already waiting (else a robot parked there for good would hold it up). Robots with a
        non-finite position, velocity or radius are left out (odometry is not checked for them)."""
        here = self.points[0]
        ahead = math.hypot(float(here[0]) - float(position[0]), float(here[1]) - float(position[1]))
        direction = self.points[0] - self.points[-1]          # the way a robot coming through drives
        reach = radius + margin
        for other in others:
            (x, y), (vx, vy), r = other.position, other.velocity, other.radius
            if not all(map(math.isfinite, (x, y, vx, vy, r))):
                continue
            to_end = self.far_end - (x, y)
            gap = math.hypot(float(to_end[0]), float(to_end[1]))
            if math.hypot(vx, vy) < moving_speed:
                # Standing: waited for only as a robot waiting at the far end that goes first by name.
                if waiting and gap <= waiting_room(r, radius, margin) + STEP and other.name < name:
                    return other
                continue
            near = r + reach
            x0, y0, x1, y1 = self.box
            inside = x0 - near < x < x1 + near and y0 - near < y < y1 + near and \
                float(np.hypot(*(self.points - (x, y)).T).min()) < near
            if inside:
                if vx * direction[0] + vy * direction[1] > 0.0:   # in it, coming this way
                    return other
                continue
            if vx * to_end[0] + vy * to_end[1] <= 0.0 or gap > ahead + TIE:
                continue                                        # not coming, or this robot is nearer
            if gap < ahead - TIE or other.name < name:
                return other
        return None


def passages(world: World, points: FloatArray, radius: float, other_radius: float, margin: float,
             start: float = 0.0, stop: float = math.inf) -> list[Passage]:
    """The passages of the polyline `points` (n, 2) between `start` and `stop` metres along it, for a robot of
    `radius` and others of `other_radius`; entries and exits in metres from the polyline's start. The samples
    lie on multiples of STEP from the start whatever the window, and a passage going on past `stop` ends
    there: the caller looks further when it needs to (a whole route of kilometres among a thousand obstacles
    took seconds)."""
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    if len(points) > 1:   # a repeated vertex is a leg without a direction (its normal would be zero)
        points = points[np.concatenate([[True], np.hypot(*np.diff(points, axis=0).T) > 0.0])]
    if len(points) < 2:
        return []
    legs = np.diff(points, axis=0)
    lengths = np.hypot(*legs.T)
    starts = np.concatenate([[0.0], np.cumsum(lengths)])
    total = float(starts[-1])
    start, stop = max(0.0, start), min(total, stop)
    if stop < start:
        return []
    s = np.arange(math.ceil(start / STEP - 1e-9) * STEP, stop + 1e-9, STEP)
    if not len(s):
        return []
    leg = np.clip(np.searchsorted(starts, s, side='right') - 1, 0, len(legs) - 1)
    unit = legs[leg] / lengths[leg][:, None]
    samples = points[leg] + unit * (s - starts[leg])[:, None]
    normal = np.stack([-unit[:, 1], unit[:, 0]], axis=1) * (radius + other_radius + margin)
    room = world.room(np.concatenate([samples + normal, samples - normal]))
    need = max(radius, other_radius) + 2.0 * margin
    narrow = (room[:len(s)] < need) & (room[len(s):] < need)
    out: list[Passage] = []
    edges = np.flatnonzero(np.diff(np.concatenate([[0], narrow.astype(np.int8), [0]])))
    for first, end in zip(edges[::2], edges[1::2]):
        out.append(Passage(float(s[first]), float(s[end - 1]), samples[first:end].copy()))
    return out
