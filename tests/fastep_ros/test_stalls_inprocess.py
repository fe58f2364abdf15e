"""A planner and a plant descheduled at chosen moments, on a clock the test drives: what a loaded machine does to
the control loop, reproduced exactly (docs/robustness.md, "A loaded machine").

The run is test_faults' "map server restarted with a new obstacle" one: fast gains (alpha 1, 3 m/s), circles at
(10, 10) r 1.5 and (15, 10.3) r 1, robot radius 0.5, both nodes built in this process. Time advances in 1 ms
steps. A node that is not stalled runs its timer when it is due and takes the newest message sent to it (both
inputs are LATEST, depth 1); a stalled node runs nothing, and when it wakes its overdue timer runs once, first,
then it takes the newest message (rclpy's executor serves timers before subscriptions). Messages reach the
subscription callbacks as the executor passes them, with the DDS source timestamp of the send when the callback
takes a MessageInfo. Every integration step of the plant is recorded, so the robot's margin to the obstacles is
known exactly, also inside the catch-up after a stall (the plant publishes only its last state).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np
import pytest
from geometry_msgs.msg import Twist, TwistStamped
from rclpy.parameter import Parameter
from rclpy.subscription import Subscription

from fastep_core.geometry import Circle
from fastep_core.world import World
from fastep_ros.planner import PlannerNode
from fastep_ros.plant import PlantNode
from msg_tools import convert
from msg_tools.interface import RELIABLE

CIRCLES = (Circle((10.0, 10.0), 1.5), Circle((15.0, 10.3), 1.0))
START, GOAL, RADIUS = (2.0, 10.0), (18.0, 10.5), 0.5
# The paper's literal activation policy: the moments below (when a circle is detected, where the run passes) were
# measured with it; these tests are about the control loop under stalls, not about when the swarm runs.
FAST = {'alpha1': 1.0, 'alpha2': 1.0, 'max_speed': 3.0, 'algorithm': 'fastep_paper'}


@dataclass(frozen=True)
class Stall:
    """`node` ('planner' or 'plant') runs nothing from `start` until `end` (seconds of the bench's clock)."""

    node: str
    start: float
    end: float


@dataclass(frozen=True)
class Tick:
    """What the planner did at one control tick."""

    t: float
    odom_age: float          # control time minus the stamp of the odometry it had
    command: tuple[float, float]
    mode: str                # status message: kinematic, avoiding, stale...


class _Recording:
    """The plant's model, keeping every state it integrates to."""

    def __init__(self, model: Any, states: list[np.ndarray]) -> None:
        self._model, self._states = model, states

    def __getattr__(self, name: str) -> Any:
        return getattr(self._model, name)

    def integrate(self, state: np.ndarray, command: np.ndarray, dt: float) -> np.ndarray:
        after = self._model.integrate(state, command, dt)
        self._states.append(np.array(after))
        return after


class _Scheduled:
    """One node on the bench: its timer and the newest message waiting for it."""

    def __init__(self, node: Any, period_ms: int, topic: str, on_timer: Any) -> None:
        self.period_ms, self.on_timer = period_ms, on_timer
        self.due_ms = period_ms
        self.subscription: Subscription = next(s for s in node.subscriptions if s.topic_name.endswith(topic))
        self.inbox: list[tuple[Any, int]] = []   # (message, ms it was sent at)

    def run(self, now_ms: int) -> None:
        if now_ms >= self.due_ms:
            self.on_timer()
            self.due_ms += ((now_ms - self.due_ms) // self.period_ms + 1) * self.period_ms  # missed ticks: once
        if self.inbox:
            msg, sent_ms = self.inbox[-1]
            self.inbox.clear()
            # As rclpy's executor does: a callback that takes a MessageInfo gets one.
            if self.subscription._callback_type is Subscription.CallbackType.WithMessageInfo:
                self.subscription.callback(msg, {'source_timestamp': sent_ms * 1_000_000,
                                                 'received_timestamp': now_ms * 1_000_000})
            else:
                self.subscription.callback(msg)


class Bench:
    """The planner and the plant of one robot in this process, on the bench's clock, with chosen stalls."""

    def __init__(self, context: Any, stalls: Sequence[Stall] = ()) -> None:
        self.stalls = tuple(stalls)
        self.now_ms = 0
        # The bench's clock decides when each node runs: every control tick plans (no thread running beside it).
        overrides = {**FAST, 'robot_radius': RADIUS, 'seed': 0, 'planning_thread': False}
        self.planner = PlannerNode(context=context,
                                   parameter_overrides=[Parameter(k, value=v) for k, v in overrides.items()])
        self.plant = PlantNode(context=context, parameter_overrides=[Parameter('start', value=list(START))])
        for node in (self.planner, self.plant):
            node.now = self.now   # type: ignore[method-assign]  # both nodes decide on now(): the bench's clock
        self.states: list[np.ndarray] = []
        self.plant.model = _Recording(self.plant.model, self.states)  # type: ignore[assignment]  # records each step
        self.ticks: list[Tick] = []
        self.nodes = {'plant': _Scheduled(self.plant, 20, 'cmd_vel', self.plant.on_timer),
                      'planner': _Scheduled(self.planner, 50, 'odom', self._control)}
        # The bench delivers what they publish (bytes, as their subscriptions take them).
        self.planner.cmd_pub.publish = self._sender('plant')   # type: ignore[method-assign]  # the bench delivers
        self.plant.odom_pub.publish = self._sender('planner')  # type: ignore[method-assign]  # the bench delivers
        world = World.from_obstacles((0.0, 0.0, 20.0, 20.0), CIRCLES)
        self.planner.inputs.on_obstacles(convert.obstacles_to_marker_array(world.obstacle_list))
        self.planner.inputs.on_map(convert.world_to_occupancy_grid(world, 0.5))
        self.planner.on_goal(convert.point_to_pose_stamped(GOAL))

    def now(self) -> float:
        return self.now_ms * 1e-3

    def _sender(self, to: str) -> Any:
        return lambda msg: self.nodes[to].inbox.append((msg, self.now_ms))

    def _control(self) -> None:
        self.planner.on_control()
        odom = self.planner.inputs.odom
        age = np.inf if odom is None else self.now() - odom.stamp
        command = self.planner.last_command
        message = self.planner.reports.status()[1]
        self.ticks.append(Tick(self.now(), age, (float(command[0]), float(command[1])), message))

    def stalled(self, name: str) -> bool:
        t = self.now()
        return any(s.node == name and s.start <= t < s.end for s in self.stalls)

    def run(self, until: float = 60.0) -> str:
        """Run until the robot arrived or failed, or `until`; the navigator's mode then."""
        assert self.planner.navigator is not None
        while self.now() < until and self.planner.navigator.mode.value not in ('arrived', 'failed'):
            self.now_ms += 1
            for name in ('plant', 'planner'):
                if not self.stalled(name):
                    self.nodes[name].run(self.now_ms)
        return self.planner.navigator.mode.value

    def margins(self) -> list[float]:
        """Per circle, the least distance between its surface and the robot's radius over the run (< 0: hit)."""
        xy = np.array(self.states)[:, :2]
        return [float((np.hypot(*(xy - c.center).T) - c.radius).min()) - RADIUS for c in CIRCLES]

    def close(self) -> None:
        self.planner.destroy_node()
        self.plant.destroy_node()


def drive(context: Any, stalls: Sequence[Stall] = (), until: float = 60.0) -> Bench:
    bench = Bench(context, stalls)
    try:
        bench.run(until)
    finally:
        bench.close()
    return bench


def test_undisturbed_the_run_passes_both_circles_a_tenth_of_a_metre_off(context: Any) -> None:
    bench = drive(context)
    assert bench.planner.navigator is not None and bench.planner.navigator.mode.value == 'arrived'
    assert min(bench.margins()) == pytest.approx(0.114, abs=0.002)   # the half clearance margin a run keeps
    assert max(tick.odom_age for tick in bench.ticks[1:]) < 0.05


# At 6.35 s the robot, past the first circle, drives straight to the goal at 3 m/s: the new circle is more than
# sensing_range (3 m) ahead, so nothing blocks the way yet. Then the plant is descheduled for 0.45 s and the
# planner, 30 ms later, for 1 s. The command the planner sent at 6.35 waits in the plant's queue; when the plant
# wakes (6.80) it first catches up the 0.45 s with the command it held, then takes the waiting one. Counting
# cmd_timeout (0.5 s) from taking it, it drove that command on until 7.30: 0.95 s blind, 2.85 m, into the
# circle (0.04 m inside the radius). Counted from sending, the command ends at 6.85 and the robot stops there.
LATE_COMMAND = (Stall('plant', 6.35, 6.80), Stall('planner', 6.38, 7.38))


def test_a_command_taken_late_acts_no_longer_than_cmd_timeout_after_it_was_sent(context: Any) -> None:
    premise = drive(context, until=6.35)
    assert premise.ticks[-1].mode == 'kinematic' and np.hypot(*premise.ticks[-1].command) == pytest.approx(3.0)
    here = premise.states[-1][:2]
    assert np.hypot(*(here - CIRCLES[1].center)) - CIRCLES[1].radius > premise.planner.params.sensing_range

    bench = drive(context, LATE_COMMAND)
    assert bench.planner.navigator is not None and bench.planner.navigator.mode.value == 'arrived'
    assert min(bench.margins()) >= 0.0, f'margins {bench.margins()}: a command acted after its time'


# The plant is descheduled for 0.6 s while the planner runs on: the odometry it has gets older every tick.
ODOMETRY_STOPS = (Stall('plant', 6.0, 6.6),)


def test_the_planner_holds_the_robot_while_its_odometry_is_older_than_it_predicts(context: Any) -> None:
    bench = drive(context, ODOMETRY_STOPS)
    horizon = bench.planner.max_extrapolation
    late = [tick for tick in bench.ticks if tick.odom_age > horizon]
    assert len(late) >= 6, 'the premise: ticks with odometry older than the prediction horizon'
    moving = [tick for tick in late if tick.command != (0.0, 0.0)]
    # Before: 3 m/s to the goal, "way is clear", decided where the robot would be 0.25 s after the odometry's
    # stamp, while by then it would be 0.6 s on, where the second circle is within sensing range.
    assert not moving, f'commands from odometry it cannot predict: {moving[:3]}'
    assert all(tick.mode == 'stale' for tick in late)
    assert bench.planner.navigator is not None and bench.planner.navigator.mode.value == 'arrived'
    assert min(bench.margins()) >= 0.0


# A schedule found by descheduling both nodes at random (heavily) and minimised: it hits the first circle before
# (0.008 m inside the radius) and, with only the plant's fix, 0.13 m inside. The decisive moment with the
# plant's fix alone: at 7.95 s the planner, its odometry 0.53 s old, sees "way is clear" from where it
# predicts the robot to be and sends 3 m/s to the goal; the plant takes it at 8.13 s, is descheduled from 8.41
# s and drives it until 8.45 s, from beside the first circle into it. With the planner's fix it sends zero.
STALE_DECISION = (
    Stall('planner', 0.477, 0.939), Stall('planner', 1.094, 1.924), Stall('planner', 2.654, 3.511),
    Stall('planner', 4.548, 5.09), Stall('planner', 6.055, 7.029), Stall('planner', 7.092, 7.891),
    Stall('planner', 7.965, 8.556), Stall('plant', 0.772, 1.448), Stall('plant', 1.86, 2.537),
    Stall('plant', 3.672, 4.629), Stall('plant', 5.16, 6.044), Stall('plant', 6.72, 7.083),
    Stall('plant', 7.421, 8.132), Stall('plant', 8.406, 9.073))


def test_no_command_decided_on_stale_odometry_drives_the_robot_into_an_obstacle(context: Any) -> None:
    bench = drive(context, STALE_DECISION)
    assert bench.planner.navigator is not None and bench.planner.navigator.mode.value == 'arrived'
    assert min(bench.margins()) >= 0.0, f'margins {bench.margins()}'


def test_planner_acts_on_odometry_stamped_within_max_extrapolation_only(context: Any) -> None:
    planner = PlannerNode(context=context,
                          parameter_overrides=[Parameter('workspace', value=[0.0, 0.0, 20.0, 20.0]),
                                               Parameter('planning_thread', value=False)])
    now = [50.0]
    planner.now = lambda: now[0]   # type: ignore[method-assign]  # the test's clock
    try:
        planner.inputs.on_obstacles(convert.obstacles_to_marker_array([]))
        planner.on_goal(convert.point_to_pose_stamped(GOAL))
        planner.inputs.on_odom(convert.state_to_odometry(START, convert.seconds_to_stamp(49.8)))
        planner.on_control()
        assert planner.reports.status()[1] == 'kinematic' and np.any(planner.last_command != 0.0)
        planner.inputs.on_odom(convert.state_to_odometry(START, convert.seconds_to_stamp(49.7)))
        planner.on_control()
        _, message, reason = planner.reports.status()
        assert message == 'stale' and reason.startswith('odometry stale: stamped 0.30 s ago'), reason
        assert np.all(planner.last_command == 0.0)
        planner.inputs.on_odom(convert.state_to_odometry(START))   # unset stamp: as old as since it arrived
        now[0] = 50.2
        planner.on_control()
        assert planner.reports.status()[1] == 'kinematic' and np.any(planner.last_command != 0.0)
        now[0] = 50.3
        planner.on_control()
        assert planner.reports.status()[1] == 'stale'
    finally:
        planner.destroy_node()


def random_stalls(seed: int, until: float = 120.0) -> list[Stall]:
    """Each node descheduled every 0.1 s on average (exponential gaps), for 0.02-1 s: it runs a sixth of the
    time."""
    rng = np.random.default_rng(seed)
    stalls = []
    for node in ('planner', 'plant'):
        t = 0.0
        while t < until:
            t += rng.exponential(0.1)
            length = rng.uniform(0.02, 1.0)
            stalls.append(Stall(node, t, t + length))
            t += length
    return stalls


@pytest.mark.parametrize('seed', range(12))
def test_both_nodes_descheduled_at_random_the_robot_touches_nothing(context: Any, seed: int) -> None:
    # Before the fixes, seeds 3, 8 and 11 went 0.2-0.31 m inside the radius (15 of 80 such runs touched); after,
    # the robot holds more (it arrives in 41-61 s instead of 15-19) and keeps 0.045 m at least.
    bench = drive(context, random_stalls(seed), until=120.0)
    assert bench.planner.navigator is not None and bench.planner.navigator.mode.value == 'arrived'
    assert min(bench.margins()) >= 0.0, f'margins {bench.margins()}'


def test_plant_counts_a_commands_age_from_when_it_was_sent(context: Any) -> None:
    plant = PlantNode(context=context, parameter_overrides=[Parameter('start', value=[0.0, 0.0])])
    try:
        twist = convert.command_to_twist([1.0, 0.0])
        assert plant.sent_time(twist, 1_700_000_000_250_000_000) == pytest.approx(1_700_000_000.25)
        assert plant.sent_time(twist, 0) is None   # no source timestamp: the age counts from taking it
        stamped = TwistStamped(twist=twist)
        stamped.header.stamp = convert.seconds_to_stamp(12.5)
        assert plant.sent_time(stamped, 0) == pytest.approx(12.5)
        assert plant.sent_time(TwistStamped(twist=twist), 0) is None   # stamp unset
        plant.advance(100.0)
        plant.now = lambda: 100.4   # type: ignore[method-assign]  # the test's clock
        plant.on_cmd_vel(twist, sent=100.0)
        assert plant.command_time == pytest.approx(100.0)
        plant.advance(101.0)   # acts until 100.5 only: 0.1 s at 1 m/s since it was taken
        assert plant.state[0] == pytest.approx(0.1)
    finally:
        plant.destroy_node()


def test_plant_reads_when_a_twist_was_sent_from_dds(context: Any) -> None:
    """Through DDS (in this process): the subscription gets the message info, and a Twist taken 0.6 s after it
    was published counts its age from the publishing."""
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    plant = PlantNode(context=context)
    sender = rclpy.create_node('sender', context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(plant)
    try:
        pub = sender.create_publisher(Twist, '/cmd_vel', RELIABLE)
        deadline = time.monotonic() + 10.0
        while pub.get_subscription_count() == 0 and time.monotonic() < deadline:
            time.sleep(0.01)
        sent = plant.now()
        pub.publish(convert.command_to_twist([0.5, 0.0]))
        time.sleep(0.6)
        plant.timer.cancel()   # only the subscription is served below
        while plant.command_time is None and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.05)
        assert plant.command.tolist() == [0.5, 0.0]
        # When it was published, not when it was taken (>= 0.6 s later); a loaded machine may pause this test a
        # while between reading the clock and publishing.
        assert plant.command_time is not None and sent - 0.01 <= plant.command_time <= sent + 0.3
    finally:
        executor.shutdown()
        sender.destroy_node()
        plant.destroy_node()
