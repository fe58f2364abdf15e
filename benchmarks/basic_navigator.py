"""Nav2's own BasicNavigator, unmodified, against a fastep robot: issue 46's targets, measured.

    python -m benchmarks.basic_navigator [--commander PATH]

PATH is a robot_navigator.py (Nav2 Jazzy's nav2_simple_commander/nav2_simple_commander/robot_navigator.py); without
it the installed nav2_simple_commander is imported. Starts a map server (a disc on the direct line, a walled-in box),
a diff_drive plant and a planner in /r1 on a DDS domain of their own (fastep_testing.graph), drives them with
`BasicNavigator(namespace='r1')` the way Nav2's examples do (every isTaskComplete followed by getFeedback), and
prints one row per check against the issue's targets; exits 1 if a target is missed (2: no commander). Every
process it starts is stopped, by its id, at the end, also on failure; its logs stay in the directory printed at the
end.

The module's code runs unmodified (imported as it is, from the package or the file). It imports nav2_msgs
interfaces fastep does not build (AssistedTeleop, DockRobot, UndockRobot, FollowGPSWaypoints, SmoothPath, LoadMap,
ManageLifecycleNodes), whose verbs this script never calls: before the import, only where such a name is missing,
an interface that is built stands in under it (BasicNavigator's constructor makes a client for each, which needs a
real type). Only those unused interfaces are stood in for.

Every BasicNavigator call runs on a thread of its own with a wall-clock bound: one still running at its bound is
reported BLOCKED (its thread is then interrupted; if it does not end, the later calls are not run), never a hang.

Measured:
- distance_remaining at every feedback message getFeedback returns, against the route then left: the length of what
  the robot drives from that message's stamp (its current_pose) to the task's end, from the odometry this script
  records; within max(5 %, 0.2 m);
- each task's TaskResult and the result's error_code (SUCCEEDED 0, CANCELED, FAILED 206 inside an obstacle, FAILED
  208 walled in, within 20 s), where the robot ended (odometry), and how long each call took;
- getPath: a nav_msgs/Path in map from the robot to the goal round the disc, beside what the robot then drives.
"""

from __future__ import annotations

import argparse
import ctypes
import importlib
import importlib.util
import math
import os
import sys
import tempfile
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType
from typing import Any, Callable, Sequence

import numpy as np

from fastep_testing.basic_navigator_world import PARAMS, RADIUS, WORLD

NS = 'r1'
START = (3.0, 10.0, 0.0)
DISC, DISC_RADIUS = (9.0, 10.0), 1.5   # WORLD's disc
GOAL_TOLERANCE, YAW_TOLERANCE = 0.1, 0.25   # the planner's defaults (fastep_core/planning/params.py)
END_SLACK = 0.05            # m / rad beyond those tolerances that an end pose may be off (odometry vs the goal check)
FEEDBACK_SHARE, FEEDBACK_FLOOR = 0.05, 0.2   # the bound on distance_remaining: 5 % of the route left, or 0.2 m
CONTROL_HZ = 20.0           # the planner's control rate (its log's first line)
UNREACHABLE_BOUND = 20.0    # s: an unreachable goal ends FAILED within this (the target)

CALL_BOUND = 30.0           # wall s any one request/response call may take (send a goal, cancel, clear, ...)
ACTIVE_BOUND = 120.0        # waitUntilNav2Active: the nodes start and the planner activates
TASK_BOUND = 90.0           # a task (isTaskComplete to the end): a ~12 m drive at 1.5 m/s takes ~10 s
PATH_BOUND = 60.0           # getPath retried this long while the planner does not know the world yet (207)
INTERRUPT_WAIT = 5.0        # s a blocked call's thread is given to end once interrupted


class Interrupted(Exception):
    """Raised in a blocked call's thread to end it."""


class NoCommander(Exception):
    """No robot_navigator to drive: the one line saying what to pass."""


@dataclass
class Call:
    """One bounded BasicNavigator call: what it returned, how long it took, or that it blocked."""
    verb: str
    seconds: float = 0.0
    value: Any = None
    error: str = ''      # an exception's one line
    blocked: bool = False
    skipped: bool = False

    def text(self) -> str:
        if self.skipped:
            return f'{self.verb}: not run ({self.error})'
        if self.blocked:
            return f'{self.verb}: BLOCKED, no return after {self.seconds:.0f} s'
        return f'{self.verb}: {self.error}' if self.error else f'{self.verb} {self.seconds:.2f} s'


@dataclass
class Row:
    check: str
    target: str
    measured: str
    ok: bool | None     # None: information, not a target


