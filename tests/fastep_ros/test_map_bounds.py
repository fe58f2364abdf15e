"""Big or noisy worlds: a /map or /obstacles beyond the planner's bounds is coarsened (a map's cells merged) or
refused (the world before kept), status saying so; a big map is built off the control path while the control
tick drives on the world before, a newer map wins over one still being built, and "world updated" is a line a
WORLD_LOG_PERIOD at most. The node built in this process, its callbacks called directly."""

from __future__ import annotations

import array
from typing import Any, Callable

import numpy as np
import pytest
from diagnostic_msgs.msg import DiagnosticStatus
from nav_msgs.msg import OccupancyGrid
from rclpy.serialization import deserialize_message

from fastep_core.geometry import Circle, Segment
from fastep_core.world import World
from fastep_ros.limits import INLINE_WORLD_ITEMS, WORLD_OBSTACLES_MAX
from fastep_ros.planner import PlannerNode
from fastep_testing.in_process import TickClock, planner_node
from fastep_testing.planning_gate import WAIT, Gate, wait_for
from msg_tools import convert

ROOM = World.from_obstacles([0, 0, 10, 6], [Segment((5.0, 0.0), (5.0, 2.0)), Circle((8.0, 4.0), 0.5)])


def make(context: Any, **params: Any) -> PlannerNode:
    overrides = {'obstacle_source': 'map', 'robot_radius': 0.3, **params}
    return planner_node(context, **overrides)


def noisy_map(cells: int, seed: int = 0, room: World = ROOM, resolution: float = 0.1) -> OccupancyGrid:
    """The room's map in the corner of a cells x cells grid whose other cells are occupied at random (half)."""
    grid = convert.world_to_occupancy_grid(room, resolution)
    h, w = grid.info.height, grid.info.width
    data = np.where(np.random.default_rng(seed).random((cells, cells)) < 0.5, 100, 0).astype(np.int8)
    data[:h, :w] = np.asarray(grid.data, dtype=np.int8).reshape(h, w)
    data[:h + 2, w:w + 2] = data[h:h + 2, :w + 2] = 0   # a free strip round the room: its walls are its own
    grid.info.width = grid.info.height = cells
    grid.data = data.ravel()
    return grid


def published_status(node: PlannerNode) -> dict[str, Any]:
    """The status message the node sends now, as a dict (convert.diagnostic_to_dict)."""
    sent: list[bytes] = []
    publish = node.reports.status_pub.publish
    node.reports.status_pub.publish = sent.append   # keep what is sent
    try:
        node.reports.publish(force=True)
    finally:
        node.reports.status_pub.publish = publish   # as it was
    return convert.diagnostic_to_dict(deserialize_message(sent[-1], DiagnosticStatus))


@pytest.fixture
def held_builds(monkeypatch: pytest.MonkeyPatch) -> Gate:
    """Every build on the world builder thread waits at this gate first (the executor's own builds do not)."""
    import fastep_ros.world_builder as world_builder
    gate, build = Gate(), world_builder.build

    def held(job: Any) -> Any:
        gate.wait()
        return build(job)
    monkeypatch.setattr(world_builder, 'build', held)
    return gate


def building(node: PlannerNode) -> bool:
    """Is a world still being built off the control path (or its result not taken yet)?"""
    return node.inputs.builder is not None and node.inputs.builder.busy


def taken(node: PlannerNode, done: Callable[[], bool], what: str) -> None:
    """The executor's looks for a world built off the control path (its world timer), until `done`."""
    def look() -> bool:
        node.inputs.on_world_timer()
        return done()
    wait_for(look, what)


