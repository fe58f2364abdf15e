"""Nav2's get_costmap and clear_costmap_around_pose served by the planner (issue "Nav2's own client", item 3): the
belief drawn onto a grid of Nav2's costs (fastep_ros/costmap_grid.py: lethal inside an obstacle, inscribed within
the robot's radius of one, free, no information off the map; row-major from the origin's corner), the global grid
over the workspace and the local one a window following the robot, at the resolution asked within MAX_CELLS; and
clearing what the laser added around a pose given in any frame TF resolves. The grid alone, then the services over
the in-process planner (fastep_testing.in_process), their coroutines stepped by the test as the action thread's
executor would, a control tick between two steps."""

from __future__ import annotations

import math
import time
from typing import Any, Callable, Iterator

import numpy as np
import pytest

from fastep_core.geometry import Circle, Obstacles, Segment
from fastep_core.sensing.laser import LaserSpec, scan
from fastep_ros.costmap_grid import (
    FREE,
    INSCRIBED,
    LETHAL,
    LOCAL_SIZE,
    MAX_CELLS,
    NO_INFORMATION,
    Window,
    draw,
    global_window,
    local_window,
)
from fastep_ros.planner import PlannerNode
from fastep_testing.in_process import DT, LoggedLines, planner_node
from fastep_testing.planning_gate import WAIT, wait_for
from msg_tools import convert

WORKSPACE = (0.0, 0.0, 10.0, 8.0)
RADIUS = 0.3
DISC = Circle((3.0, 4.0), 1.0)
WALL = Segment((6.02, 1.0), (6.02, 7.0))   # off the cells' edges: the cells it passes through are one column


def cell(window: Window, x: float, y: float) -> int:
    """The flat index (Nav2's row-major: y * size_x + x) of the cell holding the point (x, y)."""
    ix = math.floor((x - window.origin_x) / window.resolution)
    iy = math.floor((y - window.origin_y) / window.resolution)
    return iy * window.size_x + ix


# ------------------------------------------------------------------------------------------------ the grid alone
def test_a_circle_and_a_wall_are_lethal_inside_inscribed_within_the_radius_and_free_beyond() -> None:
    window = global_window(WORKSPACE, 0.1)
    assert (window.origin_x, window.origin_y, window.resolution, window.size_x, window.size_y) == \
        (0.0, 0.0, 0.1, 100, 80)
    costs = draw(window, WORKSPACE, RADIUS, [Obstacles([DISC, WALL])])
    assert costs.shape == (80, 100) and costs.dtype == np.uint8
    data = costs.ravel()   # as nav2_msgs/Costmap's data
    assert data[cell(window, 3.0, 4.0)] == LETHAL and data[cell(window, 3.95, 4.0)] == LETHAL   # inside
    assert data[cell(window, 4.12, 4.0)] == INSCRIBED and data[cell(window, 3.0, 2.78)] == INSCRIBED
    assert data[cell(window, 4.45, 4.0)] == FREE and data[cell(window, 3.0, 5.45)] == FREE
    # The wall: the column it passes through lethal over its length, the robot's radius either side inscribed.
    column = costs[:, 60]   # centres x = 6.05, 0.03 m from the wall
    assert (column[10:70] == LETHAL).all() and column[5] == FREE
    assert (costs[40, 57:60] == INSCRIBED).all() and (costs[40, 61:63] == INSCRIBED).all()
    assert costs[40, 55] == FREE and costs[40, 64] == FREE
    # Row-major: (x 3, y 4) is in the disc, its transpose (x 4, y 3) 0.42 m off it.
    assert data[40 * 100 + 30] == LETHAL and data[30 * 100 + 40] == FREE
    assert not (costs == NO_INFORMATION).any()   # every centre is on the map


