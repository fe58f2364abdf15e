"""Nav2's planner_server actions, served by the planner: `compute_path_to_pose`, `compute_path_through_poses`.

nav2_msgs/action/ComputePathToPose and ComputePathThroughPoses with Nav2 Jazzy's definitions, on the planner's
navigation node (fastep_ros/navigate_actions.py), so that nav2_simple_commander's BasicNavigator.getPath and
getPathThroughPoses get the route fastep would drive. The path is the exact shortest route over what the robot
knows (the map's obstacles and what its laser added: the world of the newest planning pass, PassResult.plan.world,
an immutable value), keeping the clearance FAStep-Route keeps (planning/exact_path.exact_path: the planning radius
plus clearance_margin where there is room, down to the radius through a narrow gap; the planning radius of a
footprint is its inscribed radius + FOOTPRINT_MARGIN, planning/outline.py), as nav_msgs/Path in the map frame:
poses PATH_RESOLUTION apart along the exact lines and arcs, each heading along the path, a leg's last pose with its
goal's heading when the goal has one; through poses, the legs joined in order (each via pose once).

Where: the inputs are taken on the planner's executor when the goal is handed over (`start`: the goals and a
`use_start` start put in the map frame through TF, else the robot's pose from odometry and localization, the
radius, the parameters, the world), the path is computed on a thread of its own (PathWorker: an exact path can
take hundreds of milliseconds in clutter, and the control tick runs at 20 Hz), one request at a time, and the goal
is ended on the executor (`check`, every control tick) once the worker is done. A goal canceled ends CANCELED at
once; one not done within planning_timeout (node seconds since it came) ends with TIMEOUT; what the worker still
computes for a goal ended is dropped. As Nav2's servers, each action keeps at most one goal waiting: a newer one
ends the waiting one (ABORTED, error code 0, as Nav2's SimpleActionServer terminates a pending goal).

Error codes (Nav2 Jazzy's, by name: ComputePathToPose's 20x, ComputePathThroughPoses' 30x): TF_ERROR (a frame TF
does not resolve, or no robot pose to start from), START_OUTSIDE_MAP, GOAL_OUTSIDE_MAP, START_OCCUPIED (the start
nearer an obstacle than the radius less exact_path.BACK_OUT, or in an occupied cell of /map), GOAL_OCCUPIED
(nearer than the radius, or in an occupied cell), TIMEOUT, NO_VALID_PATH, NO_VIAPOINTS_GIVEN (no goals), UNKNOWN
(anything else: a value not finite, too many poses, a fault); error_msg says why in one line. planner_id is ignored
(fastep has one planner).
"""

from __future__ import annotations

import functools
import math
import queue
import threading
from dataclasses import dataclass, replace
from typing import Any, Callable, Sequence

import numpy as np
from numpy.typing import NDArray

from fastep_core.errors import GoalError
from fastep_core.planning.outline import planning_radius
from fastep_core.planning.params import PlannerParams
from fastep_core.planning.shortest_path.exact_path import BACK_OUT, exact_path, no_path_reason
from fastep_core.planning.shortest_path.optimal import OptimalPath
from fastep_core.world import World
from fastep_ros.companion import CompanionServers
from fastep_ros.limits import GOAL_POSES_MAX

__all__ = ['MAX_PATH_POSES', 'PATH_RESOLUTION', 'PathActions', 'PathFailure', 'PathRequest', 'PathWorker',
           'compute_path', 'route_poses']

FloatArray = NDArray[np.float64]
TO_POSE, THROUGH_POSES = 'compute_path_to_pose', 'compute_path_through_poses'
PATH_RESOLUTION = 0.05    # m between the path's poses: Nav2's default costmap resolution (its planners, a pose a cell)
MAX_PATH_POSES = 100_000  # poses a path has at most (5 km at PATH_RESOLUTION); a longer one spaces them wider
WORLD_WAIT = 10.0         # node s a goal waits for a planning pass's world when planning_timeout is 0 (never)
WORKER_JOIN = 5.0         # wall s destroy waits for a path being computed (an exact path cannot be interrupted)
CLEARANCE_PAIRS = 1_000_000   # point-obstacle distances computed at a time (8 MB a chunk)