@dataclass
class Task:
    """One navigation task run to its end: the feedback seen (receipt wall time, message), result and timing."""
    verb: str
    began: float                       # wall time (time.time) the goal was sent
    ended: float = math.nan            # wall time isTaskComplete said done
    complete: bool = False
    feedback: list[tuple[float, Any]] = field(default_factory=list)
    result: str = 'UNKNOWN'            # TaskResult name
    code: int | None = None            # the result's error_code
    message: str = ''
    raw: Any = None                    # the result message
    cancelled: float = math.nan        # wall time cancelTask was called
    calls: list[Call] = field(default_factory=list)

    def outcome(self) -> str:
        code = '' if self.code is None else f' {self.code}'
        said = f' ({self.message})' if self.message else ''
        return f'{self.result}{code}{said}'


# ---------------------------------------------------------------------------------------------- the commander


STAND_INS = {
    'action': {'AssistedTeleop': 'Spin', 'DockRobot': 'NavigateToPose', 'UndockRobot': 'NavigateToPose',
               'FollowGPSWaypoints': 'FollowWaypoints', 'SmoothPath': 'ComputePathToPose'},
    'srv': {'LoadMap': 'ClearEntireCostmap', 'ManageLifecycleNodes': 'ClearEntireCostmap'},
}


def stand_in_unused_interfaces() -> list[str]:
    """Put built nav2_msgs interfaces under the names robot_navigator imports but this script never uses (only
    where missing: on a ROS install nothing is stood in). The names stood in for."""
    stood = []
    for kind, names in STAND_INS.items():
        package = importlib.import_module(f'nav2_msgs.{kind}')
        for name, stand_in in names.items():
            if not hasattr(package, name):
                setattr(package, name, getattr(package, stand_in))
                stood.append(f'nav2_msgs.{kind}.{name}')
    return stood


def load_commander(path: str | None) -> ModuleType:
    """robot_navigator from `path`, or from the installed nav2_simple_commander; NoCommander if neither."""
    if path is None:
        try:
            return importlib.import_module('nav2_simple_commander.robot_navigator')
        except ModuleNotFoundError as e:
            if e.name is not None and e.name.startswith('nav2_simple_commander'):
                raise NoCommander('nav2_simple_commander is not installed: pass --commander PATH (a '
                                  'robot_navigator.py of Nav2 Jazzy)') from None
            raise
    spec = importlib.util.spec_from_file_location('robot_navigator', path)
    if spec is None or spec.loader is None or not Path(path).is_file():
        raise NoCommander(f'--commander {path}: not a Python file')
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


# ---------------------------------------------------------------------------------------------- bounded calls


class Session:
    """Runs BasicNavigator's calls one at a time, each on a thread of its own, each within a wall-clock bound."""

    def __init__(self, nav: Any, rclpy: Any) -> None:
        self.nav = nav
        self.rclpy = rclpy
        self.wedged = ''        # the call whose thread could not be ended: later calls are not run
        self.calls: list[Call] = []

    def call(self, verb: str, bound: float, fn: Callable[..., Any], *args: Any) -> Call:
        call = Call(verb)
        self.calls.append(call)
        if self.wedged:
            call.skipped, call.error = True, f'{self.wedged} is still blocked'
            return call
        box: dict[str, Any] = {}

        def body() -> None:
            try:
                box['value'] = fn(*args)
            except Interrupted:
                pass
            except Exception as e:   # the call's own failure: reported as its outcome
                box['error'] = f'{type(e).__name__}: {e}'.splitlines()[0]

        began = time.monotonic()
        thread = threading.Thread(target=body, name=verb, daemon=True)
        thread.start()
        thread.join(bound)
        call.seconds = time.monotonic() - began
        if thread.is_alive():
            call.blocked = True
            self.interrupt(thread)
            if thread.is_alive():
                self.wedged = verb
            return call
        call.value, call.error = box.get('value'), box.get('error', '')
        return call

    def interrupt(self, thread: threading.Thread) -> None:
        """End a blocked call: an Interrupted raised in its thread at its next Python step. BasicNavigator blocks
        either in a `wait_for_server(timeout_sec=1.0)` loop (steps each second) or in spin_until_future_complete
        without a timeout, which waits in rcl until the executor is woken."""
        assert thread.ident is not None
        ctypes.pythonapi.PyThreadState_SetAsyncExc(ctypes.c_ulong(thread.ident), ctypes.py_object(Interrupted))
        end = time.monotonic() + INTERRUPT_WAIT
        while thread.is_alive() and time.monotonic() < end:
            self.rclpy.get_global_executor().wake()
            thread.join(0.1)