def test_the_tiled_grid_is_the_grid_of_every_cell_against_every_obstacle() -> None:
    rng = np.random.default_rng(3)
    items: list[Any] = [Circle((float(x), float(y)), float(r)) for x, y, r in
                        zip(rng.uniform(0, 10, 25), rng.uniform(0, 8, 25), rng.uniform(0.05, 0.8, 25))]
    starts = rng.uniform((0.0, 0.0), (10.0, 8.0), (40, 2))
    ends = starts + rng.uniform(-3.0, 3.0, (40, 2))
    items += [Segment(tuple(a), tuple(b)) for a, b in zip(starts, ends)]
    obstacles = Obstacles(items)
    window = global_window(WORKSPACE, 0.05)
    costs = draw(window, WORKSPACE, RADIUS, [obstacles])
    xs = window.origin_x + (np.arange(window.size_x) + 0.5) * window.resolution
    ys = window.origin_y + (np.arange(window.size_y) + 0.5) * window.resolution
    gx, gy = np.meshgrid(xs, ys)
    room = obstacles.clearance(np.column_stack([gx.ravel(), gy.ravel()])).reshape(gx.shape)
    expected = np.where(room <= 0.025, LETHAL, np.where(room < RADIUS, INSCRIBED, FREE))
    assert (costs == expected).all()
    assert {FREE, INSCRIBED, LETHAL} <= set(np.unique(costs).tolist())


def test_the_local_window_follows_the_robot_on_the_global_grid_s_cells_and_has_no_information_off_the_map() -> None:
    obstacles = Obstacles([DISC, WALL])
    glob = global_window(WORKSPACE, 0.05)
    whole = draw(glob, WORKSPACE, RADIUS, [obstacles])
    n = round(LOCAL_SIZE / 0.05)
    for centre in ((5.0, 4.0), (4.23, 3.01), (6.5, 5.77)):
        local = local_window(WORKSPACE, centre, 0.05)
        assert (local.size_x, local.size_y) == (n, n)
        assert abs(local.origin_x + 0.5 * LOCAL_SIZE - centre[0]) <= 0.025 + 1e-9
        assert abs(local.origin_y + 0.5 * LOCAL_SIZE - centre[1]) <= 0.025 + 1e-9
        ix, iy = round(local.origin_x / 0.05), round(local.origin_y / 0.05)
        assert local.origin_x == pytest.approx(ix * 0.05) and local.origin_y == pytest.approx(iy * 0.05)
        assert (draw(local, WORKSPACE, RADIUS, [obstacles]) == whole[iy:iy + n, ix:ix + n]).all()
    corner = local_window(WORKSPACE, (0.5, 7.5), 0.05)   # past the map's left and top edges by 1 m
    costs = draw(corner, WORKSPACE, RADIUS, [obstacles])
    assert (costs[:, :20] == NO_INFORMATION).all() and (costs[-20:, :] == NO_INFORMATION).all()
    assert (costs[:-20, 20:] != NO_INFORMATION).all()


def test_a_resolution_is_honoured_and_one_too_fine_is_drawn_coarser_within_max_cells() -> None:
    window = global_window(WORKSPACE, 0.25)
    assert (window.size_x, window.size_y, window.coarsened) == (40, 32, False)
    fine = global_window((0.0, 0.0, 20.0, 20.0), 1e-4)
    assert fine.coarsened and fine.cells <= MAX_CELLS and fine.resolution == pytest.approx(0.01, rel=0.01)
    exact = global_window((0.0, 0.0, 20.0, 20.0), float(np.float32(0.01)))   # as a float32 request carries it
    assert (exact.size_x, exact.size_y, exact.coarsened) == (2000, 2000, False)
    small = local_window(WORKSPACE, (5.0, 4.0), 1e-3, max_cells=10_000)
    assert small.coarsened and small.cells <= 10_000 and small.size_x == small.size_y >= 99


# ------------------------------------------------------------------------------------------------ the services
srv = pytest.importorskip('nav2_msgs.srv', reason='nav2_msgs is built by make (interfaces/build.sh)')
GLOBAL, LOCAL = 'global_costmap/get_costmap', 'local_costmap/get_costmap'
AROUND_POSE = 'local_costmap/clear_costmap_around_pose'
MAP = (0.0, 0.0, 20.0, 20.0)
STAND = (5.0, 10.0)
ON_MAP = Circle((12.0, 10.0), 1.0)
MAP_WALL = Segment((15.02, 4.0), (15.02, 16.0))