# ------------------------------------------------------------------------------------------------ bounds
def test_a_map_outlining_more_walls_than_a_world_may_have_is_coarsened_never_less_obstacle(context: Any) -> None:
    node = make(context, planning_thread=False)
    try:
        grid = noisy_map(400)   # ~80,000 walls as given
        node.inputs.on_map(grid)
        world = node.inputs.world
        assert world is not None and world.workspace == (0.0, 0.0, 40.0, 40.0)
        assert 0 < len(world.obstacle_list) <= WORLD_OBSTACLES_MAX
        status = published_status(node)
        assert status['obstacles'] == str(len(world.obstacle_list))
        problem = status['world_problem']
        assert problem.startswith('/map coarsened: 400 x 400 cells of 0.1 m outline') and \
            f'more than {WORLD_OBSTACLES_MAX:,}' in problem and 'merged into' in problem, problem
        # Every occupied cell of the map lies in an occupied merged cell, behind the walls: a goal there is refused.
        data = np.asarray(grid.data, dtype=np.int16).reshape(400, 400)
        rows, cols = np.nonzero(data >= 65)
        lookup = node.inputs.occupied
        assert lookup is not None and all(lookup(((c + 0.5) * 0.1, (r + 0.5) * 0.1)) for r, c in zip(rows, cols))
        node.inputs.on_odom(convert.state_to_odometry([1.0, 3.0]))
        far = next((r, c) for r, c in zip(rows, cols) if min(r, c) > 100)   # an occupied cell in the clutter
        node.on_goal(convert.point_to_pose_stamped(((far[1] + 0.5) * 0.1, (far[0] + 0.5) * 0.1)))
        assert node.reports.status()[1] == 'failed'
        node.on_goal(convert.point_to_pose_stamped((3.0, 4.0)))   # in the room, which stays free
        assert node.goal == (3.0, 4.0), node.reports.status()
    finally:
        node.destroy_node()


def test_a_map_of_more_cells_than_a_map_may_have_is_refused_and_the_world_before_kept(context: Any) -> None:
    node = make(context, planning_thread=False)
    try:
        big = OccupancyGrid()
        big.info.resolution, big.info.width, big.info.height = 0.05, 2001, 2000
        big.info.origin.orientation.w = 1.0
        big.data = array.array('b', bytes(2001 * 2000))
        node.inputs.on_map(big)   # before any world: waiting, saying why
        level, message, reason = node.reports.status()
        assert message == 'waiting' and '/map refused: 2001 x 2000 = 4,002,000 cells, more than the 4,000,000' \
            in reason and 'no world yet' in reason, reason
        node.inputs.on_map(convert.world_to_occupancy_grid(ROOM, 0.1))
        room = node.inputs.world
        assert room is not None and node.inputs.world_problem == ''
        node.inputs.on_map(big)
        assert node.inputs.world is room and node.inputs.map_workspace == (0.0, 0.0, 10.0, 6.0)
        problem = published_status(node)['world_problem']
        assert problem.startswith('/map refused: 2001 x 2000') and problem.endswith('the world before kept'), problem
    finally:
        node.destroy_node()


def test_obstacles_beyond_the_bound_are_refused_and_the_world_before_kept(context: Any) -> None:
    node = make(context, obstacle_source='markers', workspace=[0.0, 0.0, 100.0, 100.0], planning_thread=False)
    try:
        node.inputs.on_obstacles(convert.obstacles_to_marker_array([Circle((50.0, 50.0), 1.0)]))
        before = node.inputs.world
        assert before is not None
        xs = np.linspace(1.0, 99.0, WORLD_OBSTACLES_MAX + 1)
        node.inputs.on_obstacles(convert.obstacles_to_marker_array([Circle((x, 10.0), 0.001) for x in xs]))
        assert node.inputs.world is before and node.inputs.obstacles is not None and len(node.inputs.obstacles) == 1
        problem = published_status(node)['world_problem']
        assert problem == (f'/obstacles refused: {WORLD_OBSTACLES_MAX + 1:,} obstacles, more than the '
                           f'{WORLD_OBSTACLES_MAX:,} a world may have; the world before kept'), problem
    finally:
        node.destroy_node()