def run_to_end(nav: Any, feedback_type: Any, deadline: float, task: Task) -> None:
    """Nav2's example loop: `while not isTaskComplete(): feedback = getFeedback()`, until `deadline` (monotonic).
    Keeps each new feedback message of the task's own type (BasicNavigator keeps the last task's until a new one
    comes) with the wall time it was first seen."""
    stale = nav.getFeedback()
    while not nav.isTaskComplete():
        fb = nav.getFeedback()
        if (fb is not None and fb is not stale and isinstance(fb, feedback_type)
                and (not task.feedback or fb is not task.feedback[-1][1])):
            task.feedback.append((time.time(), fb))
        if time.monotonic() > deadline:
            return
    task.complete = True


def run_task(session: Session, verb: str, send: Callable[[], Any], action: Any,
             bound: float = TASK_BOUND, cancel_after: float | None = None) -> Task:
    """Send a task (goToPose, followWaypoints, ...), loop isTaskComplete/getFeedback to its end (cancelTask after
    `cancel_after` s if given), and read its result."""
    nav = session.nav
    task = Task(verb, time.time())
    sent = session.call(verb, CALL_BOUND, send)
    task.calls.append(sent)
    if sent.value is not True:
        task.result = 'not sent' if sent.value is None else 'rejected'
        task.message = sent.text() if sent.value is None else ''
        return task
    if cancel_after is not None:
        loop = session.call('isTaskComplete loop', cancel_after + CALL_BOUND, run_to_end, nav, action.Feedback,
                            time.monotonic() + cancel_after, task)
        task.calls.append(loop)
        task.cancelled = time.time()
        task.calls.append(session.call('cancelTask', CALL_BOUND, nav.cancelTask))
    loop = session.call('isTaskComplete loop', bound + CALL_BOUND, run_to_end, nav, action.Feedback,
                        time.monotonic() + bound, task)
    task.calls.append(loop)
    task.ended = time.time()
    if not task.complete:
        task.result = 'no result'
        task.message = loop.text() if loop.blocked or loop.skipped else f'still running after {bound:.0f} s'
        session.call('cancelTask (clean-up)', CALL_BOUND, nav.cancelTask)
        return task
    task.result = nav.getResult().name
    future = nav.result_future
    if future is not None and future.result() is not None:
        result = future.result().result
        task.code = int(getattr(result, 'error_code', 0))
        task.message = str(getattr(result, 'error_msg', ''))
        task.raw = result
    return task


# ---------------------------------------------------------------------------------------------- odometry


class Odometry:
    """The robot's odometry, and the planner's commands, as this script's own subscriptions recorded them (a helper
    node in its own context)."""

    def __init__(self, helper: Any, topic: str, cmd_topic: str) -> None:
        from geometry_msgs.msg import Twist
        from nav_msgs.msg import Odometry as OdometryMsg

        from msg_tools.interface import offered_qos
        self.helper = helper
        self.seen = helper.record(topic, OdometryMsg)
        self.commands: list[tuple[float, float]] = []   # (receipt wall time, forward speed) of each cmd_vel
        helper.node.create_subscription(Twist, cmd_topic, lambda m: self.commands.append((time.time(), m.linear.x)),
                                        offered_qos(cmd_topic))
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self.spin, name='odometry', daemon=True)
        self.thread.start()

    def spin(self) -> None:
        while not self.stop.is_set():
            self.helper.executor.spin_once(timeout_sec=0.05)

    def close(self) -> None:
        self.stop.set()
        self.thread.join(5.0)

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Stamps (s), positions (n, 2), yaws, forward speeds of every message so far, in stamp order."""
        msgs = list(self.seen)
        t = np.array([m.header.stamp.sec + m.header.stamp.nanosec * 1e-9 for m in msgs])
        xy = np.array([(m.pose.pose.position.x, m.pose.pose.position.y) for m in msgs]).reshape(-1, 2)
        q = np.array([(m.pose.pose.orientation.z, m.pose.pose.orientation.w) for m in msgs]).reshape(-1, 2)
        v = np.array([m.twist.twist.linear.x for m in msgs])
        order = np.argsort(t, kind='stable')
        return t[order], xy[order], 2.0 * np.arctan2(q[order, 0], q[order, 1]), v[order]

    def wait_through(self, t: float, timeout: float = 10.0) -> bool:
        """Has odometry stamped `t` or later come (waiting up to `timeout` s)?"""
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            if self.seen and stamp(self.seen[-1]) >= t:
                return True
            time.sleep(0.05)
        return False

    def pose_at(self, t: float) -> tuple[float, float, float]:
        ts, xy, yaw, _ = self.arrays()
        k = int(np.clip(np.searchsorted(ts, t), 0, len(ts) - 1))
        return float(xy[k, 0]), float(xy[k, 1]), float(yaw[k])

    def driven(self, t0: float, t1: float) -> tuple[float, np.ndarray]:
        """The length of what the robot drove from t0 to t1 (positions interpolated at t0), and those positions."""
        ts, xy, _, _ = self.arrays()
        inside = (ts > t0) & (ts <= t1)
        start = np.array([[np.interp(t0, ts, xy[:, 0]), np.interp(t0, ts, xy[:, 1])]])
        points = np.vstack([start, xy[inside]])
        return float(np.hypot(*np.diff(points, axis=0).T).sum()), points


def stamp(msg: Any) -> float:
    return float(msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9)


def turned(odom: Odometry, t0: float, t1: float) -> float:
    """The robot's heading change from t0 to t1, unwrapped (rad)."""
    ts, _, yaw, _ = odom.arrays()
    inside = (ts >= t0) & (ts <= t1)
    return float(np.unwrap(yaw[inside])[-1] - np.unwrap(yaw[inside])[0]) if inside.sum() > 1 else 0.0


