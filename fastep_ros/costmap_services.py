"""Nav2's costmap-clearing services, served by the planner: what the laser added to the planner's belief forgotten.

fastep keeps no costmap. Its planner believes a world of shapes (fastep_core/perception/belief.py): the map's
obstacles, less those a scan saw through, plus what its scans added (walls, still circles, the tracks of things
seen, movers among them). Clearing forgets what the scans added, in the region asked, and keeps the map's
obstacles: the next scans add again what is still there. Nav2's costmaps do the same to their clearable layers
(obstacle, voxel) and leave the static layer alone (nav2_costmap_2d/src/clear_costmap_service.cpp). The local and
the global costmap are one belief here: clearing either forgets from it.

Served on the navigation node (`<planner>_navigation`, in the planner's namespace; fastep_ros/action_thread.py),
with the names nav2_simple_commander's BasicNavigator calls and those Nav2's costmap nodes offer:

- `global_costmap/clear_entirely_global_costmap`, `local_costmap/clear_entirely_local_costmap`
  (nav2_msgs/srv/ClearEntireCostmap): everything the laser added;
- `local_costmap/clear_costmap_around_robot` (BasicNavigator's), `local_costmap/clear_around_local_costmap`,
  `global_costmap/clear_around_global_costmap` (ClearCostmapAroundRobot): inside the square of side
  `reset_distance` centred on the robot, axis-aligned in the map frame (Nav2's square: its corners at the robot's
  position -/+ reset_distance / 2);
- `local_costmap/clear_costmap_except_region`, `local_costmap/clear_except_local_costmap`,
  `global_costmap/clear_except_global_costmap` (ClearCostmapExceptRegion): outside that square.

A wall crossing the square's edge is cut there (its part on the cleared side forgotten); a circle or a track goes
with its centre. The belief is the planning side's (fastep_ros/planner_threads.py): a request is taken on the
action thread, handed to the executor (`check`, every control tick), which reads the robot's position and asks
the planning side (ForgetSeen, applied between two passes by PlannerNode.apply); the answer goes once it was
applied, or after CLEAR_WAIT wall seconds with a warning (a pass under way that does not end: it is applied when
the pass ends). The responses are empty, as Nav2's; the log says what was forgotten.

Also `local_costmap/clear_costmap_around_pose` (BasicNavigator's), `local_costmap/clear_around_pose_local_costmap`,
`global_costmap/clear_around_pose_global_costmap` (Nav2's; ClearCostmapAroundPose): inside the square of side
`reset_distance` centred on the given pose, put into the map frame through TF on the executor (a frame TF does not
resolve: nothing cleared, a warning, as Nav2's "pose cannot be transformed").

And `global_costmap/get_costmap`, `local_costmap/get_costmap` (GetCostmap): the belief drawn onto a grid of Nav2's
costs (fastep_ros/costmap_grid.py): the world of the newest planning pass (PassResult.plan.world, an immutable
value; lock step: the navigator's) and its tracked movers, the global grid over the workspace, the local one a
LOCAL_SIZE window round the robot. The executor hands the snapshot over (`check`); the grid is drawn on a worker
thread of its own (GridWorker: 20-50 ms for a 20 m x 20 m map at 0.05 m with some 100 obstacles, 0.1-0.5 s
with 1,000 walls or 4 million cells: too long for the action thread, which answers goals meanwhile) and the
service awaits it.
"""

from __future__ import annotations

import array
import concurrent.futures
import functools
import math
import queue
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Generator, Sequence

import numpy as np
from numpy.typing import NDArray

from fastep_core.geometry import Circle, Obstacle, Obstacles, Segment
from fastep_core.perception.belief import Belief, BelievedWorld, Perception, track_name
from fastep_core.planning.navigator import Navigator
from fastep_core.planning.others import OtherRobot
from fastep_core.planning.outline import planning_radius
from fastep_core.world import World
from fastep_ros import costmap_grid
from fastep_ros.companion import CompanionServers
from fastep_ros.path_actions import poses_in_map
from fastep_ros.planner_threads import ForgetSeen