# ------------------------------------------------------------------------------------------------ off the control path
def test_the_control_tick_drives_on_the_world_before_while_a_big_map_is_built(context: Any,
                                                                              held_builds: Gate) -> None:
    node = make(context)
    clock = TickClock(node, (1.0, 3.0))
    commands: list[np.ndarray] = []
    publish = node.publish_command

    def counted(command: np.ndarray, at: float | None = None) -> None:
        commands.append(command)
        publish(command, at)
    node.publish_command = counted   # type: ignore[method-assign]  # count what the control tick sends
    try:
        node.inputs.on_map(convert.world_to_occupancy_grid(ROOM, 0.5))   # small: built at once
        room = node.inputs.world
        assert room is not None and not held_builds.entered.is_set()
        node.on_goal(convert.point_to_pose_stamped((4.0, 3.0)))

        def moving() -> bool:   # ticks until the planning thread's first plan reaches the control tick
            clock.tick()
            return bool(np.hypot(*node.last_command) > 0.0)
        wait_for(moving, 'a command towards the goal')
        big = noisy_map(300)   # 90,000 cells: the executor copies them, the builder makes the walls
        assert big.info.width * big.info.height > INLINE_WORLD_ITEMS
        node.inputs.on_map(big)
        assert held_builds.entered.wait(WAIT)   # the build is under way, on the builder's thread
        commands.clear()
        for _ in range(20):
            clock.tick()
        assert node.inputs.world is room and len(commands) == 20 and all(np.hypot(*c) > 0.0 for c in commands)
        assert node.reports.status()[1] == 'kinematic', node.reports.status()
        held_builds.open.set()
        taken(node, lambda: node.inputs.world is not room, 'the big map adopted')
        assert node.inputs.world is not None and node.inputs.world.workspace == (0.0, 0.0, 30.0, 30.0)
        assert 'coarsened' in node.inputs.world_problem
    finally:
        held_builds.open.set()
        node.destroy_node()


def test_a_newer_map_supersedes_one_still_being_built_never_the_reverse(context: Any, held_builds: Gate) -> None:
    node = make(context)
    adopted: list[tuple[float, ...]] = []
    adopt = node.adopt_world

    def recorded(world: World, count: int) -> None:
        adopted.append(world.workspace)
        adopt(world, count)
    node.adopt_world = recorded   # type: ignore[method-assign]  # keep what was adopted
    try:
        node.inputs.on_map(noisy_map(200, seed=1))
        assert held_builds.entered.wait(WAIT)   # the first map's build held under way
        node.inputs.on_map(noisy_map(250, seed=2))   # waits for the builder
        held_builds.open.set()
        taken(node, lambda: node.inputs.world is not None and not building(node), 'both built')
        assert adopted == [(0.0, 0.0, 25.0, 25.0)]   # the first map, built when the second had come: dropped
        # A big map held under way, then a small one built at once: the big one, done later, is dropped.
        held_builds.open.clear()
        held_builds.entered.clear()
        node.inputs.on_map(noisy_map(220, seed=3))
        assert held_builds.entered.wait(WAIT)
        node.inputs.on_map(convert.world_to_occupancy_grid(ROOM, 0.5))
        room = node.inputs.world
        assert room is not None and room.workspace == (0.0, 0.0, 10.0, 6.0)
        held_builds.open.set()
        taken(node, lambda: not building(node), 'the big map built')
        assert node.inputs.world is room and published_status(node)['obstacles'] == str(len(room.obstacle_list))
        assert adopted[1:] == [(0.0, 0.0, 10.0, 6.0)]
    finally:
        held_builds.open.set()
        node.destroy_node()


# ------------------------------------------------------------------------------------------------ the log
def test_world_updated_is_a_line_a_period_at_most_saying_the_latest_count(context: Any) -> None:
    node = make(context, planning_thread=False)
    lines: list[str] = []

    class Logger:
        def __getattr__(self, severity: str) -> Callable[..., None]:
            return lambda text, **kwargs: lines.append(text)
    node.get_logger = Logger  # type: ignore[method-assign]  # keep what is said
    now = [0.0]   # the line's wall clock, the test's: the maps come within a period however busy the machine
    node.inputs.world_info.clock = lambda: now[0]
    try:
        for k in range(1, 6):   # a map republished as SLAM does, each with one pillar more
            pillars = [Circle((1.0 + 1.5 * i, 1.0), 0.3) for i in range(k)]
            node.inputs.on_map(convert.world_to_occupancy_grid(World.from_obstacles([0, 0, 10, 6], pillars), 0.5))
        said = [line for line in lines if line.startswith('world')]
        assert len(said) == 2 and said[0].startswith('world known') and said[1].startswith('world updated'), said
        now[0] += 10.0   # a period later
        node.inputs.on_map(convert.world_to_occupancy_grid(ROOM, 0.5))
        count = len(node.inputs.obstacles or ())
        assert lines[-1] == f'world updated: {count} obstacles (3 more such lines left out before it)', lines[-3:]
    finally:
        node.destroy_node()