def path_length(xy: np.ndarray) -> float:
    return float(np.hypot(*np.diff(xy, axis=0).T).sum()) if len(xy) > 1 else 0.0


def path_xy(path: Any) -> np.ndarray:
    return np.array([(p.pose.position.x, p.pose.position.y) for p in path.poses]).reshape(-1, 2)


def distance_to_polyline(points: np.ndarray, line: np.ndarray) -> np.ndarray:
    """Each point's distance to the polyline `line` (numpy over all point x segment pairs)."""
    a, b = line[:-1], line[1:]
    ab = b - a
    denom = np.maximum((ab * ab).sum(axis=1), 1e-12)
    s = np.clip(((points[:, None, :] - a[None]) * ab[None]).sum(axis=2) / denom[None], 0.0, 1.0)
    nearest = a[None] + s[..., None] * ab[None]
    return np.hypot(*(points[:, None, :] - nearest).transpose(2, 0, 1)).min(axis=1)


# ---------------------------------------------------------------------------------------------- the checks


def feedback_rows(verb: str, task: Task, odom: Odometry, target: bool) -> list[Row]:
    """distance_remaining at every feedback message against the route then left (what the robot then drove)."""
    if not task.complete:
        return [Row(f'{verb}: distance_remaining', 'every message within max(5 %, 0.2 m) of the route left',
                    'no end to measure to', False if target else None)]
    odom.wait_through(task.ended + 0.3)
    errors, ratios, etas, told = [], [], [], []
    worst = (0.0, 0.0, 0.0)
    for received, fb in task.feedback:
        t = stamp(fb.current_pose) or received
        left, _ = odom.driven(t, task.ended + 0.3)
        error = float(fb.distance_remaining) - left
        errors.append(abs(error) <= max(FEEDBACK_SHARE * left, FEEDBACK_FLOOR))
        if abs(error) > abs(worst[0]):
            worst = (error, left, float(fb.distance_remaining))
        if left > 1.0:
            ratios.append(float(fb.distance_remaining) / left)
            eta = fb.estimated_time_remaining.sec + fb.estimated_time_remaining.nanosec * 1e-9
            etas.append(eta / max(task.ended - t, 1e-3))
        told.append(float(fb.distance_remaining))
    n = len(errors)
    rises = max((b - a for a, b in zip(told, told[1:])), default=0.0)
    measured = (f'{sum(errors)}/{n} within; worst {worst[0]:+.2f} m (told {worst[2]:.2f}, left {worst[1]:.2f}); '
                f'median told/left {np.median(ratios) if ratios else math.nan:.3f}; first {told[0] if told else 0:.2f}'
                f' m, last {told[-1] if told else 0:.2f} m; largest rise {rises:+.2f} m')
    rows = [Row(f'{verb}: distance_remaining', 'every message within max(5 %, 0.2 m) of the route left', measured,
                (n > 0 and all(errors)) if target else None)]
    if etas:
        driven, _ = odom.driven(task.began, task.ended)
        ts, _, _, v = odom.arrays()
        peak = float(np.abs(v[(ts >= task.began) & (ts <= task.ended)]).max(initial=0.0))
        speeds = [float(fb.distance_remaining) / max(fb.estimated_time_remaining.sec
                                                     + fb.estimated_time_remaining.nanosec * 1e-9, 1e-3)
                  for _, fb in task.feedback if float(fb.distance_remaining) > 1.0]
        rows.append(Row(f'{verb}: estimated_time_remaining', '(information)',
                        f'median ETA / time really left {np.median(etas):.2f} (messages with > 1 m left); speed the '
                        f'ETA implies: median {np.median(speeds):.2f} m/s; driven: {driven:.2f} m in '
                        f'{task.ended - task.began:.1f} s, mean {driven / (task.ended - task.began):.2f} m/s, '
                        f'peak {peak:.2f} m/s', None))
    return rows


