"""Nav2's costmap-clearing services (issue "Nav2's own client", item 3): what the laser added to the planner's belief
forgotten, everywhere (clear_entirely), inside the square around the robot (clear_costmap_around_robot) or outside
it (clear_costmap_except_region), the map's obstacles kept, the next scans adding back what is still there; and an
answer within CLEAR_WAIT while planning is stalled. In the test's process, on the test's clock
(fastep_testing.in_process): the node's callbacks called directly, each service's coroutine stepped by the test
as the action thread's executor would, a control tick between two steps."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from fastep_core.geometry import Circle, Segment
from fastep_core.perception.belief import Perception
from fastep_core.sensing.laser import LaserSpec, scan
from fastep_core.world import World
from fastep_ros.planner import PlannerNode
from fastep_testing.in_process import DT, LoggedLines, planner_node
from fastep_testing.planning_gate import WAIT, Gate, wait_for
from msg_tools import convert

srv = pytest.importorskip('nav2_msgs.srv', reason='nav2_msgs is built by make (interfaces/build.sh)')

SPEC = LaserSpec(range=8.0, fov=2 * math.pi, beams=360, noise=0.01)
ROBOT = (5.0, 10.0)
ON_MAP = Circle((15.0, 16.0), 1.0)              # the map's, out of the laser's reach
NEAR = Segment((7.0, 9.0), (7.0, 11.0))          # not on the map: 2 m ahead of the robot
FAR = Segment((1.5, 8.5), (1.5, 11.5))           # not on the map: 3.5 m behind it
POLE = Circle((5.0, 12.5), 0.4)                  # not on the map: 2.5 m to its left (a track, standing)
RESET = 6.0   # reset_distance: Nav2's square of side 6 around the robot, [2, 8] x [7, 13], holds NEAR and POLE
ENTIRELY_LOCAL, ENTIRELY_GLOBAL = 'local_costmap/clear_entirely_local_costmap', \
    'global_costmap/clear_entirely_global_costmap'
AROUND, EXCEPT = 'local_costmap/clear_costmap_around_robot', 'local_costmap/clear_costmap_except_region'


class Scanned:
    """A point mass standing at ROBOT, its odometry and a scan of the true world every tick, on the test's clock."""

    def __init__(self, node: PlannerNode) -> None:
        self.node, self.now, self.rng = node, 100.0, np.random.default_rng(5)
        node.now = lambda: self.now   # type: ignore[method-assign]  # the test's clock
        node.inputs.on_obstacles(convert.obstacles_to_marker_array([ON_MAP]))

    def tick(self, scans: bool = True, wait: bool = True, odometry: bool = True) -> None:
        """A control tick with the odometry (if `odometry`) and a scan (if `scans`) of now; with the planning
        thread (`wait`) until the pass on its snapshot ended."""
        node = self.node
        self.now += DT
        stamp = convert.seconds_to_stamp(self.now)
        if odometry:
            node.inputs.on_odom(convert.state_to_odometry(ROBOT, stamp))
        if scans:
            walls = np.array([(NEAR.start, NEAR.end), (FAR.start, FAR.end)])
            reading = scan(SPEC, (*ROBOT, 0.0), self.rng, self.now, np.array([ON_MAP.center, POLE.center]),
                           np.array([ON_MAP.radius, POLE.radius]), walls[:, 0], walls[:, 1])
            node.inputs.on_scan(convert.scan_to_laser_scan(reading, stamp))
        count, passes = node.control_count, 0 if node.planning is None else node.planning.passes
        node.on_control()
        if wait and node.planning is not None and node.control_count > count:   # a snapshot went: its pass
            wait_for(lambda: node.planning is not None and node.planning.passes > passes and
                     node.planning.pass_started is None, 'the pass')


def services(node: PlannerNode) -> Any:
    from fastep_ros.costmap_services import CostmapServices
    assert node.actions is not None
    return next(c for c in node.actions.companions if isinstance(c, CostmapServices))


def call(robot: Scanned, name: str, request: Any, ticks: int = 10, odometry: bool = True) -> int:
    """Step the service's coroutine as its executor would, a control tick between two steps, until it answers:
    the ticks it took (AssertionError after `ticks`)."""
    kind = {ENTIRELY_LOCAL: srv.ClearEntireCostmap, ENTIRELY_GLOBAL: srv.ClearEntireCostmap,
            AROUND: srv.ClearCostmapAroundRobot, EXCEPT: srv.ClearCostmapExceptRegion}[name]
    coroutine = services(robot.node).handlers[name](request, kind.Response())
    for k in range(ticks):
        try:
            coroutine.send(None)
        except StopIteration as answered:
            assert isinstance(answered.value, kind.Response)
            return k
        robot.tick(scans=False, wait=False, odometry=odometry)
    coroutine.close()
    raise AssertionError(f'{name}: no answer within {ticks} ticks')


