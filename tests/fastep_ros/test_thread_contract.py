"""The planner node's thread contract (fastep_ros/planner_threads.py): the executor and the planning thread share
nothing mutable; each test races the two sides, or interleaves them where the race once was, and checks the
invariant."""

from __future__ import annotations

import sys
import threading
from typing import Any, Iterator

import numpy as np
import pytest

from fastep_core.geometry import Circle
from fastep_core.planning.control import ControlTick, Plan
from fastep_core.planning.navigator import Mode
from fastep_core.planning.safety.guard import ScanReturns
from fastep_core.planning.safety.guard_inputs import GuardInputs
from fastep_ros.planner import PlannerNode
from fastep_testing.in_process import TickClock, planner_node
from fastep_testing.planning_gate import WAIT, Gate, wait_for
from msg_tools import convert, frames


@pytest.fixture
def fast_switching() -> Iterator[None]:
    """Threads switch as often as the interpreter allows: a race that exists shows within a few thousand reads."""
    interval = sys.getswitchinterval()
    sys.setswitchinterval(1e-6)
    try:
        yield
    finally:
        sys.setswitchinterval(interval)


def make(context: Any, **params: Any) -> PlannerNode:
    overrides = {'workspace': [0.0, 0.0, 20.0, 20.0], **params}
    return planner_node(context, **overrides)


def start_driving(node: PlannerNode, clock: TickClock) -> None:
    node.inputs.on_obstacles(convert.obstacles_to_marker_array([Circle((10.0, 16.0), 1.0)]))
    node.on_goal(convert.point_to_pose_stamped((18.0, 10.0)))
    clock.tick()
    wait_for(lambda: node.planning is not None and node.planning.plan is not None and
             node.planning.busy_for == 0.0, 'the first plan')


def hold_a_pass(node: PlannerNode, clock: TickClock) -> tuple[Any, Gate]:
    """The robot driving on its first plan, then a pass held under way: its navigator and the gate it waits at."""
    start_driving(node, clock)
    nav = node.navigator
    assert nav is not None
    gate = Gate.holding(nav)
    clock.tick()
    assert gate.entered.wait(WAIT)
    return nav, gate


# ------------------------------------------------------------------------------------------------ R1
@pytest.mark.usefixtures('fast_switching')
def test_the_odometry_history_read_while_it_grows_pairs_every_stamp_with_its_own_pose() -> None:
    history = frames.MapFromOdom(keep=4)   # trimmed at every pose added
    stop = threading.Event()
    newest = [0.0]

    def executor() -> None:   # the subscription's side: add and trim, and a clock that goes back now and then
        stamp = 0.0
        while not stop.is_set():
            stamp = 0.0 if stamp > 50.0 else stamp + 0.01
            history.add_odometry(stamp, (stamp, 2.0 * stamp, 0.0))
            newest[0] = stamp

    writer = threading.Thread(target=executor, daemon=True)
    writer.start()
    wrong: list[str] = []
    try:
        for k in range(100_000):
            stamp = newest[0] - 0.005 * (k % 7)
            try:
                pose = history.interpolated(stamp)
            except IndexError as exc:
                wrong.append(f'IndexError at {stamp}: {exc}')
                continue
            if pose is not None and (abs(pose[0] - stamp) > 1e-6 or abs(pose[1] - 2.0 * stamp) > 1e-6):
                wrong.append(f'at {stamp}: {pose}')
    finally:
        stop.set()
        writer.join()
    assert not wrong, f'{len(wrong)} reads paired a stamp with another pose: {wrong[:3]}'