def test_the_costmap_message_draws_the_tracked_movers_and_is_filled_as_nav2_fills_it() -> None:
    from fastep_core.planning.others import OtherRobot
    from fastep_core.world import World
    from fastep_ros.costmap_services import GridInputs, draw_costmap
    mover = OtherRobot('track_1', (3.0, 4.0), (0.5, 0.0), 0.4, mover=True)
    window = global_window(WORKSPACE, 0.1)
    message = draw_costmap(GridInputs(World(WORKSPACE, (WALL,)), (mover,), RADIUS, window, 'map', (7, 5)))
    assert (message.header.frame_id, message.header.stamp.sec, message.header.stamp.nanosec) == ('map', 7, 5)
    meta = message.metadata
    assert (meta.layer, meta.size_x, meta.size_y, meta.resolution) == ('master', 100, 80, pytest.approx(0.1))
    assert (meta.update_time.sec, meta.map_load_time.sec, meta.origin.orientation.w) == (7, 7, 1.0)
    assert message.data[cell(window, 3.0, 4.0)] == LETHAL and message.data[cell(window, 3.55, 4.0)] == INSCRIBED
    assert message.data[cell(window, 6.05, 4.0)] == LETHAL and message.data[cell(window, 4.5, 4.0)] == FREE


class Robot:
    """A point mass standing at `at` in MAP with ON_MAP and MAP_WALL on its map, its odometry every tick."""

    def __init__(self, context: Any, at: tuple[float, float] = STAND, **params: Any) -> None:
        self.node = node = planner_node(context, workspace=list(MAP), model='point_mass', robot_radius=RADIUS,
                                        **params)
        self.now, self.at, self.odometry = 100.0, at, True
        node.now = lambda: self.now   # type: ignore[method-assign]  # the test's clock
        node.inputs.on_obstacles(convert.obstacles_to_marker_array([ON_MAP, MAP_WALL]))
        self.tick()
        wait_for(lambda: node.planning is None or node.planning.plan is not None, 'the first pass')

    def tick(self) -> None:
        self.now += DT
        if self.odometry:
            self.node.inputs.on_odom(convert.state_to_odometry(self.at, convert.seconds_to_stamp(self.now)))
        self.node.on_control()

    def call(self, name: str, request: Any, tick: Callable[[], None] | None = None) -> Any:
        """Step the service's coroutine as its executor would, a control tick between two steps (a wall
        millisecond too: the grid is drawn on a thread of its own), until it answers: its response."""
        kind = {GLOBAL: srv.GetCostmap, LOCAL: srv.GetCostmap}.get(name, srv.ClearCostmapAroundPose)
        coroutine = services(self.node).handlers[name](request, kind.Response())
        deadline = time.monotonic() + WAIT
        while time.monotonic() < deadline:
            try:
                coroutine.send(None)
            except StopIteration as answered:
                assert isinstance(answered.value, kind.Response)
                return answered.value
            (tick or self.tick)()
            time.sleep(0.001)
        coroutine.close()
        raise AssertionError(f'{name}: no answer within {WAIT:g} s')

    def costmap(self, name: str = GLOBAL, resolution: float = 0.0) -> Any:
        request = srv.GetCostmap.Request()
        request.specs.resolution = resolution
        return self.call(name, request).map


def services(node: PlannerNode) -> Any:
    from fastep_ros.costmap_services import CostmapServices
    assert node.actions is not None
    return next(c for c in node.actions.companions if isinstance(c, CostmapServices))


def costs_at(costmap: Any, x: float, y: float) -> int:
    meta = costmap.metadata
    ix = math.floor((x - meta.origin.position.x) / meta.resolution)
    iy = math.floor((y - meta.origin.position.y) / meta.resolution)
    assert 0 <= ix < meta.size_x and 0 <= iy < meta.size_y
    return int(costmap.data[iy * meta.size_x + ix])


def lethal_near(costmap: Any, x: float, y: float) -> bool:
    """Is a cell within 0.1 m along x of (x, y) lethal (a believed wall along y, placed within the scan's noise)?"""
    return any(costs_at(costmap, x + dx, y) == LETHAL for dx in np.linspace(-0.1, 0.1, 9))


