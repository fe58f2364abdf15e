"""What the planner node tells about itself: its `status` (diagnostic_msgs/DiagnosticStatus), the tasks it puts
on /diagnostics, and the control timings both carry.

The levels, messages and reasons are those fastep_ros/planner.py's module docstring lists; this module is how
they are worked out from the node's state. `PlannerReports` is the node's `reports` member: it owns the status
publisher, /diagnostics, what was last published and the control loop's timings (wall and CPU times, stamps).
"""

from __future__ import annotations

import collections
from typing import Any, Protocol

import numpy as np
from diagnostic_msgs.msg import DiagnosticStatus
from rclpy.lifecycle import LifecycleNode

from fastep_core.planning.control import ControlTick
from fastep_core.planning.navigator import Mode, Navigator
from fastep_ros.diagnostics import Diagnostics, Task
from fastep_ros.lifecycle import Lifecycle
from fastep_ros.planner_inputs import PlannerInputs
from fastep_ros.planning_thread import PlanningThread
from fastep_ros.robots import RobotFollower
from fastep_ros.sim_time import SimTimeWatch
from msg_tools import cdr, convert, interface
from msg_tools.interface import offered_qos

__all__ = ['CONTROL_TIMES', 'RATE_SHORTFALL', 'RATE_WINDOW', 'STATUS_MESSAGES', 'PlannerNodeView', 'PlannerReports']

# Every `status` message the planner says (PlannerReports.status), its levels and what it means: the reference's
# status page (fastep_ros.reference) is made from it, and a test checks that status() says nothing else.
STATUS_MESSAGES: tuple[tuple[str, str, str], ...] = (
    ('inactive', 'OK', 'lifecycle: deactivated; sent once as the publishers go off, then nothing is published and no '
                       'commands are sent (activate to drive)'),
    ('waiting', 'WARN', 'waiting for the world (/obstacles, /map), for localization (none yet, a map -> odom from '
                        'TF that stopped, or a localization that puts the robot off the map: "localization pose '
                        'refused: ..."), or for a robot in the way (the reason says which); no commands while the '
                        'world or localization is missing'),
    ('idle', 'OK', 'no goal: none given yet, or cancelled (the reason says so)'),
    ('kinematic', 'OK / WARN', 'driving to the goal (or the route vertex in sight) by the kinematic controller; '
                               'WARN while inputs are stale (kept where last seen), a newer goal was refused, a '
                               'localization off the map was refused (the last pose taken kept), the control '
                               'loop acts late and drives slower for it ("speed reduced to ...: the control loop '
                               'is ... late": its worst recent tick gap, odometry and scan age), or the base '
                               'tracks worse than configured (its braking measured from odometry)'),
    ('avoiding', 'OK / WARN', 'driving to a swarm waypoint, escaping a trap, manoeuvring or yielding to a mover; '
                              'WARN as for kinematic'),
    ('arrived', 'OK', 'the goal is reached (within goal_tolerance, and facing its heading if it has one)'),
    ('failed', 'ERROR', 'the goal failed; the reason says why (the failure reasons below; "planning timed out": '
                        'no plan for planning_timeout)'),
    ('stale', 'WARN / ERROR', 'held still: own odometry missing, old, rejected or not finite, or the clock stands '
                              'still (WARN); planning stalled, the plan older than max_plan_age (ERROR)'),
    ('conflict', 'ERROR', 'another node publishes on cmd_vel: not commanding (exclusive_cmd_vel)'),
    ('blind', 'WARN / ERROR', 'held still for its scans (scan_mode): scans come but cannot be used (no transform '
                              'places them, stamped too far from the clock, not a scanner\'s, a mount outside the '
                              'robot) or stopped coming (ERROR, also while idle when the scans that come cannot be '
                              'used); the first scans waiting for their transform (WARN, scan_timeout); the reason '
                              'names the cause'),
)

RATE_WINDOW = 2.0        # s of node time over which the control loop's achieved rate is measured
CONTROL_TIMES = 200      # control callbacks (10 s at 20 Hz) whose wall times status' control_ms sums up
BASE_SHORT = 'the base tracks worse than configured'
RATE_SHORTFALL = 0.9     # an achieved rate below this share of control_rate_hz is a missed rate (WARN)


