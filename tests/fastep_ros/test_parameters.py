"""Parameters through the real parameter services (issue 14, item 5), as `ros2 param` uses them: nodes built in this
process on a free domain, a client node beside them calling get/set/describe_parameters over DDS."""

from __future__ import annotations

import math
import os
import select
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from builtin_interfaces.msg import Time as TimeMsg
from diagnostic_msgs.msg import DiagnosticStatus
from rcl_interfaces.msg import ParameterType
from rclpy.parameter import Parameter
from rosgraph_msgs.msg import Clock

from fastep_core.geometry import Circle
from fastep_core.planning.navigator import Mode
from fastep_core.world import World
from fastep_ros.clock import ClockNode
from fastep_ros.planner import PlannerNode
from fastep_ros.plant import PlantNode
from fastep_ros.recorder import RecorderNode
from fastep_testing.graph import free_domain, isolated_env, stop_process
from fastep_testing.services import Services
from msg_tools import convert

DBL_MAX = sys.float_info.max


# Every control tick plans, so a handler's effect is seen at once (the planning thread: test_planning_thread.py).
SYNCHRONOUS = {'planning_thread': False}


def make(cls: type, context: Any, **params: Any) -> Any:
    return cls(context=context, parameter_overrides=[Parameter(k, value=v)
                                                  for k, v in {**SYNCHRONOUS, **params}.items()])


def _with_world_and_goal(node: PlannerNode, start: tuple[float, float] = (1.0, 1.0),
                         goal: tuple[float, float] = (9.0, 9.0)) -> None:
    world = World.from_obstacles([0, 0, 10, 10], [Circle((5.0, 2.0), 0.5)])
    node.inputs.on_obstacles(convert.obstacles_to_marker_array(world.obstacle_list))
    node.inputs.on_map(convert.world_to_occupancy_grid(world, 0.5))
    node.inputs.on_odom(convert.state_to_odometry(np.array(start), convert.seconds_to_stamp(0.0)))
    node.on_goal(convert.point_to_pose_stamped(goal))


def test_planner_tunables_set_through_the_service_reach_the_running_navigator(context: Any) -> None:
    # Main: every parameter was read-only ("Trying to set a read-only parameter").
    node = make(PlannerNode, context)
    services = Services(context, node)
    try:
        _with_world_and_goal(node)
        nav = node.navigator
        assert nav is not None
        node.on_control()
        assert nav.mode is Mode.KINEMATIC and np.hypot(*node.last_command) > 0.0
        results = services.set(a=0.5, alpha1=0.3, alpha2=1, max_speed=0.25, goal_tolerance=0.2, odom_timeout=2.0,
                               control_rate_hz=10.0)
        assert all(r.successful for r in results), [r.reason for r in results]
        assert node.navigator is nav and nav.mode is Mode.KINEMATIC   # the same run goes on, not a restart
        assert (nav.params.a, nav.params.alpha1, nav.params.alpha2) == (0.5, 0.3, 1.0)   # 1 is taken as 1.0
        assert nav.guard_check.params is nav.params and node.params is nav.params
        assert (nav.controller.alpha1, nav.controller.max_speed) == (0.3, 0.25)
        assert node.odom_timeout == 2.0 and node.control_timer.timer_period_ns == 100_000_000
        assert services.set(other_robot_radius=0.7)[0].successful and node.robots.override_radius == 0.7
        node.inputs.on_odom(convert.state_to_odometry(np.array([1.0, 1.0]), convert.seconds_to_stamp(0.0)))
        node.on_control()
        assert math.isclose(float(np.hypot(*node.last_command)), 0.25)   # the new speed limit drives the robot
        assert [v.double_value for v in services.get('a', 'max_speed')] == [0.5, 0.25]
    finally:
        services.close()


def test_planner_refuses_a_bad_set_with_a_reason_and_changes_nothing(context: Any) -> None:
    node = make(PlannerNode, context, algorithm='dwa')
    services = Services(context, node)
    try:
        before = node.params
        cases = {'model': ('tractor_trailer', 'read-only'), 'n_fireflies': (1, 'out of range'),
                 'max_speed': (0.0, 'dwa needs a speed limit'), 'a': (-1.0, 'out of range'),
                 'odom_timeout': (0.0, 'odom_timeout must be > 0'), 'gamma': (math.inf, 'out of range'),
                 'alpha': ('big', 'type')}
        for name, (value, words) in cases.items():
            (result,) = services.set(**{name: value})
            assert not result.successful and words in result.reason, (name, result.reason)
        # A batch is all or nothing: the good change of a refused batch is not made.
        result = services.set_atomically(a=0.4, max_speed=0.0)
        assert not result.successful and 'max_speed' in result.reason
        assert node.params == before and node.get_parameter('a').value == before.a
    finally:
        services.close()


