"""Following an exact path out of a trap: densified vertices and the pursuit target."""

import numpy as np

from fastep_core.geometry import Circle, Segment
from fastep_core.planning import PlannerParams
from fastep_core.planning.recovery.escape import EscapePath, TrapEscape, densify
from fastep_core.planning.shortest_path.optimal import shortest_path
from fastep_core.world import World


def test_densify_keeps_the_vertices_and_splits_long_edges():
    points = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 0.2]])
    out = densify(points, spacing=0.5)
    assert np.allclose(out[0], [0, 0]) and np.allclose(out[4], [2, 0]) and np.allclose(out[-1], [2, 0.2])
    assert len(out) == 6
    assert max(np.hypot(*(b - a)) for a, b in zip(out, out[1:])) <= 0.5 + 1e-12


def wall_world():
    return World.from_obstacles([0, 0, 20, 20], [Segment((10.0, 4.0), (10.0, 16.0))])


def test_target_is_a_carrot_step_radius_ahead_on_a_visible_vertex():
    world = wall_world()
    path = shortest_path(world, (5.0, 10.0), (15.0, 10.0), 0.7)
    escape = EscapePath.from_path(path, world)
    assert escape.rest[-1] == 0.0 and np.isclose(escape.rest[0] + np.hypot(*(escape.vertices[0] - [5, 10])),
                                                   path.polyline_length)
    position = np.array([5.0, 10.0])
    target = escape.target(position, 0.5, 0.2, 2.0, 0.3, 0.7)
    assert target is not None and np.isclose(np.hypot(*(target - position)), 2.0)
    assert world.obstacles.path_clearance(position, target) >= 0.6 - 1e-9   # the run to it is free


def test_no_target_when_nothing_ahead_is_in_sight_unless_the_path_is_fresh():
    world = wall_world()
    path = shortest_path(world, (5.0, 10.0), (15.0, 10.0), 0.7)
    escape = EscapePath.from_path(path, world)
    behind_the_wall = np.array([11.0, 10.0])   # knocked off the path, to the far side of the wall
    escape.index = 1
    assert escape.target(behind_the_wall, 0.5, 0.2, 2.0, 0.3, 0.7) is None
    assert escape.target(behind_the_wall, 0.5, 0.2, 2.0, 0.3, 0.7, fresh=True) is not None


def test_densify_is_bounded_on_a_vast_path():
    """Every 0.5 m of path was a vertex: a far goal, or coordinates near 1e299, ended in MemoryError."""
    from fastep_core.planning.recovery.escape import MAX_VERTICES
    for far in (1e6, 1e299):
        points = np.array([[0.0, 0.0], [3.0, 4.0], [far, far]])
        out = densify(points)
        assert len(out) <= MAX_VERTICES + len(points)
        assert np.array_equal(out[0], points[0]) and np.array_equal(out[-1], points[-1])
        assert any(np.array_equal(p, points[1]) for p in out)      # the path's own vertices stay


def test_a_far_goal_at_a_crawl_ends_with_a_status():
    """A trap escape (no progress at 0.01 m/s) towards a goal 1e299 m away: bounded, a plain failure."""
    import warnings

    from fastep_core.scenario import parse_scenario
    from fastep_core.simulator import simulate
    data = {'name': 'far', 'workspace': [0, 0, 1e299, 1e299],
            'obstacles': [{'circle': {'center': [20, 20], 'radius': 2}}],
            'planner': {'max_speed': 0.01, 'max_sim_time': 12, 'trap_timeout': 5},
            'robots': [{'name': 'r1', 'model': 'point_mass', 'start': [5, 5], 'goal': [9e298, 9e298], 'radius': 0.5}]}
    with warnings.catch_warnings():
        warnings.simplefilter('ignore', RuntimeWarning)       # squared distances overflow at this scale
        robot = simulate(parse_scenario(data)).robots[0]
    assert robot.escapes >= 1 and not robot.reached
    assert robot.status.startswith('failed')