class PlannerNodeView(Protocol):
    """What the reports read of their planner node (fastep_ros.planner.PlannerNode); `ros`: the node itself."""

    algorithm: str
    goal: tuple[float, float] | None
    goal_refused: str
    hold: str
    plan_problem: str
    plan_failed: str
    clock_problem: str
    cmd_conflict: str
    exclusive_cmd_vel: bool
    control_rate_hz: float
    odom_timeout: float
    control_count: int
    navigator: Navigator | None
    control_tick: ControlTick | None
    planning: PlanningThread[Any, Any] | None
    inputs: PlannerInputs
    robots: RobotFollower
    sim_time: SimTimeWatch
    lifecycle: Lifecycle
    cmd_pub: Any

    @property
    def ros(self) -> LifecycleNode: ...
    def now(self) -> float: ...
    def speed_cap(self) -> float | None: ...


class PlannerReports:
    """Status and /diagnostics of the planner node (fastep_ros.planner.PlannerNode's `reports`), with the control
    loop's timings they carry."""

    def __init__(self, node: PlannerNodeView) -> None:
        self.node = node
        self.control_times: collections.deque[float] = collections.deque(maxlen=CONTROL_TIMES)
        self.control_cpu_times: collections.deque[float] = collections.deque(maxlen=CONTROL_TIMES)
        self.control_stamps: collections.deque[float] = collections.deque(maxlen=CONTROL_TIMES)   # node times
        # Lifecycle publishers (on while the node is active): made by the node's configure, destroyed by its cleanup.
        self.status_pub = node.ros.create_lifecycle_publisher(DiagnosticStatus, interface.STATUS,
                                                              offered_qos(interface.STATUS))
        self.cmd_vel_readers = 0   # cmd_vel's matched readers when status last told them
        self.diagnostics: Diagnostics | None = None   # made once the node's clock is watched (make_diagnostics)
        # What was last published.
        self._status_key: tuple[Any, ...] | None = None
        self._status_since = 0.0

    def make_diagnostics(self) -> None:
        self.diagnostics = Diagnostics(self.node.ros, managed=True)

    def destroy(self) -> None:
        """Destroy the publishers of status and /diagnostics."""
        self.node.ros.destroy_lifecycle_publisher(self.status_pub)
        if self.diagnostics is not None:
            self.diagnostics.destroy()
            self.diagnostics = None

    def changed(self) -> None:
        """What status tells changed: the next publish sends it."""
        self._status_key = None

    def timed(self, wall: float, cpu: float) -> None:
        """A control callback's wall and CPU time (s): control_ms, control_cpu_ms."""
        self.control_times.append(wall)
        self.control_cpu_times.append(cpu)

    def status(self) -> tuple[bytes, str, str]:
        if not self.node.lifecycle.is_active:
            return DiagnosticStatus.OK, 'inactive', 'lifecycle: not active (no commands); activate to drive'
        if self.node.cmd_conflict and self.node.exclusive_cmd_vel:
            return DiagnosticStatus.ERROR, 'conflict', f'{self.node.cmd_conflict}: not commanding while another node ' \
                                                       f'does (exclusive_cmd_vel)'
        level, message, reason = self.navigation_status()
        if self.node.clock_problem and level != DiagnosticStatus.ERROR:
            # The control loop stands still with the clock: a robot under way is held (check_clock).
            return DiagnosticStatus.WARN, 'stale' if message in (Mode.KINEMATIC.value, Mode.AVOIDING.value) else \
                message, self.node.clock_problem
        return level, message, reason

    def navigation_status(self) -> tuple[bytes, str, str]:
        nav = self.node.navigator
        if nav is None:
            inputs = self.node.inputs
            missing = [name for name, have in ((interface.OBSTACLES, inputs.obstacles is not None),
                                               (interface.MAP, inputs.workspace_param or inputs.map_workspace))
                       if not have]
            refused = f'; {inputs.world_problem}' if inputs.world_problem else ''   # a world message refused
            return DiagnosticStatus.WARN, 'waiting', f'waiting for the world ({" and ".join(missing)}){refused}'
        if self.node.plan_failed:   # failed by the executor: planning left no plan for planning_timeout
            return DiagnosticStatus.ERROR, Mode.FAILED.value, self.node.plan_failed
        mode = nav.mode
        if mode is Mode.FAILED:
            return DiagnosticStatus.ERROR, mode.value, nav.reason
        if self.node.plan_problem and mode in (Mode.KINEMATIC, Mode.AVOIDING):
            return DiagnosticStatus.ERROR, 'stale', self.node.plan_problem
        scans = self.node.inputs.scans
        level, blind = scans.hold(self.node.now())
        if mode in (Mode.IDLE, Mode.ARRIVED):
            if blind and scans.problem and level == DiagnosticStatus.ERROR:
                return level, 'blind', blind   # scans come and cannot be used: said before a goal is given
            return DiagnosticStatus.OK, mode.value, nav.reason
        if self.node.hold:
            if self.node.hold.startswith('waiting'):
                return DiagnosticStatus.WARN, 'waiting', self.node.hold
            return DiagnosticStatus.WARN, 'stale', self.node.hold
        if blind:
            return level, 'blind', blind
        if self.node.goal_refused and self.node.goal is not None:
            return DiagnosticStatus.WARN, mode.value, f'{self.node.goal_refused}; still driving to ' \
                                                     f'({self.node.goal[0]:g}, {self.node.goal[1]:g})'
        refused = self.node.inputs.localization_refused   # the localizer's newest put the robot off the map
        if refused:
            kept = f'{refused} (the last pose taken is kept)'
            return DiagnosticStatus.WARN, mode.value, f'{nav.reason}; {kept}' if nav.reason else kept
        stale = self.node.inputs.stale_inputs(self.node.now())
        if stale:
            kept = f'stale: {", ".join(name for name, _ in stale)} (kept where last seen, the reach widening)'
            return DiagnosticStatus.WARN, mode.value, f'{nav.reason}; {kept}' if nav.reason else kept
        if self.node.inputs.twist_problem:
            problem = self.node.inputs.twist_problem
            return DiagnosticStatus.WARN, mode.value, f'{nav.reason}; {problem}' if nav.reason else problem
        control = self.node.control_tick
        if control is not None and control.slowed:   # a late control loop drives slower (planning/safety/lateness.py)
            return DiagnosticStatus.WARN, mode.value, f'{nav.reason}; {control.slowed}' \
                if nav.reason and nav.reason != control.slowed else control.slowed
        weak = nav.response.problem()
        if weak:
            slower = f'{BASE_SHORT}: {weak} (stops planned with what it measured)'
            return DiagnosticStatus.WARN, mode.value, f'{nav.reason}; {slower}' if nav.reason else slower
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
        if rate is None or rate >= RATE_SHORTFALL * self.node.control_rate_hz:
            return ''
        return f'control loop missed its rate: {rate:.1f} Hz of {self.node.control_rate_hz:g} Hz over the last ' \
               f'{RATE_WINDOW:g} s (tick ms p50 / p99 / max: {self.control_ms()})'

    def plan_age(self) -> float:
        """Seconds (control periods) since the tick the plan in use was planned from; 0 without the thread."""
        result = None if self.node.planning is None else self.node.planning.plan   # read once: plan and its tick
        if result is None:
            return 0.0
        return (self.node.control_count - result.tick) / self.node.control_rate_hz

    def planning_ms(self) -> str:
        """'p50 / p99 / max' of the recent planning passes in ms ('' without the thread or before a pass)."""
        if self.node.planning is None or not self.node.planning.pass_times:
            return ''
        p50, p99, top = np.percentile(np.array(self.node.planning.pass_times) * 1e3, [50.0, 99.0, 100.0])
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

    def publish(self, force: bool = False, at: float | None = None) -> None:
        """Status when it changed (or `force`); `at` is the node time of the decision it reports (default now)."""
        if self.node.planning is not None and self.node.planning.on_thread():
            self._status_key = None   # a change on the planning thread: the next control tick publishes it
            return
        level, message, reason = self.status()
        key = (level, message, reason)
        if key == self._status_key and not force:
            return
        if self._status_key is None or key[1] != self._status_key[1]:
            self._status_since = self.node.now() if at is None else at
        self._status_key = key
        nav = self.node.navigator
        waypoint = None if nav is None or nav.waypoint is None else nav.waypoint
        values = {
            'reason': reason,
            'activations': 0 if nav is None else nav.activations,
            'escapes': 0 if nav is None else nav.escapes,
            'manoeuvres': 0 if nav is None else nav.manoeuvres,
            'waypoint': waypoint,
            'goal': self.node.goal,
            'cost': 0.0 if nav is None else float(nav.cost),
            'others': ' '.join(self.node.robots.fleet.names(self.node.now())),
            # What is avoided on data that stopped coming: robots by name, '/movers' (stale_inputs).
            'stale': ' '.join(name for name, _ in self.node.inputs.stale_inputs(self.node.now())),
            'algorithm': self.node.algorithm,
            't': self.node.now(),
            # When the message (mode) began: a monitor that missed that status (keep-last at a high rtf) and
            # hears a later one, re-published, still knows when the robot arrived.
            'since': self._status_since,
            'odom_lag': self.node.inputs.odom_lag,
            'obstacles': -1 if self.node.inputs.obstacles is None else len(self.node.inputs.obstacles),
            # A world message refused (the world before kept) or coarsened (a map's cells merged), '' if none.
            'world_problem': self.node.inputs.world_problem,
            # Who hears cmd_vel (the plant; the clock's lock step): the readers this writer has matched. DDS
            # matches each end on its own, so that the plant's end is matched too is told by ...
            'cmd_vel_readers': self.node.cmd_pub.get_subscription_count(),
            # ... its odometry having reached this planner: while simulated time holds at 0 a plant publishes
            # its start state once its cmd_vel reader is matched (odometry is volatile: a match is not a delivery).
            'odom_heard': self.node.inputs.odom_heard,
            # Perception of `scan`: scans taken, movers tracked now, and why the last scan was not (if it was not).
            'scans': self.node.inputs.scan_perception.scans,
            'tracks': len(self.node.inputs.scan_perception.movers(self.node.now())),
            'scan_problem': self.node.inputs.scan_problem,
        }
        values['control_ms'], values['control_cpu_ms'] = self.control_ms_both()
        rate = self.control_rate()
        # The control loop's deadlines: its achieved rate, how old the plan driven on is, how long passes take.
        values['control_hz'] = '' if rate is None else round(rate, 2)
        values['plan_age'] = round(self.plan_age(), 3)
        control = self.node.control_tick
        # s the control loop acts later than its stops plan for (worst tick gap, odometry and scan age): it slows.
        values['late'] = 0.0 if control is None else round(control.lateness.late, 3)
        values['planning_ms'] = self.planning_ms()
        cap = self.node.speed_cap()
        if cap is not None:   # m/s: what a speed limit (speed_limit topic) caps max_speed at; absent without one
            values['speed_limit'] = cap
        initial_pose = getattr(self.node.inputs, 'initial_pose', None)   # fastep_ros.initial_pose; absent before one
        if initial_pose is not None and initial_pose.status:
            values['initial_pose'] = initial_pose.status
        # Sent as its bytes (msg_tools.cdr): convert.make_status's message (~0.4 ms of CPU to build and convert for
        # the middleware at 16 robots), not built. The level is one of DiagnosticStatus' byte constants.
        self.status_pub.publish(cdr.diagnostic_status_cdr(level[0], self.node.ros.get_namespace(), message, '',
                                                          convert.status_values(values)))


    def publish_diagnostics(self) -> None:
        if self.diagnostics is not None:
            self.diagnostics.publish(self.diagnostic_tasks())

    def diagnostic_tasks(self) -> list[Task]:
        """/diagnostics: the navigation (as on status), the odometry (STALE when it stopped), the clock."""
        level, message, reason = self.status()
        tasks = [Task('navigation', level, message, {'reason': reason, 'goal': self.node.goal,
                                                     'algorithm': self.node.algorithm})]
        t = self.node.now()
        topic = self.node.inputs.own_odom_topic
        if self.node.inputs.odom_problem:
            odometry = Task('odometry', DiagnosticStatus.ERROR, 'rejected', {'reason': self.node.inputs.odom_problem})
        elif self.node.inputs.odom is None:
            odometry = Task('odometry', DiagnosticStatus.WARN, 'waiting', {'reason': f'no odometry on {topic} yet'})
        elif t - self.node.inputs.odom_received > self.node.odom_timeout or self.node.hold.startswith('odometry stale'):
            why = self.node.hold if self.node.hold.startswith('odometry stale') else \
                f'none for {t - self.node.inputs.odom_received:.2f} s (odom_timeout {self.node.odom_timeout:g} s)'
            odometry = Task('odometry', DiagnosticStatus.STALE, 'stale', {'reason': why, 'topic': topic})
        else:
            odometry = Task('odometry', DiagnosticStatus.OK, 'fresh', {'topic': topic, 'lag': self.node.inputs.odom_lag,
                                                                       'heard': self.node.inputs.odom_heard})
        rate, late = self.control_rate(), self.rate_problem()
        tick = self.node.control_tick
        slowed = '' if tick is None else tick.slowed   # acting late, it drives slower (safety/lateness.py)
        level = DiagnosticStatus.ERROR if self.node.plan_problem else \
            DiagnosticStatus.WARN if late or slowed else DiagnosticStatus.OK
        control = Task('control', level, 'stalled' if self.node.plan_problem else 'slowed' if slowed else
                       'late' if late else 'on time', {
                           'reason': self.node.plan_problem or slowed or late,
                           'rate_hz': '' if rate is None else round(rate, 2), 'target_hz': self.node.control_rate_hz,
                           'tick_ms': self.control_ms(), 'plan_age': round(self.plan_age(), 3),
                           'planning_ms': self.planning_ms(),
                           'late': 0.0 if tick is None else round(tick.lateness.late, 3)})
        kind = 'simulated time' if self.node.sim_time.active else 'wall time'
        clock = Task('clock', DiagnosticStatus.WARN if self.node.clock_problem else DiagnosticStatus.OK, kind,
                     {'reason': self.node.clock_problem, 't': t})
        stale = self.node.inputs.stale_inputs(t)
        others = Task('others', DiagnosticStatus.WARN, 'stale', {
            'reason': 'kept where last seen, the reach widening at the last speed known, until fresh data comes',
            **{name: f'{age:.1f} s old' for name, age in stale}}) if stale else \
            Task('others', DiagnosticStatus.OK, 'fresh', {'robots': ' '.join(self.node.robots.fleet.names(t))})
        nav = self.node.navigator
        scan = self.scan_task(t)
        weak = '' if nav is None else nav.response.problem()
        base = Task('base', DiagnosticStatus.WARN if weak else DiagnosticStatus.OK,
                    'tracks worse than configured' if weak else 'as configured', {
                        'reason': weak,
                        'braking': '' if nav is None else round(nav.response.braking, 3),
                        'turn_braking': '' if nav is None else round(nav.response.turn_braking, 3)})
        return [*tasks, control, odometry, scan, base, others, clock]

    def scan_task(self, t: float) -> Task:
        """/diagnostics' `scan`: whether the robot may drive on its scans (fastep_ros.sensors), and why not."""
        scans = self.node.inputs.scans
        level, why = scans.hold(t)
        values = {'reason': why or scans.problem or scans.waiting, 'topic': scans.topic, 'mode': scans.mode,
                  'heard': scans.heard, 'perceived': self.node.inputs.scan_perception.scans}
        if why:
            return Task('scan', level, 'blind' if level == DiagnosticStatus.ERROR else 'waiting', values)
        if not scans.required():
            return Task('scan', DiagnosticStatus.OK, 'ignored' if not scans.followed else 'not required', values)
        return Task('scan', DiagnosticStatus.WARN if scans.problem else DiagnosticStatus.OK,
                    'usable' if not scans.problem else 'some unusable', values)
