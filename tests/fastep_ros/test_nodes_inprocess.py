"""The nodes' logic without DDS traffic: each node is built in this process (own context, isolated domain) and
its callbacks are called directly."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path
from typing import Any, Iterator

import numpy as np
import pytest
from diagnostic_msgs.msg import DiagnosticStatus
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from rclpy.parameter import Parameter

from fastep_core.geometry import Circle
from fastep_core.planning.params import PlannerParams
from fastep_core.scenario import load_scenario
from fastep_core.world import World
from fastep_ros import launch
from fastep_ros.clock import tick_plan
from fastep_ros.monitor import Monitor
from fastep_ros.planner import PlannerNode
from fastep_ros.plant import PlantNode
from fastep_ros.processes import ros_value
from fastep_testing.graph import free_domain
from fastep_testing.published import keep_published
from msg_tools import convert

# Every control tick plans, so a handler's effect is seen at once (the planning thread: test_planning_thread.py).
SYNCHRONOUS = {'planning_thread': False}


def make(cls: type, context: Any, **params: Any) -> Any:
    overrides = [Parameter(k, value=v) for k, v in {**SYNCHRONOUS, **params}.items()]
    return cls(context=context, parameter_overrides=overrides)


def test_planner_declares_every_planner_parameter_with_its_description(context: Any) -> None:
    node = make(PlannerNode, context, max_speed=2, n_fireflies=20, step_radius=1.5)
    try:
        defaults = PlannerParams()
        descriptions = PlannerParams.descriptions()
        for name in PlannerParams.names():
            assert node.has_parameter(name), name
            descriptor = node.describe_parameter(name)
            assert descriptor.description == descriptions[name]
            assert not descriptor.read_only   # tunable while running (tests/fastep_ros/test_parameters.py)
            assert 'range' in descriptor.additional_constraints
        assert node.get_parameter('gamma').value == defaults.gamma
        assert node.get_parameter('n_fireflies').value == 20
        assert node.get_parameter('max_speed').value == 2.0  # an integer given for a double is accepted
        assert node.params == defaults.with_overrides({'max_speed': 2.0, 'n_fireflies': 20, 'step_radius': 1.5})
        for name in ('algorithm', 'model', 'robot_radius', 'length', 'trailer_length', 'hitch_offset', 'seed',
                     'control_rate_hz', 'odom_timeout', 'use_stamped_cmd_vel', 'other_robot_radius', 'workspace'):
            assert node.describe_parameter(name).description, name
    finally:
        node.destroy_node()


def _world_messages(node: PlannerNode, world: World) -> None:
    node.inputs.on_obstacles(convert.obstacles_to_marker_array(world.obstacle_list))
    node.inputs.on_map(convert.world_to_occupancy_grid(world, 0.5))


def test_planner_waits_for_the_world_then_takes_a_pending_goal(context: Any) -> None:
    node = make(PlannerNode, context)
    try:
        assert node.reports.status()[:2] == (DiagnosticStatus.WARN, 'waiting')
        assert '/obstacles' in node.reports.status()[2] and '/map' in node.reports.status()[2]
        node.on_goal(convert.point_to_pose_stamped((8.0, 8.0)))
        assert node.navigator is None and node.pending_goal is not None
        _world_messages(node, World.from_obstacles([0, 0, 10, 10], [Circle((5.0, 5.0), 1.0)]))
        assert node.navigator is not None and node.inputs.world is not None
        assert node.inputs.world.workspace == (0.0, 0.0, 10.0, 10.0)
        assert node.goal == (8.0, 8.0) and node.navigator.mode.value == 'kinematic'
        node.on_control()  # no odometry yet: hold still, say why
        assert node.reports.status() == (DiagnosticStatus.WARN, 'waiting', 'waiting for odometry on /odom')
    finally:
        node.destroy_node()


def test_planner_runs_dwa_and_refuses_it_for_a_tractor_trailer(context: Any) -> None:
    from fastep_core.planning.navigators.dwa import DynamicWindow
    from fastep_ros.common import StartupError

    node = make(PlannerNode, context, algorithm='dwa', workspace=[0.0, 0.0, 10.0, 10.0])
    try:
        constraints = node.describe_parameter('algorithm').additional_constraints
        assert constraints == 'fastep | fastep_paper | aco | optimal | dwa | fastep_route'
        node.inputs.on_obstacles(convert.obstacles_to_marker_array([]))
        assert isinstance(node.navigator, DynamicWindow)
    finally:
        node.destroy_node()
    with pytest.raises(StartupError, match='parameter algorithm: dwa drives point_mass and diff_drive robots only; '
                                           'the robot is a tractor_trailer'):
        make(PlannerNode, context, algorithm='dwa', model='tractor_trailer')


def test_planner_rejects_nan_odometry_and_goals_in_other_frames(context: Any) -> None:
    node = make(PlannerNode, context, workspace=[0.0, 0.0, 10.0, 10.0])
    try:
        node.inputs.on_obstacles(convert.obstacles_to_marker_array([]))
        assert node.navigator is not None  # the workspace parameter stands in for /map
        node.on_goal(convert.point_to_pose_stamped((8.0, 8.0)))
        bad = convert.state_to_odometry([1.0, 1.0])
        bad.pose.pose.position.x = math.nan
        node.inputs.on_odom(bad)
        node.on_control()
        level, message, reason = node.reports.status()
        assert (level, message) == (DiagnosticStatus.WARN, 'stale') and 'not finite' in reason
        assert np.all(node.last_command == 0.0)
        node.inputs.on_odom(convert.state_to_odometry([1.0, 1.0]))
        assert node.inputs.odom_problem == ''
        node.on_control()
        goal = convert.point_to_pose_stamped((5.0, 5.0), frame_id='odom')
        node.on_goal(goal)   # refused; the goal under way stays (tests/fastep_ros/test_goals.py)
        level, message, reason = node.reports.status()
        assert (level, message) == (DiagnosticStatus.WARN, 'kinematic') and "frame 'odom'" in reason
        assert node.goal == (8.0, 8.0)
    finally:
        node.destroy_node()


def test_planner_survives_bad_messages_from_unknown_robots_and_bad_goals(context: Any) -> None:
    node = make(PlannerNode, context, workspace=[0.0, 0.0, 10.0, 10.0])
    try:
        node.inputs.on_obstacles(convert.obstacles_to_marker_array([Circle((5.0, 5.0), 1.0)]))
        node.inputs.on_odom(convert.state_to_odometry([1.0, 1.0]))
        # Announced robots: one sends NaN, one infinity, one a sound pose.
        for name, x in (('ghost', math.nan), ('far', math.inf), ('known', 3.0)):
            node.robots.fleet.add(f'/{name}')
            node.robots.fleet.judge(f'/{name}', True)
            msg = convert.state_to_odometry([3.0, 3.0])
            msg.pose.pose.position.x = x
            node.robots.on_odom(f'/{name}', msg)
        assert [o.name for o in node.inputs.other_robots(node.now())] == ['known']
        for goal, words in (((50.0, 5.0), 'outside the map'), ((5.0, 5.0), 'inside an obstacle'),
                            ((math.nan, 1.0), 'not finite'), ((5.0, 6.2), 'occupied')):
            node.on_goal(convert.point_to_pose_stamped(goal))
            node.on_control()
            level, message, reason = node.reports.status()
            assert (level, message) == (DiagnosticStatus.ERROR, 'failed') and words in reason, reason
            assert np.all(node.last_command == 0.0)
        node.on_goal(convert.point_to_pose_stamped((8.0, 8.0)))   # a good goal after bad ones is taken
        node.on_control()
        assert node.reports.status()[1] in ('kinematic', 'avoiding') and np.any(node.last_command != 0.0)
    finally:
        node.destroy_node()


def test_planner_reports_no_valid_path_for_a_walled_in_goal(context: Any) -> None:
    from fastep_core.geometry import Segment
    node = make(PlannerNode, context, workspace=[0.0, 0.0, 10.0, 10.0])
    try:
        box = [Segment((6.0, 6.0), (8.0, 6.0)), Segment((8.0, 6.0), (8.0, 8.0)), Segment((8.0, 8.0), (6.0, 8.0)),
               Segment((6.0, 8.0), (6.0, 6.0))]
        node.inputs.on_obstacles(convert.obstacles_to_marker_array(box))
        node.inputs.on_odom(convert.state_to_odometry([1.0, 1.0]))
        node.on_goal(convert.point_to_pose_stamped((7.0, 7.0)))
        node.on_control()
        level, message, reason = node.reports.status()
        assert (level, message) == (DiagnosticStatus.ERROR, 'failed') and reason.startswith('no valid path'), reason
        assert np.all(node.last_command == 0.0)
    finally:
        node.destroy_node()


def test_plant_integrates_fixed_steps_and_zeroes_bad_or_old_commands(context: Any) -> None:
    node = make(PlantNode, context, start=[1, 2], rate_hz=50.0, cmd_timeout=0.5)
    try:
        assert node.state.tolist() == [1.0, 2.0]
        assert node.advance(10.0) and node.tick == 500
        node.command, node.command_time = np.array([1.0, -0.5]), 10.0
        node.advance(10.2)  # ten steps of 0.02 s
        assert node.state == pytest.approx([1.2, 1.9])
        node.advance(11.0)  # the command times out 0.5 s after it arrived
        assert node.state == pytest.approx([1.5, 1.75])
        twist = Twist()
        twist.linear.x = math.nan
        node.on_cmd_vel(twist)  # logged once, treated as zero
        assert node.command.tolist() == [0.0, 0.0]
    finally:
        node.destroy_node()


def test_before_time_starts_the_plant_publishes_its_start_once_it_hears_commands(context: Any) -> None:
    """A launcher starts the clock only once every path of the loop is up. DDS matches the two ends of a
    connection each on its own, under load seconds apart: a robot whose planner had matched its plant's odometry
    but was not sent it stood still for 16 s of a two-robot run. So while simulated time holds at 0 the plant
    publishes its start state (stamped 0), once its cmd_vel reader is matched: a planner that hears it knows both
    ends of both paths are up."""
    import time

    from rclpy.executors import SingleThreadedExecutor
    from rclpy.time import Time

    plant = make(PlantNode, context, start=[2.0, 3.0], use_sim_time=True)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(plant)
    heard: list[Odometry] = []
    listener = plant.create_subscription(Odometry, 'odom', heard.append, 10)
    planner = None
    try:
        end = time.monotonic() + 1.0
        while time.monotonic() < end:
            executor.spin_once(timeout_sec=0.05)
        assert heard == [], 'no commander yet: the plant does not say it is ready'
        plant.destroy_subscription(listener)
        planner = make(PlannerNode, context, use_sim_time=True, workspace=[0.0, 0.0, 10.0, 10.0])
        assert planner.inputs.odom_heard == 0
        executor.add_node(planner)
        deadline = time.monotonic() + 20.0
        while planner.inputs.odom_heard < 2 and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.1)
        assert planner.inputs.odom_heard >= 2 and planner.cmd_pub.get_subscription_count() == 1
        assert planner.inputs.odom is not None and plant.tick is None   # simulated time has not started
        assert planner.inputs.odom.pose[:2] == (2.0, 3.0)
        assert planner.inputs.odom.stamp == 0.0
        # Once time runs, the plant publishes integrated steps only.
        plant.get_clock().set_ros_time_override(Time(nanoseconds=50_000_000, clock_type=plant.get_clock().clock_type))
        plant.on_timer()
        plant.on_at_rest_tick()
        assert plant.tick == 2 and plant.at_rest_timer.is_canceled()
    finally:
        executor.shutdown(timeout_sec=1.0)
        if planner is not None:
            planner.destroy_node()
        plant.destroy_node()


def test_plant_tractor_trailer_publishes_consistent_odometry(context: Any) -> None:
    node = make(PlantNode, context, model='tractor_trailer', start=[0.0, 0.0, 0.5, 0.5], length=1.2)
    seen: list[Odometry] = []
    keep_published(node.odom_pub, seen.append)
    try:
        node.advance(1.0)
        node.command, node.command_time = np.array([1.0, 0.2]), 1.0
        node.advance(1.4)  # within cmd_timeout: the command still acts
        node.publish()
        odom = seen[-1]
        assert convert.stamp_to_seconds(odom.header.stamp) == pytest.approx(1.4)
        assert odom.header.frame_id == 'odom' and odom.child_frame_id == 'base_link'   # REP-105, root namespace
        assert convert.quaternion_to_yaw(odom.pose.pose.orientation) == pytest.approx(node.state[2])
        expected = node.model.velocity(node.state, np.array([1.0, 0.2]))
        assert convert.odometry_velocity(odom) == pytest.approx(tuple(expected))
    finally:
        node.destroy_node()


def test_clock_tick_plan() -> None:
    assert tick_plan(1.0, 0.05, 400.0) == pytest.approx((0.05, 0.05))
    assert tick_plan(20.0, 0.05, 400.0) == pytest.approx((0.0025, 0.05))
    period, increment = tick_plan(100.0, 0.05, 400.0)
    assert period == pytest.approx(0.0025) and increment == pytest.approx(0.25)


def test_clock_lock_step_waits_longer_for_a_first_answer_and_says_the_time_again_while_it_waits(
        context: Any) -> None:
    """/clock is best effort and a node may be matched after the run started: a node silent since the start is
    late, not dead (waited for up to wait_timeout, not sync_timeout), and the time is said again while waiting."""
    from fastep_ros.clock import ClockNode

    clock = make(ClockNode, context, rtf=1.0, step=0.05, sync_topics=['/r1/cmd_vel'], sync_timeout=0.2,
                 wait_timeout=30.0)
    sent: list[float] = []
    keep_published(clock.pub, lambda msg: sent.append(convert.stamp_to_seconds(msg.clock)))
    wall = [0.0]
    clock.seconds = lambda: wall[0]  # type: ignore[method-assign]  # the test's wall clock
    commands = clock.create_publisher(Twist, '/r1/cmd_vel', 10)   # a planner on the graph
    try:
        assert clock.count_publishers('/r1/cmd_vel') == 1
        clock.matched_at = -1.0   # its subscribers are there: no more holding
        clock.sync['/r1/cmd_vel'].sub = commands   # subscribed (only its presence counts here)
        clock.on_tick()
        assert sent == [pytest.approx(0.05)]   # the first tick waits for nobody
        wall[0] = 1.0   # beyond sync_timeout, but the planner has never answered: still waited for
        clock.on_tick()
        wall[0] = 1.05
        clock.on_tick()
        assert sent == [pytest.approx(0.05)] * 2 and clock.ticks == 1, 'said again, once per HOLD_PERIOD'
        wall[0] = 1.2
        clock.on_sync('/r1/cmd_vel')   # it answers: the next tick at once
        assert clock.ticks == 2 and sent[-1] == pytest.approx(0.1)
        wall[0] = 1.5   # now silent beyond sync_timeout after having answered: taken for dead, time goes on
        clock.on_tick()
        assert clock.ticks == 3 and clock.sync['/r1/cmd_vel'].absent
    finally:
        clock.destroy_node()


def test_clock_lets_observers_lag_observer_lag_ticks_behind_and_no_further(context: Any) -> None:
    """An observer (fastep-launch's monitor, fastep-record) answers on its clock_ack: the lock step goes on without
    it for observer_lag ticks, then waits for it; a planner's cmd_vel (sync_topics) is waited for every tick."""
    from fastep_ros.clock import ClockNode

    clock = make(ClockNode, context, rtf=1.0, step=0.05, sync_topics=['/r1/cmd_vel'],
                 observer_topics=['/recorder/clock_ack'], observer_lag=3, wait_timeout=30.0)
    sent: list[float] = []
    keep_published(clock.pub, lambda msg: sent.append(convert.stamp_to_seconds(msg.clock)))
    wall = [0.0]
    clock.seconds = lambda: wall[0]  # type: ignore[method-assign]  # the test's wall clock
    commands = clock.create_publisher(Twist, '/r1/cmd_vel', 10)
    acks = clock.create_publisher(Twist, '/recorder/clock_ack', 10)   # (only its presence counts here)
    try:
        clock.matched_at = -1.0
        clock.sync['/r1/cmd_vel'].sub, clock.sync['/recorder/clock_ack'].sub = commands, acks

        def answered_tick() -> None:   # the planner answers the tick; the clock ticks once the period is over
            clock.on_sync('/r1/cmd_vel', sent[-1])
            wall[0] += 0.05
            clock.on_tick()

        clock.on_tick()
        answered_tick()
        answered_tick()
        # The observer's first answer is waited for (its /clock reader may not have matched yet: the ticks would
        # pass it by), and the tick said again meanwhile.
        assert clock.ticks == 1 and sent == pytest.approx([0.05, 0.05])
        clock.on_sync('/recorder/clock_ack', 0.05)   # it has taken tick 1
        assert clock.ticks == 2 and sent[-1] == pytest.approx(0.1)
        for _ in range(6):
            answered_tick()
        # Ticks 2-5 (0.1-0.25 s) went out without a word from the observer; tick 6 waits for its acknowledgement
        # of tick 2 at least.
        assert sorted(set(round(t, 6) for t in sent)) == [0.05, 0.1, 0.15, 0.2, 0.25] and clock.ticks == 5
        clock.on_sync('/recorder/clock_ack', 0.1)
        assert clock.ticks == 6 and sent[-1] == pytest.approx(0.3)
        clock.on_sync('/recorder/clock_ack', 0.3)   # all caught up: the next ticks wait for the planner only
        for _ in range(3):
            answered_tick()
        assert clock.ticks == 9 and sent[-1] == pytest.approx(0.45)
        wall[0] += 1.0
        clock.on_tick()   # without the planner's answer no tick, whatever the observer says
        assert clock.ticks == 9
    finally:
        clock.destroy_node()


def test_clock_takes_an_empty_topic_list_and_refuses_a_lag_out_of_range(context: Any) -> None:
    from fastep_ros.clock import ClockNode
    from fastep_ros.errors import StartupError

    # `-p sync_topics:=[]` on a command line: an empty string array (it was a traceback)
    clock = ClockNode(context=context, cli_args=['--ros-args', '-p', 'sync_topics:=[]', '-p', "observer_topics:=['']"])
    try:
        assert clock.sync == {}
    finally:
        clock.destroy_node()
    with pytest.raises(StartupError, match='observer_lag must be in'):
        make(ClockNode, context, observer_lag=501)


def test_recorder_acknowledges_clock_times_clock_ack_period_apart(context: Any, tmp_path: Path) -> None:
    from fastep_ros.recorder import RecorderNode
    from msg_tools import cdr, interface

    recorder = make(RecorderNode, context, output=str(tmp_path / 'run.mcap'), clock_ack=True,
                    clock_ack_period=0.2)
    acked: list[float] = []
    keep_published(recorder.ack_pub, lambda msg: acked.append(convert.stamp_to_seconds(msg.clock)))
    try:
        recorder.types[interface.CLOCK], recorder.counts[interface.CLOCK] = 'rosgraph_msgs/msg/Clock', 0
        for k in range(1, 21):
            recorder.on_message(interface.CLOCK, cdr.clock_cdr(cdr.stamp_parts(0.05 * k)))
        assert acked == pytest.approx([0.05, 0.25, 0.45, 0.65, 0.85])
        assert recorder.counts[interface.CLOCK] == 20   # every time recorded
        recorder.on_message(interface.CLOCK, cdr.clock_cdr(cdr.stamp_parts(1.0)))   # the clock holds 1.0 s
        assert acked[-1] == pytest.approx(1.0) and len(acked) == 6, 'a held time is acknowledged'
        recorder.on_message(interface.CLOCK, cdr.clock_cdr(cdr.stamp_parts(1.0)))
        assert len(acked) == 7 and acked[-1] == pytest.approx(1.0), 'again each time the clock says it again'
    finally:
        recorder.destroy_node()


def test_launch_passes_the_scenario_to_the_nodes() -> None:
    scenario = load_scenario('application')
    plant = launch.plant_params(scenario.robots[0], True)
    assert plant['model'] == 'tractor_trailer' and len(plant['start']) == 4 and plant['use_sim_time'] is True
    planner = launch.planner_params(scenario, 1, 'aco', 7, True)
    assert planner['seed'] == 7 and planner['seed_stream'] == 1 and planner['algorithm'] == 'aco'
    assert planner['robot_radius'] == scenario.robots[1].radius
    assert planner['control_rate_hz'] == pytest.approx(1.0 / scenario.planner.dt)
    cmd = launch._command('planner', '/r2', planner, verbose=False)
    assert cmd[cmd.index('-r') + 1] == '__ns:=/r2'
    assert 'robot_radius:=0.6' in cmd and 'seed:=7' in cmd
    tiny = load_scenario('table2_s1')
    overrides = launch._planner_overrides(tiny.planner.with_overrides({'max_speed': 2.0, 'c': 1e-5}))
    assert overrides == {'max_speed': 2.0, 'c': 1e-5, 'min_approach_speed': 0.0}   # Table 2: the paper's gains
    assert ros_value(1e-5) == '1e-05' and ros_value([5, 25]) == '[5.0, 25.0]'


@pytest.fixture
def monitor(monkeypatch: pytest.MonkeyPatch) -> Iterator[Monitor]:
    """fastep-launch's monitor of table2_s1, on a domain of its own."""
    monkeypatch.setenv('ROS_DOMAIN_ID', str(free_domain()))
    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    built = Monitor(load_scenario('table2_s1'))
    try:
        yield built
    finally:
        built.close()


def test_launch_monitor_keeps_time_from_odometry_when_clock_messages_are_lost(monitor: Monitor) -> None:
    # /clock is best effort: on a loaded machine the monitor once got none for 30 s while the robot drove on,
    # and gave the run up as stalled. Odometry stamps (reliable) carry simulated time too.
    monitor.follow_clock()
    monitor.sim_now = 0.0
    robot = next(iter(monitor.robots.values()))
    monitor.on_odom(robot, convert.state_to_odometry([3.0, 4.0], convert.seconds_to_stamp(12.5)))
    assert monitor.now() == pytest.approx(12.5)
    monitor.on_odom(robot, convert.state_to_odometry([3.0, 4.0], convert.seconds_to_stamp(12.0)))
    assert monitor.now() == pytest.approx(12.5), 'an older stamp must not take time back'
    assert robot.rows == [[pytest.approx(12.5), 3.0, 4.0]]


def test_launch_monitor_acknowledges_clock_times_ack_period_apart_and_a_held_time_each_time(monitor: Monitor) -> None:
    from rosgraph_msgs.msg import Clock

    monitor.connect()
    acked: list[float] = []
    keep_published(monitor.ack_pub, lambda msg: acked.append(convert.stamp_to_seconds(msg.clock)))
    monitor.follow_clock(0.25)
    on_clock = next(s.callback for s in monitor.node.subscriptions if s.topic_name == '/clock')
    for k in range(1, 11):
        on_clock(Clock(clock=convert.seconds_to_stamp(0.05 * k)))
    assert acked == pytest.approx([0.05, 0.3]) and monitor.now() == pytest.approx(0.5)
    on_clock(Clock(clock=convert.seconds_to_stamp(0.5)))   # said again: the clock holds it
    on_clock(Clock(clock=convert.seconds_to_stamp(0.5)))   # ... and again (the first may have been lost)
    assert acked == pytest.approx([0.05, 0.3, 0.5, 0.5])


def test_stamped_cmd_vel_between_planner_and_plant(context: Any) -> None:
    from geometry_msgs.msg import TwistStamped
    planner = make(PlannerNode, context, use_stamped_cmd_vel=True, model='tractor_trailer', robot_radius=0.6)
    plant = make(PlantNode, context, use_stamped_cmd_vel=True, model='tractor_trailer', start=[0, 0, 0, 0])
    sent: list[Any] = []
    keep_published(planner.cmd_pub, sent.append)
    try:
        planner.publish_command(np.array([0.5, -0.25]))
        assert isinstance(sent[0], TwistStamped)
        assert (sent[0].twist.linear.x, sent[0].twist.angular.z) == (0.5, -0.25)
        plant.on_cmd_vel(sent[0])
        assert plant.command.tolist() == [0.5, -0.25]
    finally:
        planner.destroy_node()
        plant.destroy_node()


def test_nodes_publish_the_interface_and_fastep_sim_records_their_qos(context: Any, tmp_path: Path) -> None:
    """Every topic a node publishes has the interface's name, type and QoS, and a fastep-sim recording offers
    exactly the nodes' profiles (so a replay of it looks like the live graph)."""
    from rclpy.node import Node

    from fastep_ros.clock import ClockNode
    from fastep_ros.map_server import MapNode
    from msg_tools import interface
    from msg_tools.mcap_io import open_recording
    from msg_tools.ros2_profile import qos_profile_to_dict, type_name_of
    from msg_tools.sim_mcap import record_run

    scenario = load_scenario('application')    # tractor-trailers: trailer_pose too
    spec = scenario.robots[0]
    nodes: list[Node] = []
    try:
        nodes.append(MapNode(context=context, parameter_overrides=[Parameter('scenario', value='application')]))
        nodes.append(ClockNode(context=context))
        trailer = [Parameter('model', value='tractor_trailer')]
        nodes.append(PlantNode(context=context, namespace=f'/{spec.name}', parameter_overrides=[
            *trailer, Parameter('start', value=[float(v) for v in spec.start])]))
        nodes.append(PlannerNode(context=context, namespace=f'/{spec.name}', parameter_overrides=trailer))
        published = {pub.topic_name: (type_name_of(pub.msg_type), qos_profile_to_dict(pub.qos_profile))
                     for node in nodes for pub in node.publishers if interface.is_interface_topic(pub.topic_name)}
    finally:
        for node in nodes:
            node.destroy_node()
    goal = interface.robot_topic(spec.name, interface.GOAL_POSE)   # the nodes subscribe to it; a user publishes
    expected = {interface.robot_topic(spec.name, t) for t in interface.ROBOT_TOPICS} - {goal}
    assert set(published) == expected | set(interface.SHARED_TOPICS)
    for topic, (type_name, qos) in published.items():
        assert type_name == interface.message_type(topic), topic
        assert [qos] == interface.offered_qos_profiles(topic), topic

    out = tmp_path / 'run.mcap'
    # Two simulated seconds publish on every topic.
    record_run(replace(scenario, planner=scenario.planner.with_overrides({'max_sim_time': 2.0})), 'fastep', 0, out)
    recording = open_recording(out)
    for topic, (type_name, qos) in published.items():
        assert recording.topics[topic].type == type_name, topic
        assert recording.topics[topic].qos == [qos], topic
    assert recording.topics[goal].qos == interface.offered_qos_profiles(goal)


def test_planner_sends_waypoint_plan_and_status_as_convert_s_messages(context: Any) -> None:
    """The waypoint, plan and status a planner sends as bytes (msg_tools.cdr) decode to the messages convert builds
    for what it planned: the target, the plan and its goal in its frame, the status' level, mode and values."""
    from geometry_msgs.msg import PoseStamped
    from nav_msgs.msg import Path as PathMsg
    node = make(PlannerNode, context, workspace=[0.0, 0.0, 10.0, 10.0], frame_id='world_frame')
    sent: dict[str, list[Any]] = {'waypoint': [], 'plan': [], 'status': []}
    keep_published(node.waypoint_pub, sent['waypoint'].append)
    keep_published(node.plan_pub, sent['plan'].append)
    keep_published(node.reports.status_pub, sent['status'].append)
    try:
        node.inputs.on_obstacles(convert.obstacles_to_marker_array([Circle((5.0, 5.0), 1.0)]))
        node.on_goal(convert.point_to_pose_stamped((8.0, 8.0), frame_id='world_frame'))
        node.inputs.on_odom(convert.state_to_odometry([1.0, 1.0], convert.seconds_to_stamp(node.now()),
                                               frame_id='world_frame'))
        node.on_control()
        nav = node.navigator
        assert nav is not None and nav.target is not None
        waypoint, plan, status = sent['waypoint'][-1], sent['plan'][-1], sent['status'][-1]
        assert isinstance(waypoint, PoseStamped) and isinstance(plan, PathMsg)
        assert waypoint == convert.point_to_pose_stamped(tuple(nav.target), waypoint.header.stamp, 'world_frame')
        assert waypoint.header.stamp.sec > 0
        points = [*(tuple(p) for p in nav.plan), (8.0, 8.0)]
        assert plan == convert.waypoints_to_path(points, plan.header.stamp, 'world_frame')
        level, message, reason = node.reports.status()
        assert (status.level, status.name, status.message, status.hardware_id) == (level, '/', message, '')
        values = {kv.key: kv.value for kv in status.values}
        assert list(values) == [kv.key for kv in status.values] == [
            'reason', 'activations', 'escapes', 'manoeuvres', 'waypoint', 'goal', 'cost', 'others', 'stale',
            'algorithm', 't', 'since', 'odom_lag', 'obstacles', 'world_problem', 'cmd_vel_readers', 'odom_heard',
            'scans', 'tracks', 'scan_problem', 'control_ms', 'control_cpu_ms', 'control_hz', 'plan_age', 'late',
            'planning_ms']
        assert (values['reason'], values['goal'], values['algorithm'], values['obstacles']) == \
            (reason, '8,8', node.algorithm, '1')
        assert values['control_ms'] == '' and values['odom_heard'] == '1'   # the tick under way is not counted yet
    finally:
        node.destroy_node()


def test_status_tells_how_long_the_control_callback_takes(context: Any) -> None:
    """status' control_ms and control_cpu_ms: p50 / p99 / max wall and thread-CPU milliseconds of the recent control
    callbacks (what benchmarks read at 16 robots), '' before the first."""
    from fastep_ros.planner_status import CONTROL_TIMES
    node = make(PlannerNode, context)
    try:
        assert node.reports.control_ms() == '' and node.reports.control_ms(cpu=True) == ''
        for _ in range(CONTROL_TIMES + 5):
            node.on_control()
        assert len(node.reports.control_times) == len(node.reports.control_cpu_times) == CONTROL_TIMES
        p50, p99, top = (float(v) for v in node.reports.control_ms().split(' / '))
        assert 0.0 < p50 <= p99 <= top
        cpu = [float(v) for v in node.reports.control_ms(cpu=True).split(' / ')]
        assert cpu == sorted(cpu) and cpu[0] >= 0.0
        # A callback's thread cannot spend more CPU than the wall time it took (the clocks' resolution aside).
        assert all(c <= w + 1e-4 for c, w in zip(node.reports.control_cpu_times, node.reports.control_times))
        node.reports.publish(force=True)   # with it among the values (a status that fails to build raises here)
    finally:
        node.destroy_node()