# ------------------------------------------------------------------------------------------------ R2
@pytest.mark.usefixtures('fast_switching')
def test_the_control_tick_checks_the_margin_and_the_returns_of_one_scan_while_perception_replaces_them() -> None:
    from fastep_core.planning.algorithms import make_navigator
    from fastep_core.planning.params import PlannerParams
    from fastep_core.scenario import RobotSpec
    from fastep_core.world import World
    world = World.from_obstacles([0.0, 0.0, 20.0, 20.0], [Circle((10.0, 16.0), 1.0)])
    nav = make_navigator('fastep', RobotSpec('r1', 'point_mass', (2.0, 10.0), (18.0, 10.0), 0.5), 0.5, world,
                         PlannerParams(), 0)
    state = np.array([2.0, 10.0])
    nav.set_goal((18.0, 10.0))
    plan = Plan.of(nav, 0.0, nav.update(0.0, state, ()))
    control = ControlTick(nav)
    stop = threading.Event()

    def perception() -> None:   # the planning side: a scan k perceived, its margin k mm and a return at x = 19 - k mm
        k = 0
        while not stop.is_set():
            k = k % 900 + 1
            returns = ScanReturns(np.array([[19.0 - 1e-3 * k, 3.0]]), state, nav.radius)
            nav.take_perception(GuardInputs(1e-3 * k, returns))

    writer = threading.Thread(target=perception, daemon=True)
    writer.start()
    mixed: list[tuple[float, float]] = []
    try:
        for tick in range(20_000):
            control.command(0.05 * tick, state, (), plan, 0.05)
            margin, returns = control.guard.obstacle_margin, control.guard.scan_points
            if returns is not None and abs((19.0 - returns.points[0, 0]) - margin) > 1e-9:
                mixed.append((margin, float(returns.points[0, 0])))
    finally:
        stop.set()
        writer.join()
    assert not mixed, f'{len(mixed)} ticks checked one scan\'s margin with another\'s returns: {mixed[:3]}'


# ------------------------------------------------------------------------------------------------ R3
def test_a_stale_plan_never_looks_fresh_while_its_successor_is_being_handed_over(context: Any,
                                                                                 monkeypatch: Any) -> None:
    node = make(context, max_plan_age=0.2)   # 4 control periods at 20 Hz
    clock = TickClock(node, (2.0, 10.0))
    gate, handover = Gate(), Gate()
    try:
        start_driving(node, clock)
        assert node.navigator is not None
        gate = Gate.holding(node.navigator)
        clock.tick()
        assert gate.entered.wait(WAIT)
        for _ in range(10):   # the pass is stuck: the plan in use grows old, and the robot is stopped
            clock.tick()
        assert node.reports.status()[1] == 'stale'
        # The stuck pass ends and hands its plan over; the next one, on the newest tick, is caught between making
        # its plan and handing it over.
        made, passes = Plan.of.__func__, [0]   # type: ignore[attr-defined]  # the classmethod's function

        def of(cls: type, *args: Any, **kwargs: Any) -> Plan:
            plan = made(cls, *args, **kwargs)
            passes[0] += 1
            if passes[0] == 2:
                handover.wait()
            return plan
        monkeypatch.setattr(Plan, 'of', classmethod(of))
        gate.open.set()
        assert handover.entered.wait(WAIT)
        clock.tick()   # on the plan in use, still the old one: still too old to drive on
        level, message, reason = node.reports.status()
        assert message == 'stale' and reason.startswith('planning stalled'), (message, reason)
        assert not node.last_command.any()
        handover.open.set()
        wait_for(lambda: node.planning is not None and node.planning.busy_for == 0.0, 'the handover')
        clock.tick()
        wait_for(lambda: node.reports.plan_age() <= 0.05, 'a fresh plan')
        clock.tick()
        assert node.reports.status()[1] != 'stale'
    finally:
        gate.open.set()
        handover.open.set()
        node.destroy_node()


# ------------------------------------------------------------------------------------------------ R4
def test_a_goal_given_before_a_cancel_never_comes_back_after_it(context: Any) -> None:
    node = make(context)
    clock = TickClock(node, (2.0, 10.0))
    gate = Gate()
    try:
        nav, gate = hold_a_pass(node, clock)   # a pass under way: goal and cancel both wait for it, in order
        node.on_goal(convert.point_to_pose_stamped((18.0, 4.0)))
        node.drop_goal('goal canceled')
        gate.open.set()
        wait_for(lambda: node.planning is not None and node.planning.busy_for == 0.0 and nav.mode is Mode.IDLE,
                 'the cancel')
        clock.tick()
        assert node.goal is None and node.goal_msg is None and nav.goal is None
        assert node.reports.status()[1] == 'idle'
    finally:
        gate.open.set()
        node.destroy_node()