def result_row(verb: str, task: Task, result: str, codes: Sequence[int], within: float | None = None) -> Row:
    took = task.ended - task.began
    ok = task.result == result and task.code in codes and (within is None or took < within)
    bound = f' within {within:.0f} s' if within else ''
    return Row(f'{verb}: result', f'{result} {"/".join(map(str, codes))}{bound}',
               f'{task.outcome()} after {took:.2f} s', ok)


def end_row(verb: str, odom: Odometry, task: Task, goal: tuple[float, float], yaw: float | None = None) -> Row:
    odom.wait_through(task.ended + 0.2)
    x, y, heading = odom.pose_at(task.ended + 0.2)
    off = math.dist((x, y), goal)
    ok = off <= GOAL_TOLERANCE + END_SLACK
    measured = f'at ({x:.2f}, {y:.2f}), {off:.3f} m off'
    target = f'within {GOAL_TOLERANCE + END_SLACK:.2f} m'
    if yaw is not None:
        yaw_off = abs(math.remainder(heading - yaw, math.tau))
        ok = ok and yaw_off <= YAW_TOLERANCE + END_SLACK
        measured += f', heading {yaw_off:.3f} rad off'
        target += f', heading within {YAW_TOLERANCE + END_SLACK:.2f} rad'
    return Row(f'{verb}: end pose (odometry)', target, measured, ok)


def pose(nav: Any, x: float, y: float, yaw: float = 0.0) -> Any:
    """A goal as Nav2's examples make one: a PoseStamped in map, stamped now."""
    from geometry_msgs.msg import PoseStamped
    p = PoseStamped()
    p.header.frame_id = 'map'
    p.header.stamp = nav.get_clock().now().to_msg()
    p.pose.position.x, p.pose.position.y = x, y
    p.pose.orientation.z, p.pose.orientation.w = math.sin(yaw / 2.0), math.cos(yaw / 2.0)
    return p


