"""The planner's world, built from its messages off the control path.

A /map of a million cells or an /obstacles message of thousands of markers takes seconds to turn into a world
(every wall is a Python object); the control tick must go on commanding meanwhile. So the executor only takes
what came (a grid's cells copied: msg_tools.occupancy_grid.grid_copy; a MarkerArray as received) into a `WorldJob`
and hands it to `WorldBuilder`, a thread of its own that runs `build`: the walls (merged cells beyond
WORLD_OBSTACLES_MAX), or a refusal, and the World. The executor takes the result on a wall timer of its own, on
only while a build is under way (rclpy's EventsExecutor has no guard conditions to be woken by), and adopts it as
any world: PlannerNode.change(AdoptWorld), between two planning passes.

Each job carries the newest of every input and a generation number: a job still waiting is replaced by a newer
one, and a result that is not of the newest job is dropped, so a map being built never replaces one that came
after it. A job of at most INLINE_WORLD_ITEMS items is built on the executor at once (fastep_ros.planner_inputs).
No ROS here but the timer the planner makes for it.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass
from typing import Any, Callable, Sequence

from visualization_msgs.msg import Marker, MarkerArray

from fastep_core.geometry import Obstacle
from fastep_core.world import World
from fastep_ros.limits import WORLD_OBSTACLES_MAX
from msg_tools import convert
from msg_tools.occupancy_grid import OCCUPIED_THRESHOLD, GridCopy

__all__ = ['BuiltWorld', 'WorldBuilder', 'WorldJob', 'build', 'marker_items']


def marker_items(msg: MarkerArray, enough: int) -> int:
    """Markers plus line points of an /obstacles message, counted up to `enough` markers (then the markers alone:
    more than enough either way)."""
    markers = msg.markers
    if len(markers) > enough:
        return len(markers)
    return len(markers) + sum(len(m.points) for m in markers)


@dataclass(frozen=True)
class WorldJob:
    """What a world is built of: its workspace and one source of obstacles (a grid's cells, an /obstacles message,
    or obstacles already made when only the workspace changed)."""

    generation: int
    workspace: tuple[float, float, float, float]
    source: str                                    # the topic the obstacles came on
    grid: GridCopy | None = None                   # obstacle_source map: walls of its occupied cells
    markers: MarkerArray | None = None             # /obstacles: read with msg_tools.convert
    obstacles: tuple[Obstacle, ...] | None = None  # made before
    occupied_threshold: int = OCCUPIED_THRESHOLD
    max_obstacles: int = WORLD_OBSTACLES_MAX

    def items(self, enough: int) -> int:
        """The work it is (cells, markers and points, or obstacles), counted up to about `enough`."""
        if self.grid is not None:
            return self.grid.cells
        if self.markers is not None:
            return marker_items(self.markers, enough)
        return len(self.obstacles or ())


@dataclass(frozen=True)
class BuiltWorld:
    """A job's world, or why there is none (`refused`: the world before is kept)."""

    generation: int
    source: str
    world: World | None
    occupied: Callable[[Sequence[float]], bool] | None = None   # obstacle_source map: is a point occupied
    problem: str = ''   # what was refused or coarsened ('' when the message was taken as it is)

    @property
    def refused(self) -> bool:
        return self.world is None


def _described(msg: MarkerArray) -> int:
    """Obstacles an /obstacles message describes at most (each cylinder one, each pair of line points one)."""
    return sum(1 if m.type == Marker.CYLINDER else len(m.points) // 2 for m in msg.markers
               if m.action not in (Marker.DELETE, Marker.DELETEALL))


def build(job: WorldJob) -> BuiltWorld:
    """The world of a job (no ROS, no node state: runs on any thread). ValueError from reading a message is a
    refusal too, in its own words."""
    occupied = None
    problem = ''
    try:
        if job.grid is not None:
            walls = convert.grid_walls(job.grid, job.occupied_threshold, job.max_obstacles)
            obstacles: Sequence[Obstacle] = walls.walls
            occupied, problem = walls.occupied, walls.coarsened(job.grid)
        elif job.markers is not None:
            described = _described(job.markers)
            if described > job.max_obstacles:
                return BuiltWorld(job.generation, job.source, None, problem=(
                    f'{described:,} obstacles, more than the {job.max_obstacles:,} a world may have'))
            obstacles = convert.marker_array_to_obstacles(job.markers)
        else:
            obstacles = job.obstacles or ()
    except ValueError as exc:
        return BuiltWorld(job.generation, job.source, None, problem=str(exc))
    return BuiltWorld(job.generation, job.source, World.from_obstacles(job.workspace, obstacles), occupied, problem)


class WorldBuilder:
    """A thread building the newest job submitted (a job still waiting is replaced); `take` gives the newest
    result once (None until there is one)."""

    def __init__(self, log_error: Callable[[str], Any]) -> None:
        self._log_error = log_error
        self._wake = threading.Condition()
        self._job: WorldJob | None = None
        self._result: BuiltWorld | None = None
        self._running: WorldJob | None = None
        self._stopping = False
        self._thread = threading.Thread(target=self._run, name='world builder', daemon=True)
        self._thread.start()

    def submit(self, job: WorldJob) -> None:
        with self._wake:
            self._job = job
            self._wake.notify()

    @property
    def busy(self) -> bool:
        """A job waits, runs, or has a result not taken yet."""
        with self._wake:
            return self._job is not None or self._running is not None or self._result is not None

    def take(self) -> BuiltWorld | None:
        with self._wake:
            result, self._result = self._result, None
        return result

    def stop(self, timeout: float = 5.0) -> None:
        """End the thread after the build under way (waits at most `timeout` seconds for it)."""
        with self._wake:
            self._stopping = True
            self._wake.notify()
        self._thread.join(timeout)

    def _run(self) -> None:
        while True:
            with self._wake:
                while not (self._stopping or self._job is not None):
                    self._wake.wait()
                job = self._job
                if self._stopping or job is None:
                    return
                self._running, self._job = job, None
            try:
                result = build(job)
            except Exception as exc:  # noqa: BLE001  the thread must outlive any fault of a build
                result = BuiltWorld(job.generation, job.source, None, problem=f'could not be built: {exc}')
                self._log_error(f'world builder: {job.source}: {exc}')
            with self._wake:
                self._running = None
                if self._result is None or self._result.generation < result.generation:
                    self._result = result
