"""Managed planner and plant (issue 14, item 6): driven through the lifecycle services over DDS, as Nav2's
lifecycle manager drives its nodes; autostarting by default."""

from __future__ import annotations

import gc
import math
import os
import subprocess
import sys
import threading
import tracemalloc
import weakref
from pathlib import Path as FilePath
from typing import Any

import numpy as np
import pytest
from diagnostic_msgs.msg import DiagnosticStatus
from geometry_msgs.msg import PoseStamped, Twist
from nav_msgs.msg import Path
from rclpy.parameter import Parameter
from visualization_msgs.msg import MarkerArray

from fastep_core.geometry import Circle
from fastep_core.planning.navigator import Mode
from fastep_core.world import World
from fastep_ros.planner import PlannerNode
from fastep_ros.plant import PlantNode
from fastep_testing.graph import ROOT, free_domain, isolated_env, without_dds_noise
from fastep_testing.services import Services
from msg_tools import convert

# Every control tick plans, so a handler's effect is seen at once (the planning thread: test_planning_thread.py).
SYNCHRONOUS = {'planning_thread': False}


def make(cls: type, context: Any, **params: Any) -> Any:
    return cls(context=context, parameter_overrides=[Parameter(k, value=v)
                                                     for k, v in {**SYNCHRONOUS, **params}.items()])


def _drive(node: PlannerNode) -> None:
    world = World.from_obstacles([0, 0, 10, 10], [Circle((5.0, 2.0), 0.5)])
    node.inputs.on_obstacles(convert.obstacles_to_marker_array(world.obstacle_list))
    node.inputs.on_map(convert.world_to_occupancy_grid(world, 0.5))
    node.inputs.on_odom(convert.state_to_odometry(np.array([1.0, 1.0]), convert.seconds_to_stamp(0.0)))
    node.on_goal(convert.point_to_pose_stamped((9.0, 9.0)))


def test_nodes_autostart_active_by_default(context: Any) -> None:
    # Main: plain nodes, no lifecycle services at all.
    for cls in (PlannerNode, PlantNode):
        node = make(cls, context)
        services = Services(context, node)
        try:
            assert services.state() == 'active'
            assert node.get_parameter('autostart').value is True
        finally:
            services.close()


def test_a_lifecycle_manager_drives_the_planner(context: Any) -> None:
    node = make(PlannerNode, context, autostart=False)
    services = Services(context, node)
    commands: list[Twist] = []
    services.client.create_subscription(Twist, '/cmd_vel', commands.append, 10)
    try:
        assert services.state() == 'unconfigured'
        # Unconfigured: nothing made yet (Nav2's order: configure makes the timers, publishers, subscriptions).
        assert not list(node.timers) and not list(node.subscriptions) and not hasattr(node, 'inputs')
        assert services.change_state('configure') and services.state() == 'inactive'
        assert node.control_timer.is_canceled() and node.reports.status()[1] == 'inactive'
        _drive(node)
        assert services.change_state('activate') and services.state() == 'active'
        assert not node.control_timer.is_canceled()
        assert services.spin_until(lambda: any(c.linear.x != 0.0 for c in commands), 10.0)   # it drives
        assert node.reports.status()[1] == Mode.KINEMATIC.value
        commands.clear()
        assert services.change_state('deactivate') and services.state() == 'inactive'
        assert node.control_timer.is_canceled() and node.reports.status()[1] == 'inactive'
        assert services.spin_until(lambda: bool(commands), 10.0)
        assert commands[-1].linear.x == 0.0 and commands[-1].linear.y == 0.0   # a zero cmd_vel stopped it
        assert services.change_state('cleanup') and services.state() == 'unconfigured'
        assert node.goal is None and node.navigator is None and not list(node.timers)   # all released
        assert services.change_state('configure') and node.goal is None and node.navigator is None
        assert services.change_state('shutdown') and services.state() == 'finalized'
        assert not list(node.timers) and not list(node.subscriptions)   # shutdown released it too
    finally:
        services.close()