def drive(session: Session, odom: Odometry, graph_status: Callable[[], str]) -> list[Row]:
    """The BasicNavigator script, each step's rows."""
    from nav2_msgs import action

    nav = session.nav
    rows: list[Row] = []

    def call_row(call: Call, what: str = 'returns, never blocks') -> Row:
        return Row(call.verb, what, call.text(), not (call.blocked or call.skipped or call.error))

    def status_row(verb: str, task: Task) -> None:
        if task.result not in ('SUCCEEDED',) and not task.complete:
            rows.append(Row(f'{verb}: planner status then', '(information)', graph_status(), None))

    # Wait until active: the planner's lifecycle state, no localizer (docs/nav2.md).
    rows.append(call_row(session.call("waitUntilNav2Active(navigator='planner', localizer='robot_localization')",
                                      ACTIVE_BOUND, nav.waitUntilNav2Active, 'planner', 'robot_localization')))

    # getPath from the robot to the goal, retried while the planner does not know the world yet.
    goal = (14.0, 10.0)
    path, tries, end, codes = None, 0, time.monotonic() + PATH_BOUND, []
    began = time.monotonic()
    while path is None and time.monotonic() < end and not session.wedged:
        tries += 1
        got = session.call('getPath', CALL_BOUND, nav.getPath, pose(nav, *START[:2]), pose(nav, *goal))
        path = got.value
        if path is None:
            if got.blocked or got.error:
                rows.append(call_row(got))
                break
            result = nav.result_future.result().result if nav.result_future else None
            codes.append(getattr(result, 'error_code', None))
            time.sleep(1.0)
    if path is None:
        rows.append(Row('getPath', 'a nav_msgs/Path, the route', f'none after {tries} tries (codes {codes})', False))
        route = np.zeros((0, 2))
    else:
        route = path_xy(path)
        clearance = float(np.hypot(*(route - DISC).T).min()) - DISC_RADIUS if len(route) else math.nan
        first = math.dist(route[0], START[:2]) if len(route) else math.nan
        last = math.dist(route[-1], goal) if len(route) else math.nan
        ok = (path.header.frame_id == 'map' and len(route) > 1 and first < 0.3 and last < 0.01
              and 11.0 < path_length(route) < 12.5 and clearance >= RADIUS - 0.05)
        rows.append(Row('getPath', 'Path in map, robot -> goal round the disc (11-12.5 m, clear by the radius)',
                        f"frame '{path.header.frame_id}', {len(route)} poses, {path_length(route):.2f} m, starts "
                        f'{first:.2f} m from the robot, ends {last:.3f} m from the goal, {clearance:.2f} m clear of '
                        f'the disc; {tries} tries ({time.monotonic() - began:.1f} s; codes before {codes})', ok))

    # goToPose with a heading, getFeedback at every isTaskComplete to the end.
    heading = math.pi / 2
    task = run_task(session, 'goToPose', lambda: nav.goToPose(pose(nav, *goal, heading)),
                    action.NavigateToPose)
    rows.append(result_row('goToPose', task, 'SUCCEEDED', (0,)))
    rows += feedback_rows('goToPose', task, odom, target=True)
    rows.append(end_row('goToPose (final heading)', odom, task, goal, heading))
    status_row('goToPose', task)
    if len(route) > 1 and task.complete:
        driven, points = odom.driven(task.began, task.ended)
        off = distance_to_polyline(points, route)
        rows.append(Row('getPath vs goToPose', '(information)', f'getPath {path_length(route):.2f} m, driven '
                        f'{driven:.2f} m; driven off the path: median {np.median(off):.3f}, max {off.max():.3f} m',
                        None))

    # cancelTask under way: CANCELED, and the robot brakes.
    task = run_task(session, 'goToPose + cancelTask', lambda: nav.goToPose(pose(nav, 3.0, 14.0)),
                    action.NavigateToPose, 30.0, cancel_after=1.5)
    rows.append(result_row('cancelTask', task, 'CANCELED', (0,)))
    cancelled = task.cancelled
    if task.complete:
        odom.wait_through(task.ended + 3.0)
        ts, _, _, v = odom.arrays()
        moving = ts[(ts >= cancelled) & (np.abs(v) > 0.02)]
        stopped = (moving.max() if len(moving) else cancelled) - cancelled
        speed = float(np.abs(v[np.searchsorted(ts, cancelled) - 1])) if len(ts) else math.nan
        # Braking judged on the commands (cmd_vel), which the planner limits per 20 Hz control tick: the plant
        # holds the latest command only, and commands that reach it unevenly make its odometry's speed jump.
        # A tick that comes late may change the command by more: each drop is divided by the time since the
        # command before (at least one tick, since commands that reach this script together left a tick apart).
        sent = np.array([c for c in list(odom.commands) if cancelled - 0.2 <= c[0] <= cancelled + stopped + 0.5])
        rate = (-np.diff(np.abs(sent[:, 1])) / np.maximum(np.diff(sent[:, 0]), 1.0 / CONTROL_HZ)
                if len(sent) > 1 else np.zeros(0))
        drop = float(np.max(-np.diff(np.abs(sent[:, 1])), initial=0.0)) if len(sent) > 1 else math.nan
        rows.append(Row('cancelTask: timing', '(information)', f'CANCELED {task.ended - cancelled:.2f} s after '
                        f'cancelTask was called; robot at {speed:.2f} m/s then, stopped {stopped:.2f} s later '
                        f'(mean braking {speed / max(stopped, 1e-3):.2f} m/s^2); cmd_vel\'s largest drop from one '
                        f'command to the next {drop:.3f} m/s, braking at most {np.max(rate, initial=0.0):.2f} m/s^2 '
                        f'over the time between them (max_acceleration 2.5)', None))
    status_row('cancelTask', task)

    # followWaypoints.
    waypoints = [(12.0, 14.0), (6.0, 14.0)]
    task = run_task(session, 'followWaypoints',
                    lambda: nav.followWaypoints([pose(nav, *w) for w in waypoints]), action.FollowWaypoints)
    rows.append(result_row('followWaypoints', task, 'SUCCEEDED', (0,)))
    if task.complete:
        missed = list(getattr(task.raw, 'missed_waypoints', []))
        seen = sorted({fb.current_waypoint for _, fb in task.feedback})
        rows.append(Row('followWaypoints: missed_waypoints', '[]', f'{missed}; current_waypoint seen {seen}',
                        missed == []))
        rows.append(end_row('followWaypoints', odom, task, waypoints[-1]))
    status_row('followWaypoints', task)

    # goThroughPoses: distance_remaining is to the last pose, along the route through the others.
    poses = [(5.0, 16.0), (12.0, 16.0)]
    task = run_task(session, 'goThroughPoses',
                    lambda: nav.goThroughPoses([pose(nav, *p) for p in poses]), action.NavigateThroughPoses)
    rows.append(result_row('goThroughPoses', task, 'SUCCEEDED', (0,)))
    rows += feedback_rows('goThroughPoses', task, odom, target=True)
    if task.complete:
        rows.append(end_row('goThroughPoses', odom, task, poses[-1]))
    status_row('goThroughPoses', task)

    # A goal inside the disc: FAILED, GOAL_OCCUPIED (206); a walled-in one: FAILED, NO_VALID_PATH (208), within 20 s.
    task = run_task(session, 'goToPose inside an obstacle', lambda: nav.goToPose(pose(nav, *DISC)),
                    action.NavigateToPose, 30.0)
    rows.append(result_row('goToPose inside an obstacle', task, 'FAILED', (206,), UNREACHABLE_BOUND))
    status_row('goToPose inside an obstacle', task)
    task = run_task(session, 'goToPose walled in', lambda: nav.goToPose(pose(nav, 17.0, 4.0)),
                    action.NavigateToPose, 45.0)
    rows.append(result_row('goToPose walled in (unreachable)', task, 'FAILED', (208,), UNREACHABLE_BOUND))
    status_row('goToPose walled in', task)

    # The behaviours.
    task = run_task(session, 'spin', lambda: nav.spin(1.57, 20), action.Spin, 40.0)
    rows.append(result_row('spin(1.57)', task, 'SUCCEEDED', (0,)))
    if task.complete:
        odom.wait_through(task.ended + 0.2)
        yaw = turned(odom, task.began, task.ended + 0.2)
        told = float(task.feedback[-1][1].angular_distance_traveled) if task.feedback else math.nan
        rows.append(Row('spin: turned (odometry)', '1.57 within 0.1 rad',
                        f'{yaw:.3f} rad (last angular_distance_traveled {told:.3f})', abs(yaw - 1.57) <= 0.1))
    status_row('spin', task)
    task = run_task(session, 'backup', lambda: nav.backup(0.3, 0.2, 20), action.BackUp, 40.0)
    rows.append(result_row('backup(0.3, 0.2)', task, 'SUCCEEDED', (0,)))
    if task.complete:
        odom.wait_through(task.ended + 0.2)
        x0, y0, yaw0 = odom.pose_at(task.began)
        x1, y1, _ = odom.pose_at(task.ended + 0.2)
        along = (x1 - x0) * math.cos(yaw0) + (y1 - y0) * math.sin(yaw0)
        rows.append(Row('backup: moved (odometry)', '0.3 m backwards within 0.05 m', f'{-along:.3f} m backwards',
                        abs(-along - 0.3) <= 0.05))
    status_row('backup', task)

    rows.append(call_row(session.call('clearAllCostmaps', CALL_BOUND, nav.clearAllCostmaps)))

    # The costmap calls only where the planner serves them (another engineer is adding them).
    names = session.call('get_service_names_and_types', CALL_BOUND, nav.get_service_names_and_types)
    served = {name for name, _ in names.value or []}
    if f'/{NS}/global_costmap/get_costmap' in served:
        got = session.call('getGlobalCostmap', CALL_BOUND, nav.getGlobalCostmap)
        grid = got.value
        if grid is not None and not (got.blocked or got.error):
            meta = grid.metadata
            cells = int(meta.size_x) * int(meta.size_y)
            rows.append(Row('getGlobalCostmap', 'a Costmap with cells', f'{meta.size_x} x {meta.size_y} at '
                            f'{meta.resolution:.3f} m in {grid.header.frame_id!r}, {len(grid.data)} cells, '
                            f'{sum(1 for c in grid.data if c >= 253)} lethal/inscribed ({got.seconds:.2f} s)',
                            cells > 0 and len(grid.data) == cells))
        else:
            rows.append(call_row(got))
    else:
        rows.append(Row('getGlobalCostmap', 'only if served', 'global_costmap/get_costmap not served: not called',
                        None))
    if f'/{NS}/local_costmap/clear_costmap_around_pose' in served:
        rows.append(call_row(session.call('clearCostmapAroundPose', CALL_BOUND, nav.clearCostmapAroundPose,
                                          pose(nav, 12.0, 16.0), 2.0)))
    else:
        rows.append(Row('clearCostmapAroundPose', 'only if served',
                        'local_costmap/clear_costmap_around_pose not served: not called', None))

    # More of the calls the issue found blocking: none may block now.
    got = session.call('getPathThroughPoses', CALL_BOUND, nav.getPathThroughPoses, pose(nav, 0.0, 0.0),
                       [pose(nav, 8.0, 14.0), pose(nav, 5.0, 12.0)])
    through = got.value
    rows.append(Row('getPathThroughPoses', 'a Path through both poses, never blocks',
                    got.text() if through is None else f'{len(through.poses)} poses, '
                    f'{path_length(path_xy(through)):.2f} m ({got.seconds:.2f} s)', through is not None))
    if through is not None:
        end_pose = (through.poses[-1].pose.position.x, through.poses[-1].pose.position.y)
        task = run_task(session, 'followPath', lambda: nav.followPath(through), action.FollowPath, 60.0)
        rows.append(result_row('followPath(getPathThroughPoses)', task, 'SUCCEEDED', (0,)))
        if task.complete:
            rows.append(end_row('followPath', odom, task, end_pose))
        status_row('followPath', task)
    task = run_task(session, 'driveOnHeading', lambda: nav.driveOnHeading(0.3, 0.2, 20),
                    action.DriveOnHeading, 40.0)
    rows.append(result_row('driveOnHeading(0.3, 0.2)', task, 'SUCCEEDED', (0,)))
    status_row('driveOnHeading', task)

    blocked = [c.verb for c in session.calls if c.blocked or c.skipped]
    rows.append(Row('no call blocks for ever', f'all {len(session.calls)} calls return within their bound',
                    'blocked: ' + ', '.join(blocked) if blocked else f'all {len(session.calls)} returned', not blocked))
    return rows


