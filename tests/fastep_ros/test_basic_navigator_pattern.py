"""A ROS user's script in nav2_simple_commander's BasicNavigator call pattern, against a fastep robot over DDS
(issue "Nav2's own client", item 5): wait until active, getPath, goToPose with feedback to the end, cancel,
followWaypoints, goThroughPoses, a goal inside an obstacle, an unreachable goal, spin, backup, clearAllCostmaps.
The calls and checks are Nav2's documented API, through fastep_ros.navigation_client (its verbs in snake_case);
every wait has a bound, so a call that would block for ever fails the test instead."""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np
import pytest

from fastep_testing.basic_navigator_world import PARAMS, WORLD
from fastep_testing.graph import Graph, write

pytest.importorskip('nav2_msgs.action', reason='nav2_msgs is built by make (interfaces/build.sh)')

NS = '/r1'
TASK = 90.0   # s: the longest any task here may take (a drive of ~12 m at 1.5 m/s takes ~10)


def run(nav: Any, bound: float = TASK) -> list[Any]:
    """isTaskComplete until done (at most `bound` s), the feedback seen on the way and at the end (the server's
    last feedback, sent just before the result, is usually taken in the same spin as the result)."""
    seen: list[Any] = []
    end = time.monotonic() + bound
    while True:
        done = nav.is_task_complete()
        if nav.get_feedback() is not None and (not seen or nav.get_feedback() is not seen[-1]):
            seen.append(nav.get_feedback())
        if done:
            return seen
        assert time.monotonic() < end, 'the task did not end'


def path_length(path: Any) -> float:
    xy = np.array([(p.pose.position.x, p.pose.position.y) for p in path.poses])
    return float(np.hypot(*np.diff(xy, axis=0).T).sum())


def test_a_basic_navigator_script_runs_to_the_end_against_a_fastep_robot(graph: Graph,
                                                                          monkeypatch: pytest.MonkeyPatch) -> None:
    from fastep_ros.navigation_client import NavigationClient
    graph.start('map', 'map_server', scenario=str(write(graph.tmp / 'world.yaml', WORLD)))
    graph.start('plant', 'plant', NS, model='diff_drive', start=[3.0, 10.0, 0.0], max_speed=PARAMS['max_speed'])
    graph.start('planner', 'planner', NS, model='diff_drive', **PARAMS)
    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    nav = NavigationClient(namespace=NS, domain_id=graph.domain, server_timeout=60.0)
    try:
        nav.wait_until_active('planner')   # waitUntilNav2Active(navigator='planner', localizer=...)

        # getPath: the route round the disc, from the robot, as nav_msgs/Path in map.
        path = None
        end = time.monotonic() + 60.0
        while path is None:   # the planner may not know the world yet: the first request may end 207
            assert time.monotonic() < end, nav.result_message()
            path = nav.get_path((14.0, 10.0))
        assert path.header.frame_id == 'map' and len(path.poses) > 50
        first, last = path.poses[0].pose.position, path.poses[-1].pose.position
        assert math.dist((first.x, first.y), (3.0, 10.0)) < 0.3 and math.dist((last.x, last.y), (14.0, 10.0)) < 1e-6
        route = path_length(path)
        assert 11.0 < route < 12.5   # round the disc: longer than the straight 11 m

        # goToPose with a heading, feedback to the end: the distance left falls along the route from its length.
        assert nav.go_to_pose(14.0, 10.0, math.pi / 2)
        seen = run(nav)
        assert nav.get_result() == 'succeeded', nav.result_message()
        told = [f.distance_remaining for f in seen]
        assert len(told) > 10 and abs(told[0] - route) < max(0.05 * route, 0.3), (told[0], route)
        assert all(b <= a + 0.1 for a, b in zip(told, told[1:])) and told[-1] < 0.5
        final = seen[-1].current_pose.pose
        assert math.dist((final.position.x, final.position.y), (14.0, 10.0)) < 0.5
        assert abs(2.0 * math.atan2(final.orientation.z, final.orientation.w) - math.pi / 2) < 0.35

        # cancelTask: CANCELED.
        assert nav.go_to_pose(3.0, 14.0)
        for _ in range(5):
            nav.is_task_complete()   # under way a moment
        assert nav.cancel_task()
        run(nav, 30.0)
        assert nav.get_result() == 'canceled'

        # followWaypoints and goThroughPoses.
        assert nav.follow_waypoints([(12.0, 14.0), (6.0, 14.0)])
        run(nav)
        assert nav.get_result() == 'succeeded', nav.result_message()
        assert nav.result.missed_waypoints == []
        assert nav.go_through_poses([(5.0, 16.0), (12.0, 16.0)])
        run(nav)
        assert nav.get_result() == 'succeeded', nav.result_message()

        # A goal inside an obstacle: ABORTED at once, GOAL_OCCUPIED; a walled-in one: ABORTED, NO_VALID_PATH.
        assert nav.go_to_pose(9.0, 10.0)
        run(nav, 20.0)
        assert (nav.get_result(), nav.result.error_code) == ('aborted', 206), nav.result_message()
        began = time.monotonic()
        assert nav.go_to_pose(17.0, 4.0)
        run(nav, 20.0)
        assert (nav.get_result(), nav.result.error_code) == ('aborted', 208), nav.result_message()
        assert time.monotonic() - began < 20.0

        # The behaviours: spin and backup end SUCCEEDED; clearAllCostmaps answers.
        assert nav.spin(1.57, time_allowance=20.0)
        turned = run(nav, 30.0)
        assert nav.get_result() == 'succeeded', nav.result_message()
        assert abs(turned[-1].angular_distance_traveled - 1.57) < 0.1
        assert nav.backup(0.3, 0.2, time_allowance=20.0)
        run(nav, 30.0)
        assert nav.get_result() == 'succeeded', nav.result_message()
        assert nav.clear_all_costmaps()
    finally:
        nav.close()