__all__ = ['CLEAR_WAIT', 'GRIDS', 'GRID_WAIT', 'MIN_PIECE', 'SERVICES', 'CostmapServices', 'Forgotten',
           'GridInputs', 'draw_costmap', 'forget_seen']

CLEAR_WAIT = 5.0   # wall seconds a service waits for the planning side to apply its clearing, then answers anyway
GRID_WAIT = 5.0    # wall seconds get_costmap waits for the executor's snapshot (one control tick), then answers empty
MIN_PIECE = 0.01   # m: a wall's piece left shorter than this at the region's edge is forgotten with the rest

ENTIRELY, AROUND, EXCEPT, AROUND_POSE = 'entirely', 'around', 'except', 'around_pose'
GLOBAL, LOCAL = 'global', 'local'
# (service name, relative to the node: resolved in the planner's namespace; nav2_msgs.srv type; what it clears)
SERVICES: tuple[tuple[str, str, str], ...] = (
    ('global_costmap/clear_entirely_global_costmap', 'ClearEntireCostmap', ENTIRELY),
    ('local_costmap/clear_entirely_local_costmap', 'ClearEntireCostmap', ENTIRELY),
    ('local_costmap/clear_costmap_around_robot', 'ClearCostmapAroundRobot', AROUND),          # BasicNavigator's
    ('local_costmap/clear_costmap_except_region', 'ClearCostmapExceptRegion', EXCEPT),        # BasicNavigator's
    ('local_costmap/clear_around_local_costmap', 'ClearCostmapAroundRobot', AROUND),          # Nav2 costmap's own
    ('local_costmap/clear_except_local_costmap', 'ClearCostmapExceptRegion', EXCEPT),
    ('global_costmap/clear_around_global_costmap', 'ClearCostmapAroundRobot', AROUND),
    ('global_costmap/clear_except_global_costmap', 'ClearCostmapExceptRegion', EXCEPT),
    ('local_costmap/clear_costmap_around_pose', 'ClearCostmapAroundPose', AROUND_POSE),       # BasicNavigator's
    ('local_costmap/clear_around_pose_local_costmap', 'ClearCostmapAroundPose', AROUND_POSE),  # Nav2 costmap's own
    ('global_costmap/clear_around_pose_global_costmap', 'ClearCostmapAroundPose', AROUND_POSE),
)
# (service name, which grid) of nav2_msgs/srv/GetCostmap: BasicNavigator's names, and Nav2's costmap nodes' own
GRIDS: tuple[tuple[str, str], ...] = (('global_costmap/get_costmap', GLOBAL), ('local_costmap/get_costmap', LOCAL))


@dataclass(frozen=True)
class Forgotten:
    """What one clearing forgot of what the laser added, and what of it stayed (outside the region)."""

    walls: int = 0     # wall segments forgotten whole
    cut: int = 0       # walls cut at the region's edge (their part in it forgotten)
    circles: int = 0   # still circles believed for good (tracks that stood still)
    tracks: int = 0    # tracks of things seen (those standing in the world as circles, movers, new ones)
    movers: int = 0    # of those tracks, movers
    kept: int = 0      # walls, circles and tracks of what the laser added that stay
    why: str = ''      # why nothing was asked of the planning side ('' when it was)

    def __str__(self) -> str:
        if self.why:
            return f'nothing cleared: {self.why}'
        if not (self.walls or self.cut or self.circles or self.tracks or self.kept):
            return 'nothing to forget: the belief is the map (the laser added nothing)'
        cut = f' ({self.cut} more cut at the edge)' if self.cut else ''
        return f'forgot {_count(self.walls, "wall")}{cut}, {_count(self.circles, "circle")} and ' \
               f'{_count(self.tracks, "track")} ({_count(self.movers, "mover")}) the laser added; ' \
               f'{self.kept} kept, the map\'s obstacles kept'