def near(found: Any, item: Circle | Segment, within: float = 0.2) -> bool:
    """Is the believed obstacle `found` the true `item`, about (its centre, or both its ends in either order)?"""
    if isinstance(item, Circle):
        return isinstance(found, Circle) and math.dist(found.center, item.center) < within
    if not isinstance(found, Segment):
        return False
    middle = np.mean([found.start, found.end], axis=0)
    return bool(np.hypot(*(middle - np.mean([item.start, item.end], axis=0))) < within + 0.5 and
                min(math.dist(found.start, item.start), math.dist(found.start, item.end)) < 1.0)


def believed(node: PlannerNode) -> dict[str, bool]:
    """Which of the laser's obstacles the belief holds (in the world the navigator plans in), and the map's."""
    belief = node.inputs.scan_perception.belief
    assert belief is not None and node.navigator is not None
    assert node.navigator.world is belief.world   # the navigator plans in what the belief holds
    items = belief.world.obstacle_list
    return {'near': any(near(o, NEAR) for o in items), 'far': any(near(o, FAR) for o in items),
            'pole': any(near(o, POLE) for o in items), 'map': ON_MAP in items}


def scanned(context: Any, **params: Any) -> tuple[PlannerNode, Scanned]:
    """A planner that has believed NEAR, FAR and POLE from its scans, beside its map's ON_MAP."""
    node = planner_node(context, workspace=[0.0, 0.0, 20.0, 20.0], model='point_mass', robot_radius=0.3, **params)
    robot = Scanned(node)
    for _ in range(8):
        robot.tick()
    assert believed(node) == {'near': True, 'far': True, 'pole': True, 'map': True}
    return node, robot


@pytest.mark.parametrize('name', [ENTIRELY_LOCAL, ENTIRELY_GLOBAL])
def test_clear_entirely_forgets_every_wall_and_track_the_laser_added_and_keeps_the_map(context: Any,
                                                                                      name: str) -> None:
    node, robot = scanned(context, planning_thread=False)
    try:
        logged = LoggedLines(node)
        assert call(robot, name, srv.ClearEntireCostmap.Request()) <= 2
        assert believed(node) == {'near': False, 'far': False, 'pole': False, 'map': True}
        perception = node.inputs.scan_perception.perception
        assert perception is not None and perception.belief.seen_obstacles == () and len(perception.tracker) == 0
        said = [text for level, text in logged.lines if text.startswith(name)]
        assert len(said) == 1 and 'forgot ' in said[0] and ' 0 walls' not in said[0], logged.lines
        robot.tick()   # the next scan adds back what is still there
        assert believed(node) == {'near': True, 'far': True, 'pole': False, 'map': True}
    finally:
        node.destroy_node()


def test_clear_around_robot_forgets_only_inside_the_square_of_side_reset_distance(context: Any) -> None:
    node, robot = scanned(context, planning_thread=False)
    try:
        assert call(robot, AROUND, srv.ClearCostmapAroundRobot.Request(reset_distance=RESET)) <= 2
        assert believed(node) == {'near': False, 'far': True, 'pole': False, 'map': True}
    finally:
        node.destroy_node()


def test_clear_except_region_forgets_only_outside_the_square_of_side_reset_distance(context: Any) -> None:
    node, robot = scanned(context, planning_thread=False)
    try:
        assert call(robot, EXCEPT, srv.ClearCostmapExceptRegion.Request(reset_distance=RESET)) <= 2
        assert believed(node) == {'near': True, 'far': False, 'pole': True, 'map': True}
    finally:
        node.destroy_node()


@pytest.mark.parametrize('inside, kept', [(True, ((8.0, 12.0), (10.0, 12.0))), (False, ((4.0, 12.0), (8.0, 12.0)))],
                         ids=['around', 'except'])
