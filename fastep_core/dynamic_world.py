"""The world of scenario format v2 over time: what is true, and what a planner is given as its map.

Why a module of its own rather than more of world.py: `World` is the static map every planner consumes; this
module holds what v2 adds around it and that planners must never read directly. Three views of one scenario:

- the truth (`DynamicWorld.still`, `DynamicWorld.movers`): every still obstacle where it really is, every moving
  circle where docs/scenarios.md puts it at time t. Collisions, margins and scans (`DynamicWorld.scan`) use it.
- the planner's map (`DynamicWorld.planner_map`): known still obstacles only, misplaced ones moved by their
  error, and the known movers reported each tick as `OtherRobot`s named 'mover K'.
- the draws: map errors come from `map_generator(seed)`, a stream of the run's seed no swarm uses, so adding
  position_sigma changes no swarm's draws and a seed's map does not depend on the number of robots.

A mover's centre runs along its polyline at constant speed and back, forever (docs/scenarios.md); all movers at
all times are one array computation (`Movers.positions`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from fastep_core.geometry import Circle, Obstacle, Segment
from fastep_core.planning.others import OtherRobot
from fastep_core.sensing import laser
from fastep_core.sensing.laser import LaserSpec, Scan
from fastep_core.world import World

__all__ = ['MAP_STREAM', 'Motion', 'Movers', 'ObstacleSpec', 'DynamicWorld', 'PlannerMap', 'dynamic_feature',
           'map_generator', 'mover_name']

FloatArray = NDArray[np.float64]

LOOKUP_ELEMENTS = 1 << 20
"""Times x movers x segments compared at once when locating movers on their polylines: a long track against
movers with many waypoints goes in chunks of times, so memory stays bounded (about 10 MB of booleans)."""
MAP_STREAM = 0x6D6170   # 'map': the spawn key of the map's stream, far above any robot's index
"""SeedSequence spawn key of the map errors' stream (robots' swarms use keys 0 .. n_robots - 1)."""


@dataclass(frozen=True)
class Motion:
    """A mover's path (the waypoints after its centre) and speed (m/s)."""

    waypoints: tuple[tuple[float, float], ...]
    speed: float


@dataclass(frozen=True)
class ObstacleSpec:
    """One obstacle of a scenario file as v2 describes it: its shape (a circle's centre at t = 0) and the
    keys v2 adds. A v1 obstacle is a still, known, exactly placed one."""

    shape: Obstacle
    motion: Motion | None = None
    known: bool = True
    position_sigma: float = 0.0

    @property
    def still(self) -> bool:
        return self.motion is None

    @property
    def v1(self) -> bool:
        """Does it mean what a v1 file means (nothing v2 adds)?"""
        return self.motion is None and self.known and self.position_sigma == 0.0


def dynamic_feature(obstacles: Sequence[ObstacleSpec]) -> str:
    """The first thing v2 adds to these obstacles, as 'obstacles[K] moves (motion)'; '' for a v1 world.

    For what cannot run v2 worlds yet (the ROS graph, fastep-sim's recordings) to refuse them in one line.
    """
    for i, spec in enumerate(obstacles):
        if spec.motion is not None:
            return f'obstacles[{i}] moves (motion)'
        if not spec.known:
            return f'obstacles[{i}] is unknown (known: false)'
        if spec.position_sigma > 0.0:
            return f'obstacles[{i}] is misplaced (position_sigma)'
    return ''


def mover_name(index: int) -> str:
    """What planners call the obstacle at `index` of the file when it moves ('mover 3')."""
    return f'mover {index}'


def map_generator(seed: int) -> np.random.Generator:
    """The Generator of a run's map errors (module docstring: a stream of the seed no swarm uses)."""
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(MAP_STREAM,)))


