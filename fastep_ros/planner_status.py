"""What the planner node tells about itself: its `status` (diagnostic_msgs/DiagnosticStatus), the tasks it puts
on /diagnostics, and the control timings both carry.

The levels, messages and reasons are those fastep_ros/planner.py's module docstring lists; this module is how
they are worked out from the node's state, apart from the node that keeps that state (subscriptions, the control
loop, lock step). `PlannerReports` is PlannerNode's base: PlannerNode sets every attribute it declares.
"""

from __future__ import annotations

import collections
from typing import Any

import numpy as np
from diagnostic_msgs.msg import DiagnosticStatus
from rclpy.publisher import Publisher

from fastep_core.planning.navigator import Mode, Navigator
from fastep_ros.diagnostics import Task
from fastep_ros.lifecycle import ManagedNode
from fastep_ros.perception import ScanPerception
from fastep_ros.planning_thread import PlanningThread
from fastep_ros.robots import RobotFollower
from fastep_ros.sim_time import SimTimeWatch
from msg_tools import cdr, convert, frames, interface

__all__ = ['RATE_SHORTFALL', 'RATE_WINDOW', 'STATUS_MESSAGES', 'PlannerReports']

# Every `status` message the planner says (PlannerReports.status), its levels and what it means: the reference's
# status page (fastep_ros.reference) is made from it, and a test checks that status() says nothing else.
STATUS_MESSAGES: tuple[tuple[str, str, str], ...] = (
    ('inactive', 'OK', 'lifecycle: not active; no commands are sent (activate to drive)'),
    ('waiting', 'WARN', 'waiting for the world (/obstacles, /map), for localization, or for a robot in the way '
                        '(the reason says which); no commands while the world is missing'),
    ('idle', 'OK', 'no goal: none given yet, or cancelled (the reason says so)'),
    ('kinematic', 'OK / WARN', 'driving to the goal (or the route vertex in sight) by the kinematic controller; '
                               'WARN while inputs are stale (kept where last seen) or a newer goal was refused'),
    ('avoiding', 'OK / WARN', 'driving to a swarm waypoint, escaping a trap, manoeuvring or yielding to a mover; '
                              'WARN as for kinematic'),
    ('arrived', 'OK', 'the goal is reached (within goal_tolerance, and facing its heading if it has one)'),
    ('failed', 'ERROR', 'the goal failed; the reason says why (the failure reasons below)'),
    ('stale', 'WARN / ERROR', 'held still: own odometry missing, old, rejected or not finite, or the clock stands '
                              'still (WARN); planning stalled, the plan older than max_plan_age (ERROR)'),
    ('conflict', 'ERROR', 'another node publishes on cmd_vel: not commanding (exclusive_cmd_vel)'),
)

RATE_WINDOW = 2.0        # s of node time over which the control loop's achieved rate is measured
RATE_SHORTFALL = 0.9     # an achieved rate below this share of control_rate_hz is a missed rate (WARN)