def test_descriptors_carry_real_ranges(context: Any) -> None:
    # Main: the ranges were free text in additional_constraints; floating_point_range / integer_range were empty.
    node = make(PlannerNode, context)
    services = Services(context, node)
    try:
        a, n_fireflies, alpha_damping, rate, model = services.describe('a', 'n_fireflies', 'alpha_damping',
                                                                      'control_rate_hz', 'model')
        assert (a.floating_point_range[0].from_value, a.floating_point_range[0].to_value) == (0.0, DBL_MAX)
        assert (n_fireflies.integer_range[0].from_value, n_fireflies.integer_range[0].to_value) == (2, 10_000)
        assert (alpha_damping.floating_point_range[0].from_value, alpha_damping.floating_point_range[0].to_value) \
            == (0.0, 1.0)
        assert (rate.floating_point_range[0].from_value, rate.floating_point_range[0].to_value) == (0.1, 10_000.0)
        assert not a.read_only and not rate.read_only and model.read_only
    finally:
        services.close()


@pytest.mark.parametrize('cls,params', [(PlannerNode, {}), (PlantNode, {}), (ClockNode, {}), (RecorderNode, {}),
                                        (PlannerNode, {'workspace': [0, 0, 10, 10]})])
def test_every_parameter_has_a_value(context: Any, tmp_path: Path, cls: type, params: dict[str, Any]) -> None:
    # Main: `workspace` (planner), `start` (plant) and `topics` (recorder) were declared without a default:
    # GetParameters answered an empty list for them (a parameter dump broke).
    if cls is RecorderNode:
        params = {'output': str(tmp_path / 'out.mcap')}
    node = make(cls, context, **params)
    services = Services(context, node)
    try:
        names = services.names()
        values = services.get(*names)
        assert len(values) == len(names)
        assert not [n for n, v in zip(names, values) if v.type == ParameterType.PARAMETER_NOT_SET]
        if cls is PlannerNode:
            (workspace,) = services.get('workspace')
            assert workspace.type == ParameterType.PARAMETER_DOUBLE_ARRAY
            assert list(workspace.double_array_value) == [float(v) for v in params.get('workspace', [])]
            assert node.describe_parameter('workspace').read_only
    finally:
        services.close()


def test_plant_command_timeout_changes_while_running_and_its_step_does_not(context: Any) -> None:
    node = make(PlantNode, context)
    services = Services(context, node)
    try:
        (result,) = services.set(cmd_timeout=0.2)
        assert result.successful and node.cmd_timeout == 0.2
        (result,) = services.set(rate_hz=10.0)
        assert not result.successful and 'read-only' in result.reason and node.rate_hz == 50.0
    finally:
        services.close()