# ------------------------------------------------------------------------------------------------ R5
def test_a_new_map_reaches_perception_between_passes_never_under_one(context: Any) -> None:
    node = make(context)
    clock = TickClock(node, (2.0, 10.0))
    gate = Gate()
    try:
        nav, gate = hold_a_pass(node, clock)
        before = node.inputs.world
        node.inputs.on_obstacles(convert.obstacles_to_marker_array([Circle((10.0, 16.0), 1.0),
                                                                    Circle((6.0, 4.0), 1.0)]))
        assert node.inputs.world is before   # the pass under way perceives in the map it started with
        gate.open.set()
        wait_for(lambda: node.inputs.world is not before, 'the new map')
        assert node.inputs.world is not None and len(node.inputs.world.obstacle_list) == 2
        assert nav.world is node.inputs.world
    finally:
        gate.open.set()
        node.destroy_node()


# ------------------------------------------------------------------------------------------------ R6
def test_the_belief_is_published_by_the_executor_never_by_the_planning_thread(context: Any) -> None:
    from sensor_msgs.msg import LaserScan
    node = make(context, model='diff_drive')
    clock = TickClock(node, (2.0, 10.0))
    publishers: list[str] = []
    publish = node.inputs.tracked_pub.publish

    def recorded(msg: Any) -> None:
        publishers.append(threading.current_thread().name)
        publish(msg)
    node.inputs.tracked_pub.publish = recorded   # type: ignore[method-assign]  # who publishes, recorded
    try:
        node.inputs.on_obstacles(convert.obstacles_to_marker_array([Circle((10.0, 16.0), 1.0)]))
        node.on_goal(convert.point_to_pose_stamped((18.0, 10.0)))
        for _ in range(6):
            clock.now += 0.05
            stamp = convert.seconds_to_stamp(clock.now)
            node.inputs.on_odom(convert.state_to_odometry([2.0, 10.0, 0.0], stamp))
            scan = LaserScan(angle_min=-2.35, angle_max=2.35, angle_increment=4.7 / 719, range_min=0.05,
                             range_max=10.0, ranges=[3.0] * 720)
            scan.header.stamp, scan.header.frame_id = stamp, 'base_link'
            node.inputs.on_scan(scan)
            node.on_control()
            wait_for(lambda: node.planning is not None and node.planning.busy_for == 0.0 and
                     node.plan_tick == node.control_count, 'the pass')
        node.on_control()
        assert node.inputs.scan_perception.scans >= 5 and publishers
        assert set(publishers) == {threading.current_thread().name}, publishers
    finally:
        node.destroy_node()


# ------------------------------------------------------------------------------------------------ the base's response
def test_a_pass_plans_its_stops_with_the_base_as_measured_at_its_snapshot_while_the_control_tick_measures_on(
        context: Any) -> None:
    node = make(context, model='diff_drive')
    clock = TickClock(node, (2.0, 10.0))
    taken: list[Any] = []
    try:
        start_driving(node, clock)
        nav = node.navigator
        assert nav is not None and node.control_tick is not None
        update = nav.update

        def recorded(*args: Any) -> np.ndarray:   # what the pass reads of the base, before and after its update
            before = nav.measured_base
            command = update(*args)
            taken.append((before, nav.measured_base))
            return command
        nav.update = recorded   # type: ignore[method-assign]  # what the pass reads, recorded
        clock.tick()
        wait_for(lambda: bool(taken) and node.planning is not None and node.planning.busy_for == 0.0, 'a pass')
        before, after = taken[-1]
        assert before is after and before is not nav.response   # a value of its own, never the live response
        assert before.braking == node.control_tick.response.braking   # as it was when the snapshot was taken
    finally:
        node.destroy_node()