def test_a_wall_across_the_square_s_edge_is_cut_there(inside: bool, kept: tuple[Any, Any]) -> None:
    from fastep_ros.costmap_services import forget_seen
    perception = Perception(SPEC, World((0.0, 0.0, 20.0, 20.0), (ON_MAP,)))
    across, outside, within = Segment((4.0, 12.0), (10.0, 12.0)), Segment((15.0, 2.0), (15.0, 4.0)), \
        Circle((6.0, 9.0), 0.3)
    perception.seen_items = [across, outside, within]
    forgotten = forget_seen(perception, None, ROBOT, RESET, inside)
    left = perception.seen_items
    pieces = [(*s.start, *s.end) for s in left if isinstance(s, Segment) and s.start[1] == 12.0]
    assert len(pieces) == 1 and pieces[0] == pytest.approx((*kept[0], *kept[1]))
    assert (outside in left, within in left) == ((True, False) if inside else (False, True))
    assert (forgotten.cut, forgotten.walls, forgotten.circles) == ((1, 0, 1) if inside else (1, 1, 0))
    assert perception.world.obstacle_list[0] is ON_MAP and perception.belief.world is perception.world


@pytest.mark.parametrize('distance', [math.nan, -1.0])
def test_a_reset_distance_that_is_not_one_clears_nothing_and_says_so(context: Any, distance: float) -> None:
    node, robot = scanned(context, planning_thread=False)
    try:
        logged = LoggedLines(node)
        assert call(robot, AROUND, srv.ClearCostmapAroundRobot.Request(reset_distance=distance)) == 0
        assert believed(node) == {'near': True, 'far': True, 'pole': True, 'map': True}
        assert any(level == 'warning' and 'nothing cleared' in text for level, text in logged.lines)
    finally:
        node.destroy_node()


def test_around_the_robot_clears_nothing_while_its_position_is_not_known_and_says_so(context: Any) -> None:
    node, robot = scanned(context, planning_thread=False)
    try:
        logged = LoggedLines(node)
        robot.now += 10.0   # no odometry for longer than odom_timeout: where the robot is is not known
        assert call(robot, AROUND, srv.ClearCostmapAroundRobot.Request(reset_distance=RESET), odometry=False) <= 2
        assert believed(node) == {'near': True, 'far': True, 'pole': True, 'map': True}
        said = [text for level, text in logged.lines if level == 'warning' and text.startswith(AROUND)]
        assert said and 'nothing cleared: the robot\'s position is not known (odometry stale' in said[0], said
    finally:
        node.destroy_node()


def test_a_service_answers_within_its_bound_while_planning_is_stalled_and_clears_once_the_pass_ends(
        context: Any) -> None:
    from fastep_ros.costmap_services import CLEAR_WAIT
    node, robot = scanned(context)   # with the planning thread: scans perceived by its passes
    assert node.navigator is not None
    gate = Gate.holding(node.navigator)
    try:
        robot.tick(wait=False)
        assert gate.entered.wait(WAIT)   # a pass under way that does not end
        logged = LoggedLines(node)
        services(node).clock = lambda: robot.now   # the wait's clock: the test's
        bound = round(CLEAR_WAIT / DT)
        ticks = call(robot, ENTIRELY_LOCAL, srv.ClearEntireCostmap.Request(), ticks=bound + 5)
        assert bound - 1 <= ticks <= bound + 2, ticks
        assert believed(node)['near']   # not applied: the planning side never took it
        assert any(level == 'warning' and 'answered before it was applied' in text for level, text in logged.lines)
        gate.open.set()   # the held pass ends, and the clearing is applied before the next one
        wait_for(lambda: any('applied late: forgot' in text for _, text in logged.lines), 'the clearing applied')
        assert not believed(node)['near'] and not believed(node)['far']
    finally:
        gate.open.set()
        node.destroy_node()


def test_the_services_have_nav2_s_names_in_the_planner_s_namespace(context: Any) -> None:
    from rclpy.parameter import Parameter
    node = PlannerNode(context=context, namespace='/r1',
                       parameter_overrides=[Parameter('workspace', value=[0.0, 0.0, 20.0, 20.0])])
    try:
        side = services(node).actions.side.node   # the navigation node: its own services, as the graph has them
        names = {name for name, _ in side.get_service_names_and_types_by_node(side.get_name(), '/r1')}
        assert {'/r1/global_costmap/clear_entirely_global_costmap', '/r1/local_costmap/clear_entirely_local_costmap',
                '/r1/local_costmap/clear_costmap_around_robot', '/r1/local_costmap/clear_costmap_except_region',
                '/r1/local_costmap/clear_around_local_costmap',
                '/r1/local_costmap/clear_except_local_costmap'} <= names
    finally:
        node.destroy_node()
