"""A planner whose obstacles are the occupied cells of /map (obstacle_source:=map), as a Nav2 user with a
map_server and no scenario file would run it: the node built in this process, its callbacks called directly,
the robot driven on the planner's own simulated clock."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from rclpy.parameter import Parameter
from rclpy.time import Time

from fastep_core.geometry import Circle, Segment
from fastep_core.world import World
from fastep_ros.common import StartupError
from fastep_ros.planner import PlannerNode
from msg_tools import convert

# A 12 x 10 m room split by a wall at x = 6 with a 1.6 m doorway (y 4.2-5.8), and a pillar.
ROOM = World.from_obstacles([0, 0, 12, 10], [Segment((6.0, 0.0), (6.0, 4.2)), Segment((6.0, 5.8), (6.0, 10.0)),
                                             Circle((9.0, 7.0), 0.8)])


# Every control tick plans, so a handler's effect is seen at once (the planning thread: test_planning_thread.py).
SYNCHRONOUS = {'planning_thread': False}


def make(context: Any, **params: Any) -> PlannerNode:
    overrides = [Parameter(k, value=v) for k, v in {**SYNCHRONOUS, **params}.items()]
    return PlannerNode(context=context, parameter_overrides=overrides)


def test_a_robot_drives_through_the_doorway_of_a_map_it_was_given_as_an_occupancy_grid(context: Any) -> None:
    node = make(context, obstacle_source='map', use_sim_time=True, robot_radius=0.3, algorithm='fastep_route')
    clock: Any = node.get_clock()   # a ROSClock on simulated time: set_ros_time_override drives it
    try:
        assert node.describe_parameter('obstacle_source').additional_constraints == 'markers | map'
        grid = convert.world_to_occupancy_grid(ROOM, 0.1, thickness=0.2)
        node.inputs.on_map(grid)
        assert node.inputs.world is not None and node.inputs.world.workspace == (0.0, 0.0, 12.0, 10.0)
        assert node.inputs.obstacles and all(isinstance(o, Segment) for o in node.inputs.obstacles)
        state, goal, dt = np.array([2.0, 9.0]), (10.0, 8.5), 0.05   # the straight line meets the wall
        node.on_goal(convert.point_to_pose_stamped(goal))
        closest, crossed = np.inf, []
        for k in range(1, 2400):
            clock.set_ros_time_override(Time(nanoseconds=int(round(k * dt * 1e9)), clock_type=clock.clock_type))
            node.inputs.on_odom(convert.state_to_odometry(state, convert.seconds_to_stamp(k * dt)))
            node.on_control()
            if node.reports.status()[1] == 'arrived':
                break
            before, state = state, state + node.last_command * dt
            if before[0] < 6.0 <= state[0]:
                crossed.append(float(state[1]))
            closest = min(closest, float(ROOM.obstacles.clearance(state)))   # against the true room
        assert node.reports.status()[1] == 'arrived', node.reports.status()
        assert np.hypot(*(state - goal)) <= 0.1
        assert closest >= 0.3   # never within its radius of the true walls ...
        assert len(crossed) == 1 and 4.2 + 0.3 <= crossed[0] <= 5.8 - 0.3   # ... it went through the doorway
    finally:
        node.destroy_node()


def test_a_goal_inside_an_occupied_region_far_from_its_outline_is_refused(context: Any) -> None:
    node = make(context, obstacle_source='map', robot_radius=0.3)
    try:
        node.inputs.on_map(convert.world_to_occupancy_grid(ROOM, 0.1))
        node.inputs.on_odom(convert.state_to_odometry([2.0, 2.0]))
        node.on_goal(convert.point_to_pose_stamped((9.0, 7.0)))   # the pillar's centre: 0.8 m from its outline
        level, message, reason = node.reports.status()
        assert message == 'failed' and 'occupied: an occupied cell of /map' in reason, reason
        node.on_goal(convert.point_to_pose_stamped((9.0, 8.5)))   # beside it: taken
        assert node.goal == (9.0, 8.5)
    finally:
        node.destroy_node()


def test_with_markers_the_map_gives_only_the_workspace_and_a_bad_source_is_refused(context: Any) -> None:
    node = make(context)
    try:
        node.inputs.on_map(convert.world_to_occupancy_grid(ROOM, 0.1))
        assert node.inputs.obstacles is None and node.inputs.world is None   # still waiting for /obstacles
        node.inputs.on_obstacles(convert.obstacles_to_marker_array(ROOM.obstacle_list))
        assert node.inputs.world is not None and len(node.inputs.world.obstacle_list) == 3
    finally:
        node.destroy_node()
    with pytest.raises(StartupError, match="parameter obstacle_source must be markers or map, got 'grid'"):
        make(context, obstacle_source='grid')
    with pytest.raises(StartupError, match=r'parameter occupied_threshold must be in \[1, 100\], got 0'):
        make(context, obstacle_source='map', occupied_threshold=0)