class PlannerReports(ManagedNode):
    """Status and /diagnostics of the planner node (fastep_ros.planner.PlannerNode, which derives from it)."""

    # What the reports read, set by PlannerNode.
    algorithm: str
    navigator: Navigator | None
    goal: tuple[float, float] | None
    hold: str                      # why the robot is held still although it has a goal ('' when it is not)
    cmd_conflict: str              # the other publishers on cmd_vel ('' when there are none)
    exclusive_cmd_vel: bool
    goal_refused: str              # why the last goal was refused, while the goal before it is driven to
    clock_problem: str             # why this node's time stands still ('' when it does not)
    obstacles: list[Any] | None
    workspace_param: tuple[float, float, float, float] | None
    map_workspace: tuple[float, float, float, float] | None
    odom: frames.StampedPose | None
    odom_received: float
    odom_timeout: float
    odom_problem: str
    odom_heard: int
    odom_lag: float
    own_odom_topic: str
    control_times: collections.deque[float]
    control_cpu_times: collections.deque[float]
    control_stamps: collections.deque[float]   # node times of the recent control callbacks
    control_rate_hz: float
    planning: PlanningThread[Any, Any] | None
    plan_problem: str              # why the plan is not driven on ('' when it is)
    control_count: int
    plan_tick: int
    robots: RobotFollower
    cmd_pub: Publisher
    status_pub: Publisher
    scan_perception: ScanPerception
    scan_problem: str
    sim_time: SimTimeWatch
    known_movers: list[Any]
    movers_stamp: float
    movers_received: float
    _status_key: tuple[Any, ...] | None
    _status_since: float
    _stale_logged: list[str]

    def now(self) -> float:
        return self.get_clock().now().nanoseconds * 1e-9

    def movers_stale(self, t: float) -> bool:
        """Whether the known movers are older than odom_timeout (the map node stopped or stalled), or stamped
        further than that ahead of this node's clock."""
        return bool(self.known_movers) and not (t - self.movers_received <= self.odom_timeout and
                                                -self.odom_timeout <= t - self.movers_stamp <= self.odom_timeout)

    def stale_inputs(self, t: float) -> list[tuple[str, float]]:
        """What this robot avoids on data that stopped coming, and how old that data is: other robots whose
        odometry stopped (by name; fastep_ros.robots), the known movers ('/movers'). Logged when that changes."""
        stale = [(r.name, t - r.received) for r in self.robots.fleet.stale(t)]
        if self.movers_stale(t):
            stale.append((interface.MOVERS, t - self.movers_received))
        names = [name for name, _ in stale]
        if names != self._stale_logged:
            went, back = [n for n in names if n not in self._stale_logged], \
                [n for n in self._stale_logged if n not in names]
            if went:
                self.get_logger().warning(f'stale: {", ".join(went)}; avoided where last seen, the reach widening '
                                          f'at the last speed known, until fresh data comes')
            if back:
                self.get_logger().info(f'fresh again: {", ".join(back)}')
            self._stale_logged = names
        return stale

    def status(self) -> tuple[bytes, str, str]:
        if not self.is_active:
            return DiagnosticStatus.OK, 'inactive', 'lifecycle: not active (no commands); activate to drive'
        if self.cmd_conflict and self.exclusive_cmd_vel:
            return DiagnosticStatus.ERROR, 'conflict', f'{self.cmd_conflict}: not commanding while another node ' \
                                                       f'does (exclusive_cmd_vel)'
        level, message, reason = self.navigation_status()
        if self.clock_problem and level != DiagnosticStatus.ERROR:
            # The control loop stands still with the clock: a robot under way is held (check_clock).
            return DiagnosticStatus.WARN, 'stale' if message in (Mode.KINEMATIC.value, Mode.AVOIDING.value) else \
                message, self.clock_problem
        return level, message, reason

    def navigation_status(self) -> tuple[bytes, str, str]:
        nav = self.navigator
        if nav is None:
            missing = [name for name, have in ((interface.OBSTACLES, self.obstacles is not None),
                                               (interface.MAP, self.workspace_param or self.map_workspace))
                       if not have]
            return DiagnosticStatus.WARN, 'waiting', f'waiting for the world ({" and ".join(missing)})'
        mode = nav.mode
        if mode is Mode.FAILED:
            return DiagnosticStatus.ERROR, mode.value, nav.reason
        if self.plan_problem and mode in (Mode.KINEMATIC, Mode.AVOIDING):
            return DiagnosticStatus.ERROR, 'stale', self.plan_problem
        if mode in (Mode.IDLE, Mode.ARRIVED):
            return DiagnosticStatus.OK, mode.value, nav.reason
        if self.hold:
            if self.hold.startswith('waiting'):
                return DiagnosticStatus.WARN, 'waiting', self.hold
            return DiagnosticStatus.WARN, 'stale', self.hold
        if self.goal_refused and self.goal is not None:
            return DiagnosticStatus.WARN, mode.value, f'{self.goal_refused}; still driving to ' \
                                                     f'({self.goal[0]:g}, {self.goal[1]:g})'
        stale = self.stale_inputs(self.now())
        if stale:
            kept = f'stale: {", ".join(name for name, _ in stale)} (kept where last seen, the reach widening)'
            return DiagnosticStatus.WARN, mode.value, f'{nav.reason}; {kept}' if nav.reason else kept
        return DiagnosticStatus.OK, mode.value, nav.reason

    def control_rate(self) -> float | None:
        """Control ticks per second of node time over the last RATE_WINDOW seconds (None before a window's worth)."""
        stamps = list(self.control_stamps)   # a copy: the control tick appends to it
        if len(stamps) < 2:
            return None
        last = stamps[-1]
        ticks = [s for s in stamps if last - s <= RATE_WINDOW]
        span = last - ticks[0]
        if span < 0.5 * RATE_WINDOW:
            return None
        return (len(ticks) - 1) / span

    def rate_problem(self) -> str:
        """Why the control loop misses its rate ('' when it keeps it, or before there is a window to tell)."""
        rate = self.control_rate()
        if rate is None or rate >= RATE_SHORTFALL * self.control_rate_hz:
            return ''
        return f'control loop missed its rate: {rate:.1f} Hz of {self.control_rate_hz:g} Hz over the last ' \
               f'{RATE_WINDOW:g} s (tick ms p50 / p99 / max: {self.control_ms()})'

    def plan_age(self) -> float:
        """Seconds (control periods) since the tick the plan in use was planned from; 0 without the thread."""
        if self.planning is None or self.planning.plan is None:
            return 0.0
        return (self.control_count - self.plan_tick) / self.control_rate_hz

    def planning_ms(self) -> str:
        """'p50 / p99 / max' of the recent planning passes in ms ('' without the thread or before a pass)."""
        if self.planning is None or not self.planning.pass_times:
            return ''
        p50, p99, top = np.percentile(np.array(self.planning.pass_times) * 1e3, [50.0, 99.0, 100.0])
        return f'{p50:.3f} / {p99:.3f} / {top:.3f}'

    def control_ms(self, cpu: bool = False) -> str:
        """'p50 / p99 / max' of the recent control callbacks' wall times (cpu: CPU times) in ms ('' before the
        first)."""
        return self.control_ms_both()[1 if cpu else 0]

    def control_ms_both(self) -> tuple[str, str]:
        """control_ms() and control_ms(cpu=True) from one percentile call (status sends both; each call of
        np.percentile costs ~35-50 us here; on the ticks that plan). Both deques take one value per callback."""
        if not self.control_times:
            return '', ''
        rows = np.percentile(np.array([self.control_times, self.control_cpu_times]) * 1e3, [50.0, 99.0, 100.0],
                             axis=1).T
        wall, cpu = (f'{p50:.3f} / {p99:.3f} / {top:.3f}' for p50, p99, top in rows)
        return wall, cpu

    def publish_status(self, force: bool = False, at: float | None = None) -> None:
        """Status when it changed (or `force`); `at` is the node time of the decision it reports (default now)."""
        if self.planning is not None and self.planning.on_thread():
            self._status_key = None   # a change on the planning thread: the next control tick publishes it
            return
        level, message, reason = self.status()
        key = (level, message, reason)
        if key == self._status_key and not force:
            return
        if self._status_key is None or key[1] != self._status_key[1]:
            self._status_since = self.now() if at is None else at
        self._status_key = key
        nav = self.navigator
        waypoint = None if nav is None or nav.waypoint is None else nav.waypoint
        values = {
            'reason': reason,
            'activations': 0 if nav is None else nav.activations,
            'escapes': 0 if nav is None else nav.escapes,
            'manoeuvres': 0 if nav is None else nav.manoeuvres,
            'waypoint': waypoint,
            'goal': self.goal,
            'cost': 0.0 if nav is None else float(nav.cost),
            'others': ' '.join(self.robots.fleet.names(self.now())),
            # What is avoided on data that stopped coming: robots by name, '/movers' (stale_inputs).
            'stale': ' '.join(name for name, _ in self.stale_inputs(self.now())),
            'algorithm': self.algorithm,
            't': self.now(),
            # When the message (mode) began: a monitor that missed that status (keep-last at a high rtf) and
            # hears a later one, re-published, still knows when the robot arrived.
            'since': self._status_since,
            'odom_lag': self.odom_lag,
            'obstacles': -1 if self.obstacles is None else len(self.obstacles),
            # Who hears cmd_vel (the plant; the clock's lock step): the readers this writer has matched. DDS
            # matches each end on its own, so that the plant's end is matched too is told by ...
            'cmd_vel_readers': self.cmd_pub.get_subscription_count(),
            # ... its odometry having reached this planner: while simulated time holds at 0 a plant publishes
            # its start state once its cmd_vel reader is matched (odometry is volatile: a match is not a delivery).
            'odom_heard': self.odom_heard,
            # Perception of `scan`: scans taken, movers tracked now, and why the last scan was not (if it was not).
            'scans': self.scan_perception.scans,
            'tracks': len(self.scan_perception.movers(self.now())),
            'scan_problem': self.scan_problem,
        }
        values['control_ms'], values['control_cpu_ms'] = self.control_ms_both()
        rate = self.control_rate()
        # The control loop's deadlines: its achieved rate, how old the plan driven on is, how long passes take.
        values['control_hz'] = '' if rate is None else round(rate, 2)
        values['plan_age'] = round(self.plan_age(), 3)
        values['planning_ms'] = self.planning_ms()
        # Sent as its bytes (msg_tools.cdr): convert.make_status's message (~0.4 ms of CPU to build and convert for
        # the middleware at 16 robots), not built. The level is one of DiagnosticStatus' byte constants.
        self.status_pub.publish(cdr.diagnostic_status_cdr(level[0], self.get_namespace(), message, '',
                                                          convert.status_values(values)))


    def diagnostic_tasks(self) -> list[Task]:
        """/diagnostics: the navigation (as on status), the odometry (STALE when it stopped), the clock."""
        level, message, reason = self.status()
        tasks = [Task('navigation', level, message, {'reason': reason, 'goal': self.goal,
                                                     'algorithm': self.algorithm})]
        t = self.now()
        topic = self.own_odom_topic
        if self.odom_problem:
            odometry = Task('odometry', DiagnosticStatus.ERROR, 'rejected', {'reason': self.odom_problem})
        elif self.odom is None:
            odometry = Task('odometry', DiagnosticStatus.WARN, 'waiting', {'reason': f'no odometry on {topic} yet'})
        elif t - self.odom_received > self.odom_timeout or self.hold.startswith('odometry stale'):
            why = self.hold if self.hold.startswith('odometry stale') else \
                f'none for {t - self.odom_received:.2f} s (odom_timeout {self.odom_timeout:g} s)'
            odometry = Task('odometry', DiagnosticStatus.STALE, 'stale', {'reason': why, 'topic': topic})
        else:
            odometry = Task('odometry', DiagnosticStatus.OK, 'fresh', {'topic': topic, 'lag': self.odom_lag,
                                                                       'heard': self.odom_heard})
        rate, late = self.control_rate(), self.rate_problem()
        level = DiagnosticStatus.ERROR if self.plan_problem else DiagnosticStatus.WARN if late else DiagnosticStatus.OK
        control = Task('control', level, 'stalled' if self.plan_problem else 'late' if late else 'on time', {
            'reason': self.plan_problem or late, 'rate_hz': '' if rate is None else round(rate, 2),
            'target_hz': self.control_rate_hz, 'tick_ms': self.control_ms(), 'plan_age': round(self.plan_age(), 3),
            'planning_ms': self.planning_ms()})
        kind = 'simulated time' if self.sim_time.active else 'wall time'
        clock = Task('clock', DiagnosticStatus.WARN if self.clock_problem else DiagnosticStatus.OK, kind,
                     {'reason': self.clock_problem, 't': t})
        stale = self.stale_inputs(t)
        others = Task('others', DiagnosticStatus.WARN, 'stale', {
            'reason': 'kept where last seen, the reach widening at the last speed known, until fresh data comes',
            **{name: f'{age:.1f} s old' for name, age in stale}}) if stale else \
            Task('others', DiagnosticStatus.OK, 'fresh', {'robots': ' '.join(self.robots.fleet.names(t))})
        return [*tasks, control, odometry, others, clock]