@pytest.mark.parametrize('cls', [PlannerNode, PlantNode])
def test_what_an_executor_delivers_after_cleanup_does_nothing(context: Any, cls: type) -> None:
    """An executor may call back a subscription or timer it took before cleanup destroyed it (at load the
    EventsExecutor called the planner's odometry callback after cleanup: AttributeError, out of the spin). From
    the moment cleanup begins every callback configure made does nothing, a service's answers empty; the lifecycle
    services and rclpy's /clock subscription keep theirs, and the next configure's callbacks work."""
    from msg_tools import cdr
    params = {'scenario': 'open_field'} if cls is PlantNode else {}
    node = make(cls, context, autostart=False, use_sim_time=True, **params)
    services = Services(context, node)
    try:
        before = {*node.subscriptions, *node.timers, *node.services}
        kept = {each: each.callback for each in before}
        assert services.change_state('configure')
        made = [each for each in (*node.subscriptions, *node.timers, *node.services) if each not in before]
        assert any(each in set(node.subscriptions) for each in made) and any(each in set(node.timers) for each in made)
        taken = {each: each.callback for each in made}
        assert services.change_state('cleanup')
        odometry = cdr.odometry_cdr((1, 0), 'odom', 'base_link', (1.0, 1.0), (0.0, 0.0, 0.0, 1.0), (0.0, 0.0), 0.0)
        for each, callback in taken.items():
            assert each.callback is not callback
            if hasattr(each, 'srv_type'):
                response = each.srv_type.Response()
                assert each.callback(each.srv_type.Request(), response) is response
            elif hasattr(each, 'msg_type'):
                each.callback(odometry if each.raw else each.msg_type())   # as delivered: nothing happens
            else:
                each.callback()
        assert all(each.callback is callback for each, callback in kept.items())
        assert services.change_state('configure') and services.change_state('activate')
        assert services.state() == 'active'
    finally:
        services.close()


@pytest.mark.parametrize('cls', [PlannerNode, PlantNode])
def test_a_transition_the_state_does_not_have_is_refused_and_the_node_carries_on(context: Any, cls: type) -> None:
    """activate while unconfigured, configure while active: success false, the state as it was (rclpy raised out of
    the service callback, and the process ended: a plant's robot then stopped for good)."""
    params = {'scenario': 'open_field'} if cls is PlantNode else {}
    node = make(cls, context, autostart=False, **params)
    services = Services(context, node)
    try:
        assert not services.change_state('activate') and services.state() == 'unconfigured'
        assert services.change_state('configure') and services.change_state('activate')
        assert not services.change_state('configure') and services.state() == 'active'
        assert not services.change_state('cleanup') and services.state() == 'active'
        assert services.change_state('deactivate') and services.state() == 'inactive'
    finally:
        services.close()


def test_an_inactive_plant_takes_no_commands(context: Any) -> None:
    node = make(PlantNode, context, start=[1.0, 1.0])
    services = Services(context, node)
    try:
        assert services.change_state('deactivate') and services.state() == 'inactive'
        assert node.timer.is_canceled()
        twist = Twist()
        twist.linear.x = 1.0
        node.on_cmd_vel(twist)
        assert not np.any(node.command)
        assert services.change_state('activate') and not node.timer.is_canceled()
        node.on_cmd_vel(twist)
        assert node.command[0] == 1.0
    finally:
        services.close()


def test_a_configure_that_fails_says_why_in_one_line_then_a_value_set_right_configures(
        context: Any, capfd: pytest.CaptureFixture[str]) -> None:
    """A value found bad only by configure (odom_timeout must be > 0; rclpy's declaration takes any double): the
    transition fails with one log line, the node stays unconfigured with nothing made; set right, it configures."""
    node = make(PlannerNode, context, autostart=False, odom_timeout=-1.0)
    services = Services(context, node)
    try:
        assert not services.change_state('configure') and services.state() == 'unconfigured'
        assert not list(node.timers) and not list(node.subscriptions) and node.planning is None
        said = [line for line in capfd.readouterr().err.splitlines() if 'configure failed' in line]
        assert len(said) == 1 and 'parameter odom_timeout must be > 0, got -1' in said[0], said
        assert services.set(odom_timeout=2.0)[0].successful   # taken as it is: configure checks it
        assert services.change_state('configure') and node.odom_timeout == 2.0
    finally:
        services.close()


def test_with_autostart_a_bad_value_is_one_line_and_exit_2(tmp_path: FilePath) -> None:
    env = isolated_env(free_domain(), tmp_path / 'roslog')
    done = subprocess.run([sys.executable, '-m', 'fastep_ros.planner', '--ros-args', '-p', 'odom_timeout:=-1.0'],
                          env=env, cwd=ROOT, capture_output=True, text=True, timeout=120)
    lines = without_dds_noise(done.stderr).splitlines()
    assert done.returncode == 2 and len(lines) == 1, done.stderr
    assert 'parameter odom_timeout must be > 0, got -1' in lines[0]


KINDS = ('publishers', 'subscriptions', 'timers', 'services', 'clients', 'guards', 'waitables')