class PathFailure(Exception):
    """No path, for a reason Nav2 has a code for: `code` is the name of the action's result constant."""

    def __init__(self, code: str, message: str) -> None:
        super().__init__(message)
        self.code = code


class PathCanceled(Exception):
    """The goal ended while its path was computed (canceled, timed out, superseded): nothing more to compute."""


@dataclass(frozen=True)
class PathRequest:
    """What one path is computed from, taken on the executor when the goal came (the world: when a pass had made
    one). Positions in the map frame; yaw NaN where none was asked for."""

    start: FloatArray                  # (2,)
    start_yaw: float
    goals: FloatArray                  # (n, 2)
    goal_yaws: FloatArray              # (n,)
    finite_orientations: NDArray[np.bool_]   # (n,): the goals' quaternions are finite
    radius: float                      # the planning radius (a footprint's: outline.planning_radius)
    params: PlannerParams
    frame_id: str
    stamp: tuple[int, int]             # (sec, nanosec): the node's time when the goal came
    through: bool                      # compute_path_through_poses (its goals are numbered in messages)
    occupied: Callable[[Sequence[float]], bool] | None = None   # /map's occupied cells (obstacle_source map)
    world: World | None = None


@dataclass(frozen=True)
class PathOutcome:
    """What the worker leaves for a goal: its path (nav_msgs/Path) or why none (`code`: a result constant's name)."""

    path: Any = None
    code: str = ''
    message: str = ''


@dataclass
class Job:
    """One goal of these actions on the executor. The worker sets `outcome` (once, whole) and `begun`; the executor
    sets `ended` (the worker then drops it, or stops between legs)."""

    goal: Any                          # planner_threads.ActionGoal
    started: float                     # node time it came
    request: PathRequest
    submitted: bool = False
    begun: bool = False
    ended: bool = False
    outcome: PathOutcome | None = None


# ------------------------------------------------------------------------------------------------ the path
def route_poses(path: OptimalPath, spacing: float) -> tuple[FloatArray, FloatArray]:
    """Points (k, 2) along the exact path's lines and arcs, evenly spaced by arc length at most `spacing` apart
    (at most MAX_PATH_POSES + 1), both ends included, and the path's heading at each (k,); a path of no length: its
    one point, heading NaN."""
    pieces = path.pieces
    if not pieces or not path.length > 0.0:
        return np.array(path.points[-1:], dtype=float).reshape(-1, 2), np.full(1, math.nan)
    lengths = np.array([p.length for p in pieces], dtype=float)
    ends = np.cumsum(lengths)
    begins = ends - lengths
    total = float(ends[-1])
    n = int(min(MAX_PATH_POSES, max(1, math.ceil(total / spacing))))
    s = np.linspace(0.0, total, n + 1)
    k = np.minimum(np.searchsorted(ends, s, side='left'), len(pieces) - 1)
    with np.errstate(divide='ignore', invalid='ignore'):
        f = np.clip(np.where(lengths[k] > 0.0, (s - begins[k]) / lengths[k], 0.0), 0.0, 1.0)
    a = np.array([p.start for p in pieces], dtype=float)[k]
    b = np.array([p.end for p in pieces], dtype=float)[k]
    arc = np.array([p.kind == 'arc' for p in pieces])[k]
    centre = np.array([p.center or (0.0, 0.0) for p in pieces], dtype=float)[k]
    radius = np.array([p.radius for p in pieces], dtype=float)[k]
    angle0 = np.array([p.angle0 for p in pieces], dtype=float)[k]
    sweep = np.array([p.sweep for p in pieces], dtype=float)[k]
    t = angle0 + f * sweep
    on_arc = centre + radius[:, None] * np.column_stack([np.cos(t), np.sin(t)])
    on_line = a + f[:, None] * (b - a)
    xy = np.where(arc[:, None], on_arc, on_line)
    heading = np.where(arc, t + np.copysign(0.5 * math.pi, sweep), np.arctan2(b[:, 1] - a[:, 1], b[:, 0] - a[:, 0]))
    xy[0], xy[-1] = path.points[0], path.points[-1]   # the ends exactly (the via poses are the path's)
    return xy, np.angle(np.exp(1j * heading))


