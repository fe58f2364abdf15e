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
    mover: bool = False   # a moving obstacle that does not plan or give way (planning/safety/yielding.py), not a robot


class TickArrays:
    """Positions (n, 2), velocities (n, 2) and radii (n,) of every robot of one tick, made once, when first asked."""

    __slots__ = ('_robots', '_arrays')

    def __init__(self, robots: Sequence[OtherRobot]) -> None:
        self._robots = robots
        self._arrays: tuple[FloatArray, FloatArray, FloatArray] | None = None

    def get(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        if self._arrays is None:
            robots = self._robots
            self._arrays = (np.array([o.position for o in robots], dtype=float).reshape(-1, 2),
                            np.array([o.velocity for o in robots], dtype=float).reshape(-1, 2),
                            np.array([o.radius for o in robots], dtype=float))
        return self._arrays


class OtherRobots(Sequence[OtherRobot]):
    """Every robot of one tick but one, as a sequence of OtherRobot, sharing the tick's arrays.

    Why: the simulator gives each of N robots the N - 1 others every tick. Built robot by robot, as lists of
    OtherRobot and then as arrays again by each consumer, that was O(N^2) Python work per tick (100 robots:
    most of a run's time). Here the N OtherRobot objects and their arrays are made once per tick; each robot's
    view leaves its own row out.
    """

    def __init__(self, robots: Sequence[OtherRobot], skip: int, arrays: TickArrays,
                 movers: Sequence[OtherRobot] | None = None):
        self._robots, self._skip, self._all = robots, skip, arrays
        self._arrays: tuple[FloatArray, FloatArray, FloatArray] | None = None
        self._all_movers = movers   # every entry that is a mover, shared by the views of one tick

    @classmethod
    def views(cls, robots: Sequence[OtherRobot], viewers: int | None = None) -> list[OtherRobots]:
        """For each of the first `viewers` entries (default: all), the others: views of one shared list and one
        set of arrays (made when a view first needs them: a robot alone never does). Entries after the viewers
        are seen by every viewer but see nothing themselves (moving obstacles, fastep_core/dynamic_world.py)."""
        arrays = TickArrays(robots)
        movers = [o for o in robots if o.mover]
        return [cls(robots, i, arrays, movers) for i in range(len(robots) if viewers is None else viewers)]

    def __len__(self) -> int:
        return len(self._robots) - 1

    def movers(self) -> list[OtherRobot]:
        """The movers among the others (a v2 world's entries after the viewers), found once per tick."""
        found = self._all_movers
        if found is None:
            found = self._all_movers = [o for o in self._robots if o.mover]
        me = self._robots[self._skip]
        return [o for o in found if o is not me] if found else []

    @overload
    def __getitem__(self, index: int) -> OtherRobot: ...

    @overload
    def __getitem__(self, index: slice) -> list[OtherRobot]: ...

    def __getitem__(self, index: int | slice) -> OtherRobot | list[OtherRobot]:
        rest = list(self._robots[:self._skip]) + list(self._robots[self._skip + 1:])
        return rest[index]

    def __iter__(self) -> Iterator[OtherRobot]:
        for j, robot in enumerate(self._robots):
            if j != self._skip:
                yield robot

    @property
    def arrays(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Positions (n, 2), velocities (n, 2) and radii (n,) of the others, made once."""
        if self._arrays is None:
            i = self._skip
            positions, velocities, radii = (np.concatenate([a[:i], a[i + 1:]]) for a in self._all.get())
            self._arrays = positions, velocities, radii
        return self._arrays

    @property
    def finite(self) -> bool:
        """Are all the positions finite (the navigator drops the others)? True with no others (a robot alone)."""
        return len(self._robots) <= 1 or bool(np.isfinite(self.arrays[0]).all())


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
    near = np.hypot(*(centres - start).T) - sums < sensing_range
    if not near.any():   # in a crowd most robots are out of range: measure runs only against those in it
        return False
    run = point_segment_distance(centres[near], start, end)
    return bool(np.any(run < sums[near] + margin))