@pytest.fixture(params=[True, False], ids=['planning_thread', 'inline'])
def robot(context: Any, request: Any) -> Iterator[Robot]:
    made = Robot(context, planning_thread=request.param)
    try:
        yield made
    finally:
        made.node.destroy_node()


def test_the_global_costmap_is_the_belief_over_the_workspace_as_nav2_fills_it(robot: Robot) -> None:
    costmap = robot.costmap()
    meta = costmap.metadata
    assert costmap.header.frame_id == 'map' and meta.layer == 'master'
    assert (meta.size_x, meta.size_y, meta.resolution) == (400, 400, pytest.approx(0.05))
    assert (meta.origin.position.x, meta.origin.position.y, meta.origin.orientation.w) == (0.0, 0.0, 1.0)
    assert len(costmap.data) == 400 * 400
    stamp = costmap.header.stamp.sec + 1e-9 * costmap.header.stamp.nanosec
    assert robot.now - 1.0 <= stamp <= robot.now   # the node's time it was asked at, a tick or so ago
    assert (meta.update_time.sec, meta.update_time.nanosec) == (costmap.header.stamp.sec,
                                                                 costmap.header.stamp.nanosec)
    assert costs_at(costmap, 12.0, 10.0) == LETHAL and costs_at(costmap, 13.1, 10.0) == INSCRIBED
    assert costs_at(costmap, 15.03, 12.0) == LETHAL and costs_at(costmap, 14.85, 12.0) == INSCRIBED
    assert costs_at(costmap, 5.0, 10.0) == FREE and costs_at(costmap, 13.5, 10.0) == FREE
    grid = np.frombuffer(bytes(costmap.data), dtype=np.uint8).reshape(400, 400)
    assert (grid[80:320, 300] == LETHAL).all()   # the wall's column, row-major: rows are y


def test_the_local_costmap_is_a_window_round_the_robot_that_follows_it(robot: Robot) -> None:
    first = robot.costmap(LOCAL)
    n = round(LOCAL_SIZE / 0.05)
    meta = first.metadata
    assert (meta.size_x, meta.size_y) == (n, n) and len(first.data) == n * n and first.header.frame_id == 'map'
    assert (meta.origin.position.x, meta.origin.position.y) == (pytest.approx(3.5), pytest.approx(8.5))
    assert set(first.data) == {FREE}   # nothing within 1.5 m of (5, 10)
    robot.at = (11.0, 10.2)
    for _ in range(3):
        robot.tick()
    moved = robot.costmap(LOCAL)
    assert (moved.metadata.origin.position.x, moved.metadata.origin.position.y) == \
        (pytest.approx(9.5), pytest.approx(8.7))
    assert costs_at(moved, 12.0, 10.0) == LETHAL and costs_at(moved, 9.6, 10.0) == FREE


def test_a_request_s_resolution_is_honoured_and_one_too_fine_is_drawn_coarser_and_logged(context: Any) -> None:
    robot = Robot(context, planning_thread=False)
    try:
        logged = LoggedLines(robot.node)
        coarse = robot.costmap(resolution=0.25)
        assert (coarse.metadata.size_x, coarse.metadata.resolution) == (80, pytest.approx(0.25))
        assert costs_at(coarse, 12.0, 10.0) == LETHAL
        assert not [text for _, text in logged.lines if text.startswith(GLOBAL)]
        fine = robot.costmap(resolution=1e-4)   # 4 x 10^10 cells asked
        meta = fine.metadata
        assert meta.size_x * meta.size_y <= MAX_CELLS and len(fine.data) == meta.size_x * meta.size_y
        assert meta.resolution == pytest.approx(0.01, rel=0.01) and costs_at(fine, 12.0, 10.0) == LETHAL
        assert any(level == 'warning' and text.startswith(f'{GLOBAL}: resolution 0.0001 m would be more than')
                   for level, text in logged.lines), logged.lines
        nan = robot.costmap(resolution=math.nan)
        assert nan.metadata.resolution == pytest.approx(0.05)
        assert any('resolution nan is not a cell size' in text for _, text in logged.lines)
    finally:
        robot.node.destroy_node()