def _counts(node: Any) -> dict[str, int]:
    """The node's entities (rclpy's public Node properties) and this process's live Python threads."""
    return {**{kind: len(list(getattr(node, kind))) for kind in KINDS}, 'threads': threading.active_count()}


def _made_since(node: Any, names: set[str], entities: set[int]) -> list[weakref.ref[Any]]:
    """Weak references to what the node has that it did not have unconfigured (its attributes not in `names`, its
    navigator, planning thread and action servers, its entities not in `entities`)."""
    made = [value for name, value in vars(node).items()
            if name not in names or name in ('navigator', 'planning', 'actions')]
    made += [each for kind in KINDS for each in getattr(node, kind) if id(each) not in entities]
    refs = []
    for each in made:
        try:
            refs.append(weakref.ref(each))
        except TypeError:   # a number, a string, a tuple, a list: held by nothing else
            pass
    return refs


def _memory() -> tuple[int, int]:
    """After a full collection: the Python objects the collector tracks, and this process's resident set (bytes)."""
    gc.collect()
    with open('/proc/self/statm') as statm:
        return len(gc.get_objects()), int(statm.read().split()[1]) * os.sysconf('SC_PAGE_SIZE')


CYCLES = 20


@pytest.mark.skipif(not sys.platform.startswith('linux'), reason='the resident set is read from /proc')
@pytest.mark.parametrize('executor', ['events', 'single'])
def test_twenty_lifecycle_cycles_with_a_goal_leave_nothing_behind(context: Any, executor: str) -> None:
    """configure, activate, a goal the robot drives toward (a plant moves it), deactivate, cleanup, 20 times
    through the lifecycle services, as a lifecycle manager cycles a node, on either executor a node process
    spins (its entities are made and destroyed while it spins). Every deactivate sends a zero cmd_vel,
    and nothing after it; after every configure no goal, plan or status of the cycle before is left; after every
    cleanup all that configure and the cycle made is gone (freed), the node's entities and the live threads are
    what they were unconfigured, and the Python objects and the resident set stay flat (bounds from the first
    cycles)."""
    from msg_tools.interface import OBSTACLES, STATUS_QOS, offered_qos
    planner = make(PlannerNode, context, autostart=False, planning_thread=True, workspace=[0.0, 0.0, 10.0, 10.0])
    plant = make(PlantNode, context, start=[3.0, 3.0])
    services = Services(context, planner, executor)
    services.executor.add_node(plant)
    client = services.client
    commands: list[Twist] = []
    statuses: list[dict[str, Any]] = []
    plans: list[Path] = []
    client.create_subscription(Twist, '/cmd_vel', commands.append, 100)
    client.create_subscription(DiagnosticStatus, '/status', lambda m: statuses.append(convert.diagnostic_to_dict(m)),
                               STATUS_QOS)
    client.create_subscription(Path, '/plan', plans.append, 100)
    world = World.from_obstacles([0, 0, 10, 10], [Circle((5.0, 8.0), 0.5)])
    latched = client.create_publisher(MarkerArray, OBSTACLES, offered_qos(OBSTACLES))
    latched.publish(convert.obstacles_to_marker_array(world.obstacle_list))   # every configure's subscription gets it
    goal_pub = client.create_publisher(PoseStamped, '/goal_pose', 10)
    unconfigured, names = _counts(planner), set(vars(planner))
    entities = {id(each) for kind in KINDS for each in getattr(planner, kind)}
    configured: dict[str, int] | None = None
    kept: list[weakref.ref[Any]] = []   # the cycle before's members
    built = 0              # Python objects the second configure made ...
    built_bytes = 0        # ... and the Python memory its cycle took, configure to the robot moving
    memory = [_memory()]   # (objects, resident set) unconfigured, then after each cleanup
    try:
        for cycle in range(CYCLES):
            goal = (7.0, 3.0) if cycle % 2 == 0 else (1.0, 3.0)   # to and fro: a goal kept would show
            if cycle == 1:
                tracemalloc.start()
            assert services.change_state('configure'), cycle
            if cycle == 1:
                built = _memory()[0] - memory[-1][0]
            # Built afresh: no goal, plan, perception, lock step or report of the cycle before (odometry may be in).
            assert planner.goal is None and planner.goal_msg is None and planner.pending_goal is None
            assert planner.planning is not None and planner.planning.plan is None and planner.control_count == 0
            assert planner.navigator is None or (planner.navigator.mode is Mode.IDLE and not planner.navigator.plan)
            assert planner.lock.acted == -math.inf and not planner.reports.control_stamps
            assert planner.inputs.scan_perception.scans == 0
            members = [planner.inputs, planner.reports, planner.lock, planner.robots, planner.tf]
            assert not any(new is old() for new, old in zip(members, kept)), cycle   # (and the old ones freed)
            kept = [weakref.ref(member) for member in members]
            del members
            counts = _counts(planner)
            assert configured is None or counts == configured, (cycle, counts, configured)
            configured = counts
            statuses.clear()
            plans.clear()
            assert services.change_state('activate'), cycle
            # Its first status once the world is known (the latched /obstacles): idle, no goal.
            assert services.spin_until(lambda: any(s['message'] == 'idle' for s in statuses), 30.0), statuses[-3:]
            assert all(s['message'] in ('idle', 'waiting') and s['goal'] == '' for s in statuses), statuses
            assert all(not p.poses for p in plans), cycle
            start = plant.state.copy()

            def taken(goal: tuple[float, float] = goal) -> bool:
                goal_pub.publish(convert.point_to_pose_stamped(goal))   # again until the new subscription has it
                return services.spin_until(lambda: planner.goal == goal, 0.5)
            assert services.spin_until(taken, 30.0), cycle
            assert services.spin_until(lambda: float(np.hypot(*(plant.state[:2] - start[:2]))) > 0.3,  # noqa: B023
                                       30.0), cycle
            assert any(c.linear.x != 0.0 for c in commands)
            if cycle == 1:
                built_bytes = tracemalloc.get_traced_memory()[0]
                tracemalloc.stop()
            commands.clear()
            assert services.change_state('deactivate'), cycle
            assert services.spin_until(lambda: bool(commands) and commands[-1].linear.x == 0.0, 10.0), cycle
            heard = len(commands)
            services.spin_until(lambda: False, 0.3)   # nothing more comes (no control tick, the publisher off)
            assert len(commands) == heard and commands[-1].linear.y == 0.0 and not np.any(plant.command), cycle
            made = _made_since(planner, names, entities)
            assert services.change_state('cleanup'), cycle
            assert planner.goal is None and planner.navigator is None and planner.planning is None
            assert not hasattr(planner, 'inputs') and not hasattr(planner, 'reports')
            commands.clear()
            statuses.clear()
            plans.clear()
            services.spin_until(lambda: False, 0.1)   # the executor lets go of what it last waited on
            memory.append(_memory())
            alive = [ref() for ref in made if ref() is not None]
            assert not alive, (cycle, alive)
            assert _counts(planner) == unconfigured, (cycle, _counts(planner), unconfigured)
    finally:
        services.close()
        plant.destroy_node()
    objects, rss = [m[0] for m in memory], [m[1] for m in memory]
    print(f'\n{executor}: unconfigured {unconfigured}\nconfigured {configured}\nPython objects per cycle {objects} '
          f'(a configure makes {built}, a cycle takes {built_bytes / 1e6:.2f} MB)\nRSS MB per cycle '
          f'{[round(r / 1e6, 2) for r in rss]}')
    # What leaked would grow with every cycle: a cycle that kept what it made would add one configure's objects and
    # one cycle's memory every time, over the last half of the cycles ten times that. Allowed: half of it, so noise
    # (a busy machine's allocator, DDS's own buffers) never fails it and any such leak always does.
    half = CYCLES // 2
    assert objects[-1] - objects[half] < 0.5 * built * (CYCLES - half), objects
    assert rss[-1] - rss[half] < 0.5 * built_bytes * (CYCLES - half), [round(r / 1e6, 2) for r in rss]


def test_the_plant_releases_what_configure_made_and_keeps_its_robot_where_it_is(context: Any) -> None:
    """Three cycles of the plant: unconfigured it has made nothing; configured, its publishers, subscription and
    timers; cleaned up, nothing again, while the simulated robot stays where the commands drove it."""
    plant = make(PlantNode, context, autostart=False, start=[1.0, 1.0])
    services = Services(context, plant)
    twist = Twist()
    twist.linear.x = 1.0
    try:
        unconfigured = _counts(plant)
        assert not list(plant.timers) and not list(plant.subscriptions)
        for cycle in range(3):
            here = plant.state.copy()
            assert services.change_state('configure') and services.change_state('activate'), cycle
            assert list(plant.timers) and list(plant.subscriptions)
            plant.on_cmd_vel(twist)
            assert services.spin_until(lambda: plant.state[0] > here[0] + 0.05, 10.0), cycle   # noqa: B023
            assert services.change_state('deactivate') and services.change_state('cleanup'), cycle
            assert _counts(plant) == unconfigured and plant.state[0] > here[0], cycle
    finally:
        services.close()