def print_table(rows: list[Row]) -> None:
    width = max(len(r.check) for r in rows)
    for r in rows:
        mark = 'info' if r.ok is None else ('ok' if r.ok else 'MISS')
        print(f'{mark:4}  {r.check:{width}}  {r.measured}' + ('' if r.ok is None else f'   [target: {r.target}]'))


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog='basic_navigator', description=__doc__.splitlines()[0])
    p.add_argument('--commander', metavar='PATH', help="Nav2's robot_navigator.py (default: the installed "
                   'nav2_simple_commander)')
    args = p.parse_args(argv)

    os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'   # read when rclpy's context starts
    os.environ.pop('ROS_LOCALHOST_ONLY', None)
    os.environ.setdefault('FASTEP_TEST_LOG_LEVEL', 'info')      # the nodes' logs, kept, say why a check failed
    try:
        stood = stand_in_unused_interfaces()
    except ModuleNotFoundError:
        print('nav2_msgs is not built: run make (interfaces/build.sh)', file=sys.stderr)
        return 2
    try:
        module = load_commander(args.commander)
    except NoCommander as e:
        print(e, file=sys.stderr)
        return 2

    import rclpy
    from rclpy.signals import SignalHandlerOptions

    from fastep_testing.graph import Graph, Helper, write

    tmp = Path(tempfile.mkdtemp(prefix='basic_navigator_'))
    graph = Graph(tmp)
    helper = odom = nav = None
    rows: list[Row] = []
    try:
        graph.start('map', 'map_server', scenario=str(write(tmp / 'world.yaml', WORLD)))
        # The base's own speed limit is the planner's: a plant left at its default (1.0 m/s) clips the planner's
        # 1.5 m/s commands, and the planner then ramps from the measured speed instead of its own commands.
        graph.start('plant', 'plant', f'/{NS}', model='diff_drive', start=list(START), max_speed=PARAMS['max_speed'])
        graph.start('planner', 'planner', f'/{NS}', model='diff_drive', **PARAMS)
        helper = Helper(graph.domain)
        helper.record_status(f'/{NS}')
        odom = Odometry(helper, f'/{NS}/odom', f'/{NS}/cmd_vel')
        rclpy.init(args=[], domain_id=graph.domain, signal_handler_options=SignalHandlerOptions.NO)
        nav = module.BasicNavigator(namespace=NS)
        session = Session(nav, rclpy)

        def graph_status() -> str:
            status = helper.status(f'/{NS}') if helper is not None else {}
            return str({k: status[k] for k in list(status)[:8]}) if status else 'no status heard'

        rows = drive(session, odom, graph_status)
    finally:
        try:
            if nav is not None:
                nav.destroy_node()
            rclpy.try_shutdown()
        finally:
            if odom is not None:
                odom.close()
            if helper is not None:
                helper.close()
            graph.close()   # every process it started, by its id

    print(f'BasicNavigator from {module.__file__}' + (f'; stood in for (unused): {", ".join(stood)}' if stood else ''))
    print_table(rows)
    missed = [r.check for r in rows if r.ok is False]
    if missed:
        lines = [line for line in graph.log('planner').splitlines() if 'WARN' in line or 'ERROR' in line]
        print('planner log, its last warnings and errors:\n' + '\n'.join(lines[-20:]))
    print(f'{len(missed)} target(s) missed' + (': ' + '; '.join(missed) if missed else '') + f'. Logs: {tmp}')
    print('load average: ' + ' '.join(f'{x:.2f}' for x in os.getloadavg()))
    return 1 if missed else 0


if __name__ == '__main__':
    raise SystemExit(main())