def _count(n: int, what: str) -> str:
    return f'{n} {what}{"" if n == 1 else "s"}'


# ------------------------------------------------------------------------------------------------ the planning side
def forget_seen(perception: Perception | None, navigator: Navigator | None, centre: Sequence[float], side: float,
                inside: bool) -> Forgotten:
    """ForgetSeen, on the planning side (PlannerNode.apply): forget what the laser added to `perception`'s belief
    inside the square of side `side` centred at `centre` (`inside` false: outside it), the map's obstacles kept; the
    navigator plans in the belief left from now on. What was forgotten."""
    if perception is None:
        return Forgotten()   # no scan perceived yet: the belief is the map
    half = 0.5 * side
    lo = np.array([centre[0] - half, centre[1] - half], dtype=float)
    hi = np.array([centre[0] + half, centre[1] + half], dtype=float)

    def cleared(points: NDArray[np.float64]) -> NDArray[np.bool_]:
        """Which of these centres (n, 2) are on the side cleared."""
        within = np.all((lo <= points) & (points <= hi), axis=1) if len(points) else np.zeros(0, dtype=bool)
        return np.asarray(within == inside)

    # Still circles and walls the scans added (seen_items), the walls cut at the square's edge.
    items = perception.seen_items
    circles = [(k, o.center) for k, o in enumerate(items) if isinstance(o, Circle)]
    walls = [(k, (o.start, o.end)) for k, o in enumerate(items) if isinstance(o, Segment)]
    gone = np.zeros(len(items), dtype=bool)
    if circles:
        gone[[k for k, _ in circles]] = cleared(np.array([c for _, c in circles], dtype=float))
    pieces: dict[int, list[Segment]] = {}
    cut = 0
    if walls:
        ends = np.array([e for _, e in walls], dtype=float)
        for (k, _), kept in zip(walls, _kept_pieces(ends[:, 0], ends[:, 1], lo, hi, inside)):
            if kept is None:
                continue   # untouched: the same object (the world stays the same where nothing changed)
            gone[k] = True
            if kept:
                pieces[k] = kept
                cut += 1
    left: list[Obstacle] = []
    for k, item in enumerate(items):
        left.extend(pieces.get(k, ()) if gone[k] else (item,))
    # Tracks (movers, standing circles in the world, tentative ones): by their estimated centre.
    tracker = perception.tracker
    dropped_tracks = cleared(tracker.states[:, :2])
    ids = {int(i) for i in tracker.ids[dropped_tracks]}
    movers = int(np.count_nonzero(dropped_tracks & tracker.confirmed & tracker.moved))
    tracker.keep(~dropped_tracks)
    perception.standing = {i: c for i, c in perception.standing.items() if i not in ids}
    perception.slow_since = {i: s for i, s in perception.slow_since.items() if i not in ids}
    perception.seen_items = left
    forgotten = Forgotten(walls=sum(1 for k, _ in walls if gone[k]) - cut, cut=cut,
                          circles=sum(1 for k, _ in circles if gone[k]), tracks=len(ids), movers=movers,
                          kept=len(left) + len(tracker))
    _believe_again(perception)
    if navigator is not None and navigator.from_scans:
        navigator.take_perception(navigator.guard_inputs, perception.world)   # the guard's returns: the scan's own
    return forgotten


