"""Other robots as a planner sees them: moving obstacles with a position, a velocity and a radius.

Known moving obstacles of a v2 world reach planners the same way, named 'mover K' (fastep_core/dynamic_world.py).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Iterator, Sequence, overload

import numpy as np
from numpy.typing import NDArray

from fastep_core.geometry import point_segment_distance

__all__ = ['OtherRobot', 'OtherRobots', 'other_arrays', 'robot_arrays', 'robots_on_run']

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class OtherRobot:
    """Another robot as a moving obstacle: where it is, how fast it goes, how big it is."""

    name: str
    position: tuple[float, float]
    velocity: tuple[float, float] = (0.0, 0.0)
    radius: float = 0.5


class _Tick:
    """One tick's robots as arrays (N rows), and what every viewer's view needs, made for all viewers at once."""

    def __init__(self, names: Sequence[str], positions: FloatArray, velocities: FloatArray, radii: FloatArray,
                 viewers: int, robots: Sequence[OtherRobot] | None = None) -> None:
        self.names, self.viewers = list(names), viewers
        self.all = (positions, velocities, radii)
        self._robots = list(robots) if robots is not None else None
        self._rest: tuple[FloatArray, FloatArray, FloatArray] | None = None
        self._gaps: FloatArray | None = None
        self.finite = bool(np.isfinite(positions).all())

    @property
    def robots(self) -> list[OtherRobot]:
        """The OtherRobot objects, made on first use (the hot path reads the arrays only)."""
        if self._robots is None:
            positions, velocities, radii = self.all
            self._robots = [OtherRobot(name, (p[0], p[1]), (v[0], v[1]), r)
                            for name, p, v, r in zip(self.names, positions, velocities, radii.tolist())]
        return self._robots

    @property
    def rest(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Each viewer's others, (viewers, N - 1, ...): row i is every row of the tick but i, in order."""
        if self._rest is None:
            n = len(self.names)
            index = np.arange(n - 1)[None, :] + (np.arange(n - 1)[None, :] >= np.arange(self.viewers)[:, None])
            positions, velocities, radii = self.all
            self._rest = positions[index], velocities[index], radii[index]
        return self._rest

    @property
    def gaps(self) -> FloatArray:
        """Centre distance from each viewer to each of its others, (viewers, N - 1): np.hypot of the offsets,
        as a consumer measuring them from the viewer's position gets them."""
        if self._gaps is None:
            offsets = self.rest[0] - self.all[0][:self.viewers, None, :]
            self._gaps = np.hypot(offsets[..., 0], offsets[..., 1])
        return self._gaps


class OtherRobots(Sequence[OtherRobot]):
    """Every robot of one tick but one, as a sequence of OtherRobot, sharing the tick's arrays.

    Why: the simulator gives each of N robots the N - 1 others every tick. Built robot by robot, as lists of
    OtherRobot and then as arrays again by each consumer, that was O(N^2) Python work per tick (100 robots:
    most of a run's time). Here one tick's arrays are made once; every viewer's arrays (its own row left out)
    and its distances to the others are made for all viewers at once, on first use; the OtherRobot objects
    only when something iterates them.
    """

    def __init__(self, tick: _Tick, skip: int) -> None:
        self._tick, self._skip = tick, skip

    @classmethod
    def views(cls, robots: Sequence[OtherRobot], viewers: int | None = None) -> list[OtherRobots]:
        """For each of the first `viewers` entries (default: all), the others: views of one shared list and one
        set of arrays. Entries after the viewers are seen by every viewer but see nothing themselves (moving
        obstacles, fastep_core/dynamic_world.py)."""
        arrays = (np.array([o.position for o in robots], dtype=float).reshape(-1, 2),
                  np.array([o.velocity for o in robots], dtype=float).reshape(-1, 2),
                  np.array([o.radius for o in robots], dtype=float))
        n = len(robots) if viewers is None else viewers
        tick = _Tick([o.name for o in robots], *arrays, viewers=n, robots=robots)
        return [cls(tick, i) for i in range(n)]

    @classmethod
    def from_arrays(cls, names: Sequence[str], positions: FloatArray, velocities: FloatArray, radii: FloatArray,
                    viewers: int | None = None) -> list[OtherRobots]:
        """views() of a tick given as arrays (N, 2), (N, 2), (N,) and names: no OtherRobot made unless asked."""
        n = len(names) if viewers is None else viewers
        tick = _Tick(names, np.asarray(positions, dtype=float).reshape(-1, 2),
                     np.asarray(velocities, dtype=float).reshape(-1, 2), np.asarray(radii, dtype=float), viewers=n)
        return [cls(tick, i) for i in range(n)]

    def __len__(self) -> int:
        return len(self._tick.names) - 1

    @overload
    def __getitem__(self, index: int) -> OtherRobot: ...

    @overload
    def __getitem__(self, index: slice) -> list[OtherRobot]: ...

    def __getitem__(self, index: int | slice) -> OtherRobot | list[OtherRobot]:
        robots = self._tick.robots
        rest = robots[:self._skip] + robots[self._skip + 1:]
        return rest[index]

    def __iter__(self) -> Iterator[OtherRobot]:
        for j, robot in enumerate(self._tick.robots):
            if j != self._skip:
                yield robot

    @property
    def arrays(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Positions (n, 2), velocities (n, 2) and radii (n,) of the others."""
        positions, velocities, radii = self._tick.rest
        i = self._skip
        return positions[i], velocities[i], radii[i]

    def gaps_from(self, point: FloatArray) -> FloatArray | None:
        """The distances from `point` to the others' centres when `point` is this robot's own position in the
        tick (made for every robot at once), else None (the caller measures)."""
        own = self._tick.all[0][self._skip]
        if point[0] == own[0] and point[1] == own[1]:
            row: FloatArray = self._tick.gaps[self._skip]
            return row
        return None

    @property
    def finite(self) -> bool:
        """Are all the positions finite (the navigator drops the others)?"""
        return self._tick.finite or bool(np.isfinite(self.arrays[0]).all())


def other_arrays(others: Sequence[OtherRobot]) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Positions (n, 2), velocities (n, 2) and radii (n,) of the other robots."""
    if isinstance(others, OtherRobots):
        return others.arrays
    return (np.array([o.position for o in others], dtype=float).reshape(-1, 2),
            np.array([o.velocity for o in others], dtype=float).reshape(-1, 2),
            np.array([o.radius for o in others], dtype=float))


def robot_arrays(others: Sequence[OtherRobot], radius: float) -> tuple[FloatArray, FloatArray]:
    """The other robots' centres (n, 2) and the sums of their radii and `radius` (n,)."""
    if not others:
        return np.zeros((0, 2)), np.zeros(0)
    centres, _, radii = other_arrays(others)
    return centres, radii + radius


def robots_on_run(others: Sequence[OtherRobot], radius: float, start: FloatArray, end: FloatArray,
                  sensing_range: float, margin: float) -> bool:
    """Is another robot within sensing range (surface to surface) and closer to the straight run start-end
    than both radii plus `margin`?"""
    if not others:
        return False
    centres, sums = robot_arrays(others, radius)
    gaps = others.gaps_from(start) if isinstance(others, OtherRobots) else None
    near = (np.hypot(*(centres - start).T) if gaps is None else gaps) - sums < sensing_range
    if not near.any():   # in a crowd most robots are out of range: measure runs only against those in it
        return False
    run = point_segment_distance(centres[near], start, end)
    return bool(np.any(run < sums[near] + margin))