class Movers:
    """Every moving circle of a world as arrays: positions and velocities at any times in one call.

    The polylines (centre, then waypoints) are padded to one length by repeating their last vertex, which adds
    segments of zero length that arc-length lookups never land inside.
    """

    def __init__(self, circles: Sequence[Circle], motions: Sequence[Motion], indices: Sequence[int] = ()) -> None:
        if len(circles) != len(motions):
            raise ValueError(f'{len(circles)} circles but {len(motions)} motions')
        self.indices: tuple[int, ...] = tuple(indices) if indices else tuple(range(len(circles)))
        self.names: tuple[str, ...] = tuple(mover_name(i) for i in self.indices)
        self.radii: FloatArray = np.array([c.radius for c in circles], dtype=float)
        self.speeds: FloatArray = np.array([m.speed for m in motions], dtype=float)
        n_vertices = 1 + max((len(m.waypoints) for m in motions), default=0)
        vertices = np.zeros((len(circles), n_vertices, 2))
        for k, (circle, motion) in enumerate(zip(circles, motions)):
            path = [circle.center, *motion.waypoints]
            vertices[k, :len(path)] = path
            vertices[k, len(path):] = path[-1]
        self.vertices: FloatArray = vertices                                 # (m, V, 2)
        steps = np.diff(vertices, axis=1)                                    # (m, V - 1, 2)
        lengths = np.sqrt((steps ** 2).sum(axis=-1))
        self.cumulative: FloatArray = np.concatenate([np.zeros((len(circles), 1)), np.cumsum(lengths, axis=1)],
                                                     axis=1)                 # (m, V): arc length at each vertex
        self.lengths: FloatArray = self.cumulative[:, -1] if len(circles) else np.zeros(0)   # L per mover
        self._steps, self._step_lengths = steps, lengths

    def __len__(self) -> int:
        return len(self.radii)

    def subset(self, keep: NDArray[np.bool_]) -> Movers:
        chosen = Movers.__new__(Movers)
        chosen.indices = tuple(i for i, k in zip(self.indices, keep) if k)
        chosen.names = tuple(n for n, k in zip(self.names, keep) if k)
        for name in ('radii', 'speeds', 'vertices', 'cumulative', 'lengths', '_steps', '_step_lengths'):
            setattr(chosen, name, getattr(self, name)[keep])
        return chosen

    def arc_lengths(self, t: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """(arc length along the polyline, direction +1 out / -1 back) of every mover at times t: (..., m)."""
        times = np.asarray(t, dtype=float)[..., None]
        period = 2.0 * self.lengths
        moving = period > 0.0
        s = np.mod(self.speeds * times, np.where(moving, period, 1.0))       # s = (speed t) mod 2L
        s = np.where(moving, s, 0.0)
        out = s <= self.lengths
        return np.where(out, s, period - s), np.where(out, 1.0, -1.0)

    def _locate(self, arc: FloatArray) -> tuple[FloatArray, FloatArray]:
        """The segment index (..., m) each arc length lies on (the last segment whose start it has reached,
        among segments of positive length) and the fraction along it."""
        n_segments = self._steps.shape[1]
        if n_segments == 0:
            return np.zeros(arc.shape, dtype=int), np.zeros(arc.shape)
        starts = self.cumulative[:, :-1]                                     # (m, V - 1)
        positive = self._step_lengths > 0.0
        reached = (starts <= arc[..., None]) & positive                      # (..., m, V - 1)
        # The last positive segment whose start is reached; arc = L (the far end) stays on the last one.
        index = np.where(reached.any(axis=-1), n_segments - 1 - np.argmax(reached[..., ::-1], axis=-1), 0)
        length = np.take_along_axis(np.broadcast_to(self._step_lengths, arc.shape + (n_segments,)),
                                    index[..., None], axis=-1)[..., 0]
        start = np.take_along_axis(np.broadcast_to(starts, arc.shape + (n_segments,)), index[..., None],
                                   axis=-1)[..., 0]
        fraction = np.where(length > 0.0, (arc - start) / np.where(length > 0.0, length, 1.0), 0.0)
        return index, np.clip(fraction, 0.0, 1.0)

    def _in_chunks(self, method: Callable[[FloatArray], FloatArray], t: ArrayLike) -> FloatArray:
        """method over times t (any shape) in chunks of at most LOOKUP_ELEMENTS compared elements."""
        times = np.asarray(t, dtype=float)
        per_time = max(1, len(self) * self._steps.shape[1])
        size = max(1, LOOKUP_ELEMENTS // per_time)
        if times.size <= size:
            return method(times)
        flat = times.reshape(-1)
        parts = [method(flat[k:k + size]) for k in range(0, len(flat), size)]
        out: FloatArray = np.concatenate(parts).reshape(times.shape + (len(self), 2))
        return out

    def positions(self, t: ArrayLike) -> FloatArray:
        """Centres (..., m, 2) of every mover at times t (a scalar or an array of shape (...))."""
        return self._in_chunks(self._positions, t)

    def velocities(self, t: ArrayLike) -> FloatArray:
        """Velocities (..., m, 2) at times t: speed along the current segment, outward or back (zero for a
        mover whose polyline has no length). At a vertex, the segment it is entering."""
        return self._in_chunks(self._velocities, t)

    def _positions(self, t: FloatArray) -> FloatArray:
        arc, _ = self.arc_lengths(t)
        index, fraction = self._locate(arc)
        mover = np.arange(len(self))
        start = self.vertices[mover, index]                                  # (..., m, 2)
        step = self._steps[mover, index] if self._steps.shape[1] else np.zeros_like(start)
        out: FloatArray = start + fraction[..., None] * step
        return out

    def _velocities(self, t: FloatArray) -> FloatArray:
        arc, direction = self.arc_lengths(t)
        # On the way back the mover enters the segment that ends at its arc length: look a hair behind it.
        index, _ = self._locate(np.where(direction > 0.0, arc, np.maximum(arc - 1e-12 * (1.0 + arc), 0.0)))
        mover = np.arange(len(self))
        if not self._steps.shape[1]:
            return np.zeros(arc.shape + (2,))
        step = self._steps[mover, index]
        length = self._step_lengths[mover, index]
        unit = step / np.where(length > 0.0, length, 1.0)[..., None]
        out: FloatArray = (self.speeds * direction)[..., None] * unit
        return out


@dataclass(frozen=True)
class PlannerMap:
    """What a planner is given in one run: the still map, and the known movers with their map errors."""

    world: World                       # known still obstacles, misplaced ones where the map says
    movers: Movers                     # known movers (true motion; the planner sees only each tick's state)
    offsets: FloatArray                # (known movers, 2): each known mover's map error

    def others(self, t: float) -> list[OtherRobot]:
        """The known movers at time t as the planner sees them: OtherRobot('mover K', position, velocity,
        radius), the position with its map error."""
        if not len(self.movers):
            return []
        positions = self.movers.positions(t) + self.offsets
        velocities = self.movers.velocities(t)
        return [OtherRobot(name, (float(p[0]), float(p[1])), (float(v[0]), float(v[1])), float(r), mover=True)
                for name, p, v, r in zip(self.movers.names, positions, velocities, self.movers.radii)]


@dataclass(frozen=True)
class DynamicWorld:
    """A scenario's obstacles over time (module docstring): the truth, and the planner's map drawn from it."""

    workspace: tuple[float, float, float, float]
    obstacles: tuple[ObstacleSpec, ...]
    still: World = field(init=False, compare=False)        # every still obstacle at its true place
    movers: Movers = field(init=False, compare=False)      # every moving circle, known or not
    known_movers: NDArray[np.bool_] = field(init=False, compare=False)

    def __post_init__(self) -> None:
        still = tuple(o.shape for o in self.obstacles if o.still)
        moving = [(i, o) for i, o in enumerate(self.obstacles) if not o.still]
        circles = [o.shape for _, o in moving if isinstance(o.shape, Circle)]
        motions = [o.motion for _, o in moving if o.motion is not None]
        object.__setattr__(self, 'still', World(self.workspace, still))
        object.__setattr__(self, 'movers', Movers(circles, motions, [i for i, _ in moving]))
        object.__setattr__(self, 'known_movers', np.array([o.known for _, o in moving], dtype=bool))

    def scan(self, spec: LaserSpec, pose: Sequence[float], t: float, rng: np.random.Generator | None = None,
             robots: tuple[ArrayLike, ArrayLike] | None = None) -> Scan:
        """What a scanner at `pose` (x, y, heading) sees of the truth at time t: every still obstacle where it
        is (known or not), every mover where it is at t, and `robots` (centres (n, 2), radii (n,): the other
        robots, not the scanning one) as circles."""
        obstacles = self.still.obstacles
        centres = [obstacles.centers, self.movers.positions(t).reshape(-1, 2)]
        radii = [obstacles.radii, self.movers.radii]
        if robots is not None:
            centres.append(np.asarray(robots[0], dtype=float).reshape(-1, 2))
            radii.append(np.asarray(robots[1], dtype=float).reshape(-1))
        return laser.scan(spec, pose, rng, t, np.concatenate(centres), np.concatenate(radii), obstacles.starts,
                          obstacles.ends)

    @property
    def is_static(self) -> bool:
        """Is this a v1 world (every obstacle still, known and exactly placed)?"""
        return all(o.v1 for o in self.obstacles)

    def planner_map(self, rng: np.random.Generator) -> PlannerMap:
        """The map a planner is given: known obstacles only, misplaced ones moved by errors drawn from rng.

        Draw order: one row of four standard normals per known obstacle with position_sigma > 0, in file order
        (a circle uses the first two: its centre's x, y error; a segment all four: its start's and its end's),
        scaled by the obstacle's sigma. A mover's error is drawn the same way, once, and shifts every position
        the map reports of it.
        """
        misplaced = [i for i, o in enumerate(self.obstacles) if o.known and o.position_sigma > 0.0]
        errors = rng.standard_normal((len(misplaced), 4)) if misplaced else np.zeros((0, 4))
        error_of = {i: errors[k] * self.obstacles[i].position_sigma for k, i in enumerate(misplaced)}
        believed: list[Obstacle] = []
        offsets = []
        for i, spec in enumerate(self.obstacles):
            if not spec.known:
                continue
            e = error_of.get(i, np.zeros(4))
            if not spec.still:
                offsets.append(e[:2])
            elif i not in error_of:
                believed.append(spec.shape)
            elif isinstance(spec.shape, Circle):
                c = spec.shape.center
                believed.append(Circle((float(c[0] + e[0]), float(c[1] + e[1])), spec.shape.radius))
            else:
                assert isinstance(spec.shape, Segment)
                a, b = spec.shape.start, spec.shape.end
                believed.append(Segment((float(a[0] + e[0]), float(a[1] + e[1])),
                                        (float(b[0] + e[2]), float(b[1] + e[3]))))
        return PlannerMap(World(self.workspace, tuple(believed)), self.movers.subset(self.known_movers),
                          np.array(offsets, dtype=float).reshape(-1, 2))