def _kept_pieces(starts: NDArray[np.float64], ends: NDArray[np.float64], lo: NDArray[np.float64],
                 hi: NDArray[np.float64], inside: bool) -> list[list[Segment] | None]:
    """For each wall start -> end: None where the clearing leaves it whole, else what is left of it (pieces of
    MIN_PIECE or more; empty: forgotten whole). The part inside the box [lo, hi] is [t0, t1] along the wall
    (Liang-Barsky, all walls at once, an axis at a time)."""
    run = ends - starts
    t0, t1 = np.zeros(len(starts)), np.ones(len(starts))
    for axis in (0, 1):
        a, d = starts[:, axis], run[:, axis]
        flat = d == 0.0
        with np.errstate(divide='ignore', invalid='ignore'):
            ta, tb = (lo[axis] - a) / d, (hi[axis] - a) / d
        within = (lo[axis] <= a) & (a <= hi[axis])
        t0 = np.maximum(t0, np.where(flat, np.where(within, -np.inf, np.inf), np.minimum(ta, tb)))
        t1 = np.minimum(t1, np.where(flat, np.where(within, np.inf, -np.inf), np.maximum(ta, tb)))
    length = np.hypot(run[:, 0], run[:, 1])
    crosses = t1 - t0 > 0.0
    out: list[list[Segment] | None] = []
    for k in range(len(starts)):   # one small list per wall: the pieces are objects of their own
        if inside:
            spans = [(0.0, float(t0[k])), (float(t1[k]), 1.0)] if crosses[k] else None
        else:
            spans = [(float(t0[k]), float(t1[k]))] if crosses[k] else []
        if spans is not None and not inside and spans == [(0.0, 1.0)]:
            spans = None   # wholly inside the region kept
        if spans is None:
            out.append(None)
            continue
        out.append([_piece(starts[k], run[k], u, v) for u, v in spans if (v - u) * length[k] >= MIN_PIECE])
    return out


def _piece(start: NDArray[np.float64], run: NDArray[np.float64], u: float, v: float) -> Segment:
    p, q = start + u * run, start + v * run
    return Segment((float(p[0]), float(p[1])), (float(q[0]), float(q[1])))


def _believe_again(perception: Perception) -> None:
    """The belief after a clearing: its world the map's obstacles still believed and what the laser added that
    stays (a new World only when that changed: planners replan on it), its movers the tracks left."""
    items = tuple(perception.map_items + perception.seen_items + list(perception.standing.values()))
    if tuple(map(id, items)) != tuple(map(id, perception.world.obstacle_list)):
        perception.world = BelievedWorld(perception.map_world.workspace, items, items[len(perception.map_items):],
                                         perception.map_world.obstacle_list)
    tracker = perception.tracker
    moving = np.flatnonzero(tracker.confirmed & tracker.moved)
    movers = tuple(OtherRobot(track_name(int(tracker.ids[k])), (float(tracker.states[k, 0]),
                                                                float(tracker.states[k, 1])),
                              (float(tracker.states[k, 2]), float(tracker.states[k, 3])), float(tracker.radii[k]),
                              mover=True) for k in moving)
    old = perception.belief
    perception.belief = Belief(old.t, perception.world, tuple(perception.map_items),
                               tuple(perception.seen_items + list(perception.standing.values())), old.dropped,
                               movers, np.zeros((0, 2)))


# ------------------------------------------------------------------------------------------------ the servers
@dataclass
class Ask:
    """One clearing asked (on the action thread), until the planning side applied it."""

    name: str
    kind: str                   # ENTIRELY, AROUND, EXCEPT or AROUND_POSE
    side: float                 # the square's side (m; inf: everywhere)
    done: Any                   # an rclpy Future: set to the Forgotten once applied (or why not)
    gave_up: list[bool] = field(default_factory=list)   # the service answered before it was applied
    pose: Any = None            # AROUND_POSE: the geometry_msgs/PoseStamped to clear around (in its frame)


@dataclass(frozen=True)
class GridInputs:
    """What one grid is drawn from, taken on the executor: the world of the newest pass, the movers then tracked,
    the robot's planning radius, the window (in the map frame) and the stamp (the node's time, sec and nanosec)."""

    world: World
    movers: tuple[OtherRobot, ...]
    radius: float
    window: costmap_grid.Window
    frame_id: str
    stamp: tuple[int, int]