def test_the_local_costmap_is_empty_and_says_why_while_the_robot_s_position_is_not_known(context: Any) -> None:
    robot = Robot(context, planning_thread=False)
    try:
        logged = LoggedLines(robot.node)
        robot.odometry, robot.now = False, robot.now + 10.0   # odometry stale
        local = robot.costmap(LOCAL)
        assert (local.metadata.size_x, local.metadata.size_y, len(local.data)) == (0, 0, 0)
        assert any(level == 'warning' and text.startswith(f'{LOCAL}: an empty costmap: the robot\'s position is '
                                                          f'not known') for level, text in logged.lines)
        assert robot.costmap().metadata.size_x == 400   # the global one needs no robot
    finally:
        robot.node.destroy_node()


# ------------------------------------------------------------------------------------------------ clear around a pose
SPEC = LaserSpec(range=8.0, fov=2 * math.pi, beams=360, noise=0.01)
NEAR = Segment((7.0, 9.0), (7.0, 11.0))     # not on the map: 2 m ahead of the robot
FAR = Segment((1.5, 8.5), (1.5, 11.5))      # not on the map: 3.5 m behind it


class Scanning(Robot):
    """A Robot whose laser sees ON_MAP, MAP_WALL, NEAR and FAR every tick (the last two only by it)."""

    def __init__(self, context: Any) -> None:
        self.rng = np.random.default_rng(5)
        super().__init__(context, planning_thread=False)
        for _ in range(6):
            self.tick()

    def tick(self) -> None:
        super().tick()
        walls = np.array([(NEAR.start, NEAR.end), (FAR.start, FAR.end), (MAP_WALL.start, MAP_WALL.end)])
        reading = scan(SPEC, (*self.at, 0.0), self.rng, self.now, np.array([ON_MAP.center]),
                       np.array([ON_MAP.radius]), walls[:, 0], walls[:, 1])
        self.node.inputs.on_scan(convert.scan_to_laser_scan(reading, convert.seconds_to_stamp(self.now)))

    def quiet(self) -> None:
        """A control tick without a scan (the clearing is not seen again before the test looks)."""
        self.now += DT
        self.node.inputs.on_odom(convert.state_to_odometry(self.at, convert.seconds_to_stamp(self.now)))
        self.node.on_control()


def pose(x: float, y: float, frame: str) -> Any:
    from geometry_msgs.msg import PoseStamped
    out = PoseStamped()
    out.header.frame_id, out.pose.position.x, out.pose.position.y, out.pose.orientation.w = frame, x, y, 1.0
    return out


def test_clear_around_a_pose_in_odom_forgets_only_there_and_the_costmap_shows_it(context: Any) -> None:
    from builtin_interfaces.msg import Time
    from tf2_msgs.msg import TFMessage

    from msg_tools import frames
    robot = Scanning(context)
    try:
        robot.node.tf.take_static(TFMessage(transforms=[frames.transform_stamped('map', 'odom', (-3.5, 0.0, 0.0),
                                                                                 Time())]))
        before = robot.costmap()
        assert lethal_near(before, 1.5, 10.0) and lethal_near(before, 7.0, 10.0)   # believed
        logged = LoggedLines(robot.node)
        request = srv.ClearCostmapAroundPose.Request(pose=pose(5.0, 10.0, 'odom'), reset_distance=4.0)
        robot.call(AROUND_POSE, request, tick=robot.quiet)   # (5, 10) in odom: (1.5, 10) in map, FAR's middle
        said = [text for level, text in logged.lines if text.startswith(AROUND_POSE)]
        assert len(said) == 1 and 'forgot ' in said[0] and ' 0 walls' not in said[0], logged.lines
        after = robot.call(GLOBAL, srv.GetCostmap.Request(), tick=robot.quiet).map
        assert not lethal_near(after, 1.5, 10.0) and not lethal_near(after, 1.5, 9.0)   # FAR forgotten
        assert lethal_near(after, 7.0, 10.0) and costs_at(after, 12.0, 10.0) == LETHAL   # the rest kept
    finally:
        robot.node.destroy_node()