def arc_vertex(escape, end, keep):
    """A vertex in the middle of the path's arc round `end`, and the point under it at `keep` from `end`."""
    on_arc = [k for k, v in enumerate(escape.vertices[:-2]) if abs(np.hypot(*(v - end)) - keep) < 0.02
              and abs(np.hypot(*(escape.vertices[k + 1] - end)) - keep) < 0.02]
    k = on_arc[len(on_arc) // 2]
    v = escape.vertices[k]
    return k, end + (v - end) * (keep / np.hypot(*(v - end)))


def test_the_next_vertex_round_a_wall_end_stays_in_sight_a_quarter_margin_lower():
    """Round a wall's end the path is an arc; a path planned from a robot that cut a chord of it keeps only what the
    robot has, and from under a vertex the run to the next one dips a little below that. It was out of sight: the
    path was planned again every REPLAN_AFTER while the robot went round the arc (11 paths per escape in U-traps)."""
    world = wall_world()
    end = np.array([10.0, 16.0])
    escape = EscapePath.from_path(shortest_path(world, (8.0, 15.0), (12.0, 15.0), 0.602), world)
    k, position = arc_vertex(escape, end, 0.602)
    assert world.obstacles.path_clearance(position, escape.vertices[k + 1]) < 0.6   # below `within`
    escape.index = k
    target = escape.target(position, 0.5, 0.2, 2.0, 0.3, 0.7)
    assert target is not None and escape.index > k
    assert world.obstacles.path_clearance(position, target) >= 0.55 - 1e-9
    # Never below radius + a quarter margin: a run that dips lower is still out of sight.
    escape = EscapePath.from_path(shortest_path(world, (8.0, 15.0), (12.0, 15.0), 0.5505), world)
    k, position = arc_vertex(escape, end, 0.5505)
    escape.index = k
    assert world.obstacles.path_clearance(position, escape.vertices[k + 1]) < 0.5495
    assert escape.target(position, 0.5, 0.2, 2.0, 0.3, 0.7) is None


def test_an_escape_goes_on_in_a_world_known_anew_only_while_the_rest_of_its_path_keeps_clear_there():
    """A robot that senses an obstacle while escaping: a path the new obstacle comes near is planned again (it was
    followed through the obstacle until the guard stopped it and no vertex was in sight); one it leaves clear is
    followed on, measured against the new world (a misplaced wall corrected by a few centimetres replanned it from
    where the robot stood, keeping only what it had there: ever closer to walls)."""
    world = wall_world()
    start, goal = np.array([5.0, 10.0]), np.array([15.0, 10.0])
    escape = TrapEscape()
    escape.start(shortest_path(world, start, goal, 0.7), world, 0.0, 1.0, world)
    assert escape.known is world
    on_path = escape.path.vertices[len(escape.path.vertices) // 2]
    sensed = World(world.workspace, world.obstacle_list + (Circle((float(on_path[0]), float(on_path[1])), 0.5),))
    assert not escape.adopt(sensed, sensed, 0.55) and escape.known is world and escape.path.world is world
    far = World(world.workspace, world.obstacle_list + (Circle((2.0, 2.0), 0.5),))
    index = escape.path.index = 3
    assert escape.adopt(far, far, 0.55) and escape.known is far and escape.path.world is far
    assert escape.path.index == index and escape.path.keep == 0.7
    # Planned again (the navigator asks for it when adopt fails): the new path and the world known are recorded.
    target, _ = escape.next_target(start, 1.0, lambda: (shortest_path(sensed, start, goal, 0.7), sensed), 0.5,
                                   PlannerParams(), replan=True, known=sensed)
    assert target is not None and escape.known is sensed and escape.path.world is sensed
    assert sensed.obstacles.path_clearance(np.array(escape.path.vertices[:-1]), np.array(escape.path.vertices[1:])) \
        .min() >= 0.7 - 1e-6                                       # round the sensed circle too


def test_a_world_known_anew_is_checked_against_the_next_stretch_of_the_path_only():
    """ADOPT_REACH metres of path ahead are checked (a path across a big map has thousands of vertices); an obstacle
    sensed farther on is met later as one out of sight."""
    from fastep_core.planning.recovery.escape import ADOPT_REACH
    world = World.from_obstacles([0, 0, 100, 100], [])
    start, goal = np.array([5.0, 50.0]), np.array([95.0, 50.0])
    for x, adopted in ((5.0 + ADOPT_REACH - 2.0, False), (5.0 + ADOPT_REACH + 5.0, True)):
        escape = TrapEscape()
        escape.start(shortest_path(world, start, goal, 0.7), world, 0.0, 1.0, world)
        sensed = World(world.workspace, (Circle((x, 50.0), 0.5),))
        assert escape.adopt(sensed, sensed, 0.55) is adopted