@dataclass
class GridAsk:
    """One get_costmap request (on the action thread), until the executor handed its inputs over."""

    name: str
    which: str                  # GLOBAL or LOCAL
    resolution: float           # m a cell, as asked (or the default)
    done: Any                   # an rclpy Future: set to the GridInputs, or to why there is no grid (a str)


class CostmapServices(CompanionServers):
    """The clearing and get_costmap services (module docstring): serves no actions (`served` empty); its services
    are on the navigation node, in a callback group of their own (a request waiting for the planning side holds
    its group: in the node's default one it would hold the action servers' goal and cancel requests as long);
    its grids are drawn on a worker thread of its own (`drawer`)."""

    served: dict[str, Any] = {}

    def __init__(self, actions: Any) -> None:
        """`actions`: the planner's NavigateActions (fastep_ros.navigate_actions), which makes this."""
        super().__init__(actions)
        from nav2_msgs import srv
        from rclpy.callback_groups import ReentrantCallbackGroup
        self.clock: Callable[[], float] = time.monotonic   # the wait's clock (wall, as the navigation node's)
        self.asked: queue.SimpleQueue[Ask] = queue.SimpleQueue()   # action thread -> executor (check)
        self.group = ReentrantCallbackGroup()
        self.handlers: dict[str, Callable[[Any, Any], Any]] = {}
        self.services: list[Any] = []
        for name, kind_name, kind in SERVICES:
            handler = self.handlers[name] = self._handler(name, kind)
            self.services.append(actions.side.node.create_service(getattr(srv, kind_name), name, handler,
                                                                  callback_group=self.group))
        self.grids: queue.SimpleQueue[GridAsk] = queue.SimpleQueue()   # action thread -> executor (check)
        self.drawer = concurrent.futures.ThreadPoolExecutor(max_workers=1, thread_name_prefix='costmaps')
        for name, which in GRIDS:
            handler = self.handlers[name] = self._grid_handler(name, which)
            self.services.append(actions.side.node.create_service(srv.GetCostmap, name, handler,
                                                                  callback_group=self.group))

    # On the action thread.
    def _handler(self, name: str, kind: str) -> Callable[[Any, Any], Any]:
        async def clear(request: Any, response: Any) -> Any:
            from rclpy.task import Future
            logger = self.node.get_logger()
            side = math.inf if kind == ENTIRELY else float(request.reset_distance)
            if not self.node.lifecycle.is_active:
                logger.warning(f'{name}: nothing cleared: the planner is not active (lifecycle)')
                return response
            if math.isnan(side) or side < 0.0:
                logger.warning(f'{name}: nothing cleared: reset_distance {side:g} is not a distance (finite or '
                               f'inf, >= 0)')
                return response
            ask = Ask(name, kind, side, Future(), pose=request.pose if kind == AROUND_POSE else None)
            self.asked.put(ask)
            deadline = self.clock() + CLEAR_WAIT
            await _Until(ask.done, lambda: self.clock() >= deadline)
            if ask.done.done() and ask.done.result().why:
                logger.warning(f'{name}: {ask.done.result()}')
            elif ask.done.done():
                logger.info(f'{name}: {ask.done.result()}')
            else:
                ask.gave_up.append(True)
                logger.warning(f'{name}: answered before it was applied: the planning side did not take it within '
                               f'{CLEAR_WAIT:g} s (a pass under way); it is cleared when that pass ends')
            return response
        return clear

    # On the planner's executor.
    def check(self) -> None:
        """Every control tick: each clearing asked since, handed to the planning side with the region it clears
        (around the robot where it is now, or the pose given, through TF); refused at once where the robot's
        position is not known or the pose's frame does not resolve. Then each get_costmap asked since: its
        snapshot (a few references and the robot's position: nothing drawn here)."""
        while True:
            try:
                ask = self.asked.get_nowait()
            except queue.Empty:
                break
            centre: tuple[float, float] = (0.0, 0.0)
            if ask.kind == AROUND_POSE:
                xy, _, _, problem = poses_in_map(self.node, [ask.pose], 'pose', numbered=False)
                if problem or not np.isfinite(xy[0]).all():
                    why = problem or f'pose ({xy[0, 0]}, {xy[0, 1]}) is not finite'
                    self._answer(ask, Forgotten(why=f'the pose cannot be put in the map frame: {why}'))
                    continue
                centre = (float(xy[0, 0]), float(xy[0, 1]))
            elif ask.kind != ENTIRELY:
                state, problem = self.node.inputs.state(self.node.now())
                if state is None:
                    self._answer(ask, Forgotten(why=f'the robot\'s position is not known ({problem})'))
                    continue
                centre = (float(state[0]), float(state[1]))
            self.node.change(ForgetSeen(centre, ask.side, ask.kind != EXCEPT, functools.partial(self._answer, ask)))
        while True:
            try:
                grid = self.grids.get_nowait()
            except queue.Empty:
                return
            try:
                inputs: GridInputs | str = self._grid_inputs(grid)
            except Exception as exc:  # noqa: BLE001  a fault answers (an empty costmap), never the control tick
                inputs = f'its snapshot failed: {type(exc).__name__}: {(str(exc).splitlines() or [""])[0]}'
            grid.done.set_result(inputs)
            self.actions.side.wake()

    def _answer(self, ask: Ask, forgotten: Forgotten) -> None:
        """Any side: the clearing's result to its service (woken), said here if the service answered already."""
        if ask.done.done():
            return
        ask.done.set_result(forgotten)
        if ask.gave_up:
            self.node.get_logger().info(f'{ask.name}: applied late: {forgotten}')
        self.actions.side.wake()

    def destroy(self) -> None:
        """Cleanup: a clearing or get_costmap not handed over yet answered (nothing cleared, no grid), the drawer
        stopped (a grid under way is left to end on its own); the services go with the node."""
        while True:
            try:
                ask = self.asked.get_nowait()
            except queue.Empty:
                break
            self._answer(ask, Forgotten(why='the planner is shutting down'))
        while True:
            try:
                grid = self.grids.get_nowait()
            except queue.Empty:
                break
            if not grid.done.done():
                grid.done.set_result('the planner is shutting down')
                self.actions.side.wake()
        self.drawer.shutdown(wait=False, cancel_futures=True)

    # get_costmap: on the action thread.
    def _grid_handler(self, name: str, which: str) -> Callable[[Any, Any], Any]:
        async def get_costmap(request: Any, response: Any) -> Any:
            from rclpy.task import Future
            logger = self.node.get_logger()
            asked = float(str(np.float32(request.specs.resolution)))   # float32: the decimal it stands for (0.01)
            resolution = asked if math.isfinite(asked) and asked > 0.0 else costmap_grid.DEFAULT_RESOLUTION
            if asked != 0.0 and resolution != asked:
                logger.warning(f'{name}: resolution {asked:g} is not a cell size (finite, > 0): drawn at '
                               f'{resolution:g} m')
            grid = GridAsk(name, which, resolution, Future())
            self.grids.put(grid)
            deadline = self.clock() + GRID_WAIT
            await _Until(grid.done, lambda: self.clock() >= deadline)
            inputs = grid.done.result() if grid.done.done() else \
                f'the planner did not hand its belief over within {GRID_WAIT:g} s'
            if isinstance(inputs, str):
                logger.warning(f'{name}: an empty costmap: {inputs}')
                response.map.metadata.layer = 'master'
                return response
            window = inputs.window
            if window.coarsened:
                logger.warning(f'{name}: resolution {resolution:g} m would be more than {costmap_grid.MAX_CELLS} '
                               f'cells: drawn at {window.resolution:.6g} m ({window.size_x} x {window.size_y})')
            try:
                drawn = self.drawer.submit(draw_costmap, inputs)
            except RuntimeError:   # the drawer was shut down (cleanup) since the inputs came
                logger.warning(f'{name}: an empty costmap: the planner is shutting down')
                response.map.metadata.layer = 'master'
                return response
            drawn.add_done_callback(lambda _: self.actions.side.wake())
            await _Until(drawn, lambda: False)   # ends: at most MAX_CELLS cells (seconds in the densest beliefs)
            try:
                response.map = drawn.result()
            except (Exception, concurrent.futures.CancelledError) as exc:  # noqa: BLE001  a fault answers, empty
                first = (str(exc).splitlines() or [''])[0]
                logger.error(f'{name}: an empty costmap: drawing it failed: {type(exc).__name__}'
                             f'{": " + first if first else ""}')
                response.map.metadata.layer = 'master'
            return response
        return get_costmap

    # get_costmap: on the planner's executor.
    def _grid_inputs(self, grid: GridAsk) -> GridInputs | str:
        """The snapshot a grid is drawn from (read-only references to immutable values), or why there is none."""
        node = self.node
        now = node.now()
        if node.planning is not None:
            result = node.planning.plan   # read once: a PassResult, replaced whole by the planning thread
            world = None if result is None else result.plan.world
            movers = () if result is None else tuple(result.plan.movers_at(now))
        else:   # no planning thread (lock step): the navigator and perception are the executor's
            world = None if node.navigator is None else node.navigator.world
            movers = tuple(node.inputs.scan_perception.movers(now)) if world is not None else ()
        if world is None:
            return 'no planning pass has made the world known yet'
        if grid.which == LOCAL:
            state, problem = node.inputs.state(now)
            if state is None:
                return f'the robot\'s position is not known ({problem})'
            window = costmap_grid.local_window(world.workspace, state[:2], grid.resolution)
        else:
            window = costmap_grid.global_window(world.workspace, grid.resolution)
        radius = node.radius if node.footprint is None else planning_radius(node.footprint, node.radius)
        whole = math.floor(now) if math.isfinite(now) else 0
        stamp = (int(whole), min(int((now - whole) * 1e9), 999_999_999)) if math.isfinite(now) else (0, 0)
        return GridInputs(world, movers, float(radius), window, node.frame_id, stamp)