def test_clear_around_a_pose_in_a_frame_tf_does_not_resolve_clears_nothing_and_says_so(context: Any) -> None:
    robot = Scanning(context)
    try:
        logged = LoggedLines(robot.node)
        request = srv.ClearCostmapAroundPose.Request(pose=pose(1.5, 10.0, 'nowhere'), reset_distance=math.inf)
        robot.call(AROUND_POSE, request, tick=robot.quiet)
        assert any(level == 'warning' and "nothing cleared: the pose cannot be put in the map frame: pose frame "
                   "'nowhere': no transform" in text for level, text in logged.lines), logged.lines
        kept = robot.call(GLOBAL, srv.GetCostmap.Request(), tick=robot.quiet).map
        assert lethal_near(kept, 1.5, 10.0) and lethal_near(kept, 7.0, 10.0)
    finally:
        robot.node.destroy_node()


def test_the_new_services_have_nav2_s_names_in_the_planner_s_namespace(context: Any) -> None:
    from rclpy.parameter import Parameter
    node = PlannerNode(context=context, namespace='/r1', parameter_overrides=[Parameter('workspace', value=list(MAP))])
    try:
        side = services(node).actions.side.node
        names = {name for name, _ in side.get_service_names_and_types_by_node(side.get_name(), '/r1')}
        assert {'/r1/global_costmap/get_costmap', '/r1/local_costmap/get_costmap',
                '/r1/local_costmap/clear_costmap_around_pose', '/r1/local_costmap/clear_around_pose_local_costmap',
                '/r1/global_costmap/clear_around_pose_global_costmap'} <= names
    finally:
        node.destroy_node()


# ------------------------------------------------------------------------------------------------ over DDS
GRAPH_WORLD = """\
name: costmap_world
workspace: [0, 0, 20, 20]
obstacles:
  - circle: {center: [10, 10], radius: 1.5}
robots:
  - {name: r1, model: point_mass, start: [2, 10], goal: [18, 10], radius: 0.5}
"""


def test_the_navigation_client_gets_both_costmaps_and_clears_around_a_pose_over_dds(
        graph: Any, monkeypatch: pytest.MonkeyPatch) -> None:
    """The planner as a process, fastep_ros.navigation_client's get_costmap and clear_costmap_around_pose over
    DDS, as BasicNavigator's getGlobalCostmap, getLocalCostmap and clearCostmapAroundPose call them."""
    from fastep_ros.navigation_client import NavigationClient
    from fastep_testing.graph import write
    graph.start('map', 'map_server', scenario=str(write(graph.tmp / 'world.yaml', GRAPH_WORLD)))
    graph.start('plant', 'plant', '/r1', model='point_mass', start=[2.0, 10.0])
    graph.start('planner', 'planner', '/r1', model='point_mass', robot_radius=0.5)
    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    nav = NavigationClient(namespace='/r1', domain_id=graph.domain, server_timeout=60.0)
    try:
        deadline = time.monotonic() + 60.0
        costmap = nav.get_costmap('global')
        while costmap.metadata.size_x == 0 and time.monotonic() < deadline:   # before the map and a pass
            time.sleep(0.5)
            costmap = nav.get_costmap('global')
        assert (costmap.metadata.size_x, costmap.metadata.size_y, costmap.header.frame_id) == (400, 400, 'map')
        assert costs_at(costmap, 10.0, 10.0) == LETHAL and costs_at(costmap, 11.8, 10.0) == INSCRIBED
        assert costs_at(costmap, 2.0, 10.0) == FREE
        local = nav.get_costmap('local', resolution=0.1)
        meta = local.metadata
        assert (meta.size_x, meta.size_y, meta.resolution) == (30, 30, pytest.approx(0.1))
        assert (meta.origin.position.x, meta.origin.position.y) == (pytest.approx(0.5), pytest.approx(8.5))
        assert nav.clear_costmap_around_pose((2.0, 10.0), 2.0)
        with pytest.raises(ValueError):
            nav.get_costmap('everywhere')
    finally:
        nav.close()