def _clearance(world: World, xy: FloatArray) -> FloatArray:
    """Each point's distance to the nearest obstacle surface (inf: none), in chunks of bounded memory."""
    obstacles = world.obstacles
    if not len(obstacles) or not len(xy):
        return np.full(len(xy), math.inf)
    step = max(1, CLEARANCE_PAIRS // len(obstacles))
    return np.concatenate([np.atleast_1d(obstacles.clearance(xy[i:i + step])) for i in range(0, len(xy), step)])


def _check_ends(request: PathRequest, world: World) -> FloatArray:
    """PathFailure for the first start or goal no path can have (Nav2's order: the start, then each goal); the
    start's clearance."""
    r, (x, y) = request.radius, request.start
    xmin, ymin, xmax, ymax = world.workspace
    if not (math.isfinite(x) and math.isfinite(y)):
        raise PathFailure('UNKNOWN', f'start ({x}, {y}) is not finite')
    if not (xmin <= x <= xmax and ymin <= y <= ymax):
        raise PathFailure('START_OUTSIDE_MAP', f'start ({x:g}, {y:g}) is outside the map '
                                               f'[{xmin:g}, {ymin:g}, {xmax:g}, {ymax:g}]')
    if request.occupied is not None and request.occupied((x, y)):
        raise PathFailure('START_OCCUPIED', f'start ({x:g}, {y:g}) is occupied: an occupied cell of /map')
    start_room = _clearance(world, request.start[None, :])
    if start_room[0] < r - BACK_OUT:   # deeper inside than a robot backs out of (exact_path.backed_out)
        raise PathFailure('START_OCCUPIED', _start_occupied(request, float(start_room[0])))
    goals = request.goals
    with np.errstate(invalid='ignore'):
        inside = (xmin <= goals[:, 0]) & (goals[:, 0] <= xmax) & (ymin <= goals[:, 1]) & (goals[:, 1] <= ymax)
    finite = np.isfinite(goals).all(axis=1) & request.finite_orientations
    room = np.full(len(goals), math.inf)
    usable = np.flatnonzero(finite & inside)
    room[usable] = _clearance(world, goals[usable])
    cells = np.zeros(len(goals), dtype=bool)
    if request.occupied is not None:
        # One lookup a pose (the grid's lookup takes one point), over at most GOAL_POSES_MAX poses.
        cells[usable] = [bool(request.occupied(goals[i])) for i in usable]
    bad = np.flatnonzero(~finite | ~inside | (room < r) | cells)
    if len(bad):
        i = int(bad[0])
        what = f'goal {i}' if request.through else 'goal'
        if not finite[i]:
            raise PathFailure('UNKNOWN', f'{what} ({goals[i, 0]}, {goals[i, 1]}) '
                                         f'{"orientation " if np.isfinite(goals[i]).all() else ""}is not finite')
        if cells[i]:
            raise PathFailure('GOAL_OCCUPIED', f'{what} ({goals[i, 0]:g}, {goals[i, 1]:g}) is occupied: an '
                                               f'occupied cell of /map')
        try:
            world.check_point(goals[i], r, what)
        except GoalError as exc:
            raise PathFailure('GOAL_OUTSIDE_MAP' if not inside[i] else 'GOAL_OCCUPIED', str(exc)) from None
    return start_room


def _start_occupied(request: PathRequest, room: float) -> str:
    x, y = request.start
    where = 'inside an obstacle' if room < 0.0 else f'{room:.3g} m from an obstacle, robot radius {request.radius:g} m'
    return f'start ({x:g}, {y:g}) is occupied: {where}'


def compute_path(request: PathRequest, stop: Callable[[], bool]) -> PathOutcome:
    """The path of a request (on the worker): every leg's exact path, sampled and joined, as nav_msgs/Path; a
    PathFailure for a start, goal or leg with none; PathCanceled once `stop()` (between legs)."""
    world = request.world
    assert world is not None
    start_room = _check_ends(request, world)
    points: list[FloatArray] = []
    headings: list[FloatArray] = []
    here, heading = request.start, request.start_yaw
    for i, goal in enumerate(request.goals):
        if stop():
            raise PathCanceled
        found = exact_path(world, here, goal, request.radius, request.params)
        if found is None:
            if i == 0 and start_room[0] < request.radius:
                raise PathFailure('START_OCCUPIED', _start_occupied(request, float(start_room[0])))
            leg = f' (leg {i})' if request.through else ''
            raise PathFailure('NO_VALID_PATH', no_path_reason(request.radius, here, goal, world) + leg)
        xy, along = route_poses(found, PATH_RESOLUTION)
        along = np.where(np.isnan(along), heading if math.isfinite(heading) else 0.0, along)
        if math.isfinite(request.goal_yaws[i]):
            along[-1] = request.goal_yaws[i]
        first = 0 if i == 0 else 1   # a leg after the first starts at the pose the one before ended with
        points.append(xy[first:])
        headings.append(along[first:])
        here, heading = goal, float(along[-1])
    return PathOutcome(path_message(np.concatenate(points), np.concatenate(headings), request.frame_id,
                                    request.stamp))


def path_message(xy: FloatArray, heading: FloatArray, frame_id: str, stamp: tuple[int, int]) -> Any:
    """nav_msgs/Path of these poses, each stamped and framed as the path (as Nav2's planners make theirs)."""
    from geometry_msgs.msg import PoseStamped
    from nav_msgs.msg import Path
    sec, nanosec = stamp
    path = Path()
    path.header.frame_id, path.header.stamp.sec, path.header.stamp.nanosec = frame_id, sec, nanosec
    qz, qw = np.sin(0.5 * heading), np.cos(0.5 * heading)
    poses = []
    # A message object a pose: no vectorised way to make them (about 20 us each, on the worker, not the executor).
    for x, y, z, w in zip(xy[:, 0].tolist(), xy[:, 1].tolist(), qz.tolist(), qw.tolist()):
        pose = PoseStamped()
        header, position, orientation = pose.header, pose.pose.position, pose.pose.orientation
        header.frame_id, header.stamp.sec, header.stamp.nanosec = frame_id, sec, nanosec
        position.x, position.y, orientation.z, orientation.w = x, y, z, w
        poses.append(pose)
    path.poses = poses
    return path


# ------------------------------------------------------------------------------------------------ the worker
class PathWorker:
    """A thread computing one job's path at a time, in the order submitted (a job ended meanwhile is skipped):
    `compute(request, stop)` gives the outcome; a PathFailure is its code and message, any other fault UNKNOWN
    with its first line."""

    def __init__(self, compute: Callable[[PathRequest, Callable[[], bool]], PathOutcome]) -> None:
        self.compute = compute
        self._jobs: queue.SimpleQueue[Job | None] = queue.SimpleQueue()
        self.computing: Job | None = None
        self._thread = threading.Thread(target=self._run, name='paths', daemon=True)
        self._thread.start()

    def submit(self, job: Job) -> None:
        job.submitted = True
        self._jobs.put(job)

    @property
    def idle(self) -> bool:
        """Nothing submitted is left to compute (tests wait for it)."""
        return self.computing is None and self._jobs.empty()

    def stop(self, timeout: float) -> bool:
        """End the thread after the path under way; False if it is still computing after `timeout` seconds."""
        self._jobs.put(None)
        self._thread.join(timeout)
        return not self._thread.is_alive()

    def _run(self) -> None:
        while True:
            job = self._jobs.get()
            if job is None:
                return
            if job.ended:
                continue
            self.computing, job.begun = job, True
            try:
                outcome = self.compute(job.request, functools.partial(getattr, job, 'ended'))
            except PathCanceled:
                outcome = PathOutcome(code='UNKNOWN', message='ended while its path was computed')
            except PathFailure as failure:
                outcome = PathOutcome(code=failure.code, message=str(failure))
            except Exception as exc:  # noqa: BLE001  any fault of a computation ends its goal, never this thread
                first = (str(exc).splitlines() or [''])[0]
                outcome = PathOutcome(code='UNKNOWN', message=f'path computation failed: {type(exc).__name__}'
                                                              f'{": " + first if first else ""}')
            job.outcome = outcome
            self.computing = None


# ------------------------------------------------------------------------------------------------ the servers
class PathActions(CompanionServers):
    """compute_path_to_pose and compute_path_through_poses (see the module docstring). Made with NavigateActions
    in configure; its methods run on the planner's executor, the paths on its PathWorker."""

    def __init__(self, actions: Any) -> None:
        from nav2_msgs.action import ComputePathThroughPoses, ComputePathToPose
        super().__init__(actions)
        self.served = {TO_POSE: ComputePathToPose, THROUGH_POSES: ComputePathThroughPoses}
        self.jobs: list[Job] = []
        self.compute: Callable[[PathRequest, Callable[[], bool]], PathOutcome] = compute_path
        self.worker = PathWorker(lambda request, stop: self.compute(request, stop))

    def fail(self, goal: Any, code: str, message: str) -> None:
        """End `goal` aborted with the action's result constant `code` (a name: 'TF_ERROR', ...) and `message`."""
        self.end(goal, 'aborted', message, int(getattr(self.served[goal.kind].Result, code)))

    def start(self, goal: Any, active: bool) -> None:
        """A goal handed over: its inputs taken now (TF, the robot's pose, the radius, the parameters, the world if
        a pass has made one), then computed on the worker; refused at once for what needs no path to say."""
        node = self.node
        if not active or goal.epoch != self.actions.epoch:
            self.fail(goal, 'UNKNOWN', 'the planner was deactivated')
            return
        msg = goal.handle.request
        through = goal.kind == THROUGH_POSES
        given = list(msg.goals) if through else [msg.goal]
        if not given:
            self.fail(goal, 'NO_VIAPOINTS_GIVEN', 'no viapoints given: goals is empty')
            return
        if len(given) > GOAL_POSES_MAX:
            self.fail(goal, 'UNKNOWN', f'{len(given)} goals, more than the {GOAL_POSES_MAX} a request may have')
            return
        now = node.now()
        if msg.use_start:
            start, start_yaw, _, problem = poses_in_map(node, [msg.start], 'start', numbered=False)
            if problem:
                self.fail(goal, 'TF_ERROR', problem)
                return
            start_xy, heading = start[0], float(start_yaw[0])
        else:
            state, why = node.inputs.state(now)
            if state is None:
                self.fail(goal, 'TF_ERROR', f'no robot pose to start from ({why}); give a start with use_start')
                return
            start_xy = np.array(state[:2], dtype=float)
            heading = float(state[2]) if len(state) > 2 else math.nan
        goals, yaws, finite, problem = poses_in_map(node, given, 'goal', numbered=through)
        if problem:
            self.fail(goal, 'TF_ERROR', problem)
            return
        radius = node.radius if node.footprint is None else planning_radius(node.footprint, node.radius)
        whole = math.floor(now)
        stamp = (int(whole), min(int((now - whole) * 1e9), 999_999_999)) if math.isfinite(now) else (0, 0)
        request = PathRequest(start_xy, heading, goals, yaws, finite, float(radius), node.params, node.frame_id,
                              stamp, through, node.inputs.occupied)
        for waiting in list(self.jobs):   # as Nav2's servers: one goal waiting an action, the newest
            if waiting.goal.kind == goal.kind and not waiting.begun:
                self.finish(waiting, 'aborted', 'preempted by a newer goal before its path was computed', 'NONE')
        job = Job(goal, now, request)
        self.jobs.append(job)
        self.submit_ready(job)

    def world(self) -> World | None:
        """What the robot knows now, as the newest planning pass planned in (an immutable World; lock step: the
        navigator's, which the executor owns then); None before any."""
        node = self.node
        if node.planning is not None:
            result = node.planning.plan   # read once: a PassResult, replaced whole by the planning thread
            return None if result is None else result.plan.world
        return None if node.navigator is None else node.navigator.world

    def submit_ready(self, job: Job) -> None:
        """Hand the job to the worker once a world is known (else it waits for a pass: check)."""
        if job.submitted:
            return
        world = self.world()
        if world is not None:
            job.request = replace(job.request, world=world)
            self.worker.submit(job)

    def check(self) -> None:
        """Every control tick: each goal canceled, deactivated, computed, timed out, or still waiting for a world."""
        if not self.jobs:
            return
        node = self.node
        active, now, timeout = node.lifecycle.is_active, node.now(), node.planning_timeout
        for job in list(self.jobs):
            waited = now - job.started
            if job.goal.handle.is_cancel_requested:
                self.finish(job, 'canceled', 'canceled', 'NONE')
            elif not active:
                self.finish(job, 'aborted', 'the planner was deactivated', 'UNKNOWN')
            elif job.outcome is not None:
                outcome = job.outcome
                if outcome.code:
                    self.finish(job, 'aborted', outcome.message, outcome.code)
                else:
                    self.finish(job, 'succeeded', '', 'NONE', path=outcome.path, planning_time=_duration(waited))
            elif not job.submitted:
                self.submit_ready(job)
                if not job.submitted and waited >= (timeout if timeout > 0.0 else WORLD_WAIT):
                    self.finish(job, 'aborted', f'planning timed out: no planning pass made the world known in '
                                                f'{waited:.1f} s (planning_timeout {timeout:g} s)', 'TIMEOUT')
            elif 0.0 < timeout <= waited:
                self.finish(job, 'aborted', f'planning timed out: no path within {waited:.1f} s (planning_timeout '
                                            f'{timeout:g} s)', 'TIMEOUT')

    def finish(self, job: Job, how: str, message: str, code: str, **fields: Any) -> None:
        """End a job's goal (the worker drops it, or stops it between legs)."""
        job.ended = True
        if job in self.jobs:
            self.jobs.remove(job)
        self.end(job.goal, how, message, int(getattr(self.served[job.goal.kind].Result, code)), **fields)

    def destroy(self) -> None:
        """Every goal ended (aborted), the worker stopped and joined (cleanup, shutdown, destroy_node)."""
        for job in list(self.jobs):
            self.finish(job, 'aborted', 'the planner is shutting down', 'UNKNOWN')
        if not self.worker.stop(WORKER_JOIN):
            self.node.get_logger().warning(f'paths: a path under way did not end within {WORKER_JOIN:g} s; its '
                                           f'thread ends when it is done')


def poses_in_map(node: Any, given: Sequence[Any], what: str, numbered: bool) -> tuple[
        FloatArray, FloatArray, NDArray[np.bool_], str]:
    """PoseStamped messages in the node's map frame (through TF, a frame at a time): positions (n, 2), yaws (n,;
    NaN: a quaternion of zero length, no heading asked for), whether each quaternion is finite, and why not ('':
    every frame resolved)."""
    n = len(given)
    frames = [p.header.frame_id.lstrip('/') for p in given]
    xy = np.array([(p.pose.position.x, p.pose.position.y) for p in given], dtype=float).reshape(n, 2)
    quat = np.array([(p.pose.orientation.x, p.pose.orientation.y, p.pose.orientation.z, p.pose.orientation.w)
                     for p in given], dtype=float).reshape(n, 4)
    finite = np.isfinite(quat).all(axis=1)
    with np.errstate(invalid='ignore'):
        yaw = np.where((quat * quat).sum(axis=1) > 0.0,
                       np.arctan2(2.0 * (quat[:, 3] * quat[:, 2] + quat[:, 0] * quat[:, 1]),
                                  1.0 - 2.0 * (quat[:, 1] ** 2 + quat[:, 2] ** 2)), np.nan)
    for frame in sorted(set(frames) - {'', 'map', node.frame_id}):
        mask = np.array([f == frame for f in frames])
        pose = node.tf.lookup(node.frame_id, frame)
        if pose is None:
            first = frames.index(frame)
            which = f'{what} {first}' if numbered else what
            return xy, yaw, finite, f'{which} frame {frame!r}: no transform to {node.frame_id!r} on /tf or /tf_static'
        c, s = math.cos(pose[2]), math.sin(pose[2])
        x, y = xy[mask, 0], xy[mask, 1]
        xy[mask] = np.column_stack([pose[0] + c * x - s * y, pose[1] + s * x + c * y])
        yaw[mask] = np.angle(np.exp(1j * (yaw[mask] + pose[2])))   # wrapped; NaN stays NaN
    return xy, yaw, finite, ''


def _duration(seconds: float) -> Any:
    from builtin_interfaces.msg import Duration
    seconds = max(0.0, min(seconds, 2.0 ** 31 - 1)) if math.isfinite(seconds) else 0.0
    whole = math.floor(seconds)
    return Duration(sec=int(whole), nanosec=min(int((seconds - whole) * 1e9), 999_999_999))