def draw_costmap(inputs: GridInputs) -> Any:
    """On the drawer: the grid of `inputs` as nav2_msgs/Costmap, as Nav2's getCostmapCallback fills it (layer
    'master', the origin cell (0, 0)'s corner, identity orientation, map_load_time and update_time the stamp)."""
    from nav2_msgs.msg import Costmap
    window, world = inputs.window, inputs.world
    sets = [world.obstacles]
    if inputs.movers:
        sets.append(Obstacles(Circle(m.position, m.radius) for m in inputs.movers))
    costs = costmap_grid.draw(window, world.workspace, inputs.radius, sets)
    message = Costmap()
    message.header.frame_id = inputs.frame_id
    sec, nanosec = inputs.stamp
    message.header.stamp.sec, message.header.stamp.nanosec = sec, nanosec
    meta = message.metadata
    meta.map_load_time.sec, meta.map_load_time.nanosec = sec, nanosec
    meta.update_time.sec, meta.update_time.nanosec = sec, nanosec
    meta.layer, meta.resolution = 'master', float(window.resolution)
    meta.size_x, meta.size_y = window.size_x, window.size_y
    meta.origin.position.x, meta.origin.position.y = float(window.origin_x), float(window.origin_y)
    meta.origin.orientation.w = 1.0
    message.data = array.array('B', costs.tobytes())   # row-major, (0, 0) first: index y * size_x + x
    return message


class _Until:
    """Awaited: the coroutine resumes each time its executor looks (woken, or every IDLE_WAKE of the action thread),
    until `future` is done or `expired()`."""

    def __init__(self, future: Any, expired: Callable[[], bool]) -> None:
        self.future, self.expired = future, expired

    def __await__(self) -> Generator[None, None, None]:
        while not self.future.done() and not self.expired():
            yield