def test_a_misspelled_parameter_is_warned_about_at_startup(tmp_path: Path) -> None:
    # Main: `-p odom_timout:=2.0` was ignored without a word.
    env = isolated_env(free_domain(), tmp_path / 'roslog')
    proc = subprocess.Popen([sys.executable, '-m', 'fastep_ros.planner', '--ros-args', '-p', 'odom_timout:=2.0',
                             '-p', 'a:=0.3'], env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    text = b''
    try:
        assert proc.stdout is not None
        fd = proc.stdout.fileno()
        end = time.monotonic() + 60.0
        # The node logs that it is up, then checks the overrides: wait for the line after that one. Read from the
        # pipe itself: select() on a buffered file said "nothing to read" while the lines after the one readline()
        # returned sat in its buffer (the test failed under load, when the node wrote its last lines in one go).
        while time.monotonic() < end and b'unknown parameter' not in text:
            if not select.select([fd], [], [], max(0.0, end - time.monotonic()))[0]:
                break
            chunk = os.read(fd, 65536)
            if not chunk:
                break
            text += chunk
            if b'planner for a' in text:
                end = min(end, time.monotonic() + 10.0)
    finally:
        stop_process(proc)
    lines = text.decode(errors='replace').splitlines(keepends=True)
    warning = [line for line in lines if 'unknown parameter' in line]
    assert warning, ''.join(lines)
    assert 'odom_timout (did you mean odom_timeout?)' in warning[0] and 'a (' not in warning[0]


def _clock(services: Services, sec: int) -> None:
    pub = getattr(services, 'clock_pub', None)
    if pub is None:
        pub = services.clock_pub = services.client.create_publisher(Clock, '/clock', 10)  # type: ignore[attr-defined]  # a test's own attribute
    pub.publish(Clock(clock=TimeMsg(sec=sec)))


def test_no_clock_on_simulated_time_is_a_warning_and_stops_the_robot(context: Any) -> None:
    # Main: on simulated time without /clock the control timer stood still and status stayed OK ('kinematic').
    node = make(PlannerNode, context, use_sim_time=True, clock_timeout=0.3)
    services = Services(context, node)
    try:
        _with_world_and_goal(node)
        node.last_command = np.array([0.5, 0.0])   # as if it had been driving
        reports = node.reports
        assert services.spin_until(lambda: reports.status()[0] == DiagnosticStatus.WARN, 5.0), reports.status()
        level, message, reason = node.reports.status()
        assert message == 'stale' and 'no /clock' in reason
        assert not np.any(node.last_command)        # a zero cmd_vel went out
        tasks = {t.task: t for t in node.reports.diagnostic_tasks()}
        assert tasks['clock'].level == DiagnosticStatus.WARN
        # The clock comes: the warning goes.
        assert services.spin_until(lambda: (_clock(services, 5), 'no /clock' not in node.reports.status()[2])[1], 5.0)
        assert {t.task: t for t in node.reports.diagnostic_tasks()}['clock'].level == DiagnosticStatus.OK
    finally:
        services.close()


def test_switching_use_sim_time_while_driving_keeps_the_goal(context: Any) -> None:
    # Main: switching use_sim_time on without /clock stopped the control loop while status said OK; back on wall
    # time, years ahead of the simulated time, the progress checker failed the goal at once.
    node = make(PlannerNode, context, clock_timeout=0.3)
    services = Services(context, node)
    try:
        _with_world_and_goal(node)
        node.on_control()
        assert node.navigator is not None and node.navigator.mode is Mode.KINEMATIC
        (result,) = services.set(use_sim_time=True)
        assert result.successful
        reports = node.reports
        assert services.spin_until(lambda: reports.status()[0] == DiagnosticStatus.WARN, 5.0), reports.status()
        assert 'no /clock' in node.reports.status()[2]
        assert services.spin_until(lambda: (_clock(services, 100), node.now())[1] >= 100.0, 5.0)
        node.inputs.on_odom(convert.state_to_odometry(np.array([1.5, 1.5]), convert.seconds_to_stamp(100.0)))
        node.on_control()
        assert node.navigator.mode is Mode.KINEMATIC and np.any(node.last_command), node.reports.status()
        (result,) = services.set(use_sim_time=False)
        assert result.successful and node.now() > 1e9
        node.on_control()   # the switch is seen: odometry from the simulated clock is not used
        assert node.reports.status()[1] == 'waiting' and not np.any(node.last_command)
        node.inputs.on_odom(convert.state_to_odometry(np.array([1.6, 1.6]), convert.seconds_to_stamp(0.0)))
        node.on_control()
        assert node.navigator.mode is Mode.KINEMATIC and np.any(node.last_command), node.reports.status()
        assert node.reports.status()[0] == DiagnosticStatus.OK
    finally:
        services.close()


def test_the_example_params_file_configures_a_planner_with_every_parameter_known(context: Any) -> None:
    """config/planner.yaml (the README's "On your robot"): every key is a planner parameter, with its value."""
    from fastep_ros.parameters import unknown_overrides
    from fastep_testing.graph import ROOT
    node = PlannerNode(context=context, namespace='/r1',
                       cli_args=['--ros-args', '--params-file', str(ROOT / 'config' / 'planner.yaml')])
    try:
        assert unknown_overrides(node) == []
        assert (node.algorithm, node.model, node.radius, node.inputs.obstacle_source, node.inputs.scans.mode) == \
            ('fastep_route', 'diff_drive', 0.22, 'map', 'required')
        assert node.inputs.laser_mount is None   # the laser's place comes from TF
        assert node.inputs.localization_topic == '/r1/amcl_pose' and node.params.max_speed == 0.5
    finally:
        node.destroy_node()


@pytest.mark.parametrize('cls', [PlannerNode, PlantNode])
def test_the_full_params_file_sets_every_parameter_to_its_default(context: Any, cls: type) -> None:
    """config/fastep.yaml (generated: fastep_ros.reference): every key a parameter of the node, at its default."""
    from fastep_ros.parameters import unknown_overrides
    from fastep_testing.graph import ROOT
    path = str(ROOT / 'config' / 'fastep.yaml')
    plain, loaded = cls(context=context, namespace='/r1'), cls(context=context, namespace='/r1',
                                                                 cli_args=['--ros-args', '--params-file', path])
    try:
        assert unknown_overrides(loaded) == []
        names = [n for n in plain.list_parameters([], 0).names if n != 'use_sim_time']
        assert [list(v) if hasattr(v, '__len__') and not isinstance(v, str) else v
                for v in (loaded.get_parameter(n).value for n in names)] == \
            [list(v) if hasattr(v, '__len__') and not isinstance(v, str) else v
             for v in (plain.get_parameter(n).value for n in names)]
    finally:
        loaded.destroy_node()
        plain.destroy_node()
