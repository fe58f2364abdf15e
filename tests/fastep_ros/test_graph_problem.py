"""Format-v2 worlds on the live graph: what the map node gives the robots (the map's knowledge, movers on /movers),
what a plant's scanner sees (the truth), and what the graph still refuses (one line, exit 2)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from rclpy.parameter import Parameter
from visualization_msgs.msg import MarkerArray

from fastep_core.dynamic_world import DynamicWorld, map_generator
from fastep_core.perception.belief import sensor_generator
from fastep_core.scenario import load_scenario, parse_scenario
from fastep_ros.limits import graph_problem
from msg_tools import convert

ROBOT = {'name': 'r1', 'model': 'point_mass', 'start': [5, 25], 'goal': [45, 25], 'radius': 0.5}
V2 = {'workspace': [0, 0, 50, 50],
      'obstacles': [{'circle': {'center': [25, 10], 'radius': 1}},
                    {'circle': {'center': [25, 40], 'radius': 1}, 'motion': {'waypoints': [[25, 45]], 'speed': 0.5}},
                    {'circle': {'center': [35, 20], 'radius': 1}, 'motion': {'waypoints': [[35, 30]], 'speed': 0.5},
                     'known': False},
                    {'circle': {'center': [12, 30], 'radius': 1.5}, 'known': False},
                    {'circle': {'center': [15, 18], 'radius': 1.5}, 'position_sigma': 0.5}],
      'robots': [{**ROBOT, 'sensor': {'range': 8.0, 'fov': 6.2832, 'beams': 90, 'noise': 0.01}}]}


def test_v2_worlds_run_on_the_graph_other_models_than_the_graph_s_do_not() -> None:
    assert graph_problem(parse_scenario(V2)) == '' and graph_problem(parse_scenario(V2), robots=False) == ''
    assert graph_problem(load_scenario('crossing_movers')) == ''
    robot = {**ROBOT, 'model': 'diff_drive', 'start': [5, 25, 0.0]}
    assert graph_problem(parse_scenario({**V2, 'robots': [robot]})) == ''


def test_the_map_node_publishes_what_the_map_knows_and_the_known_movers(context: Any, tmp_path: Path) -> None:
    from fastep_ros.map_server import MapNode
    path = tmp_path / 'v2.yaml'
    path.write_text(yaml.safe_dump(V2))
    scenario = parse_scenario(V2)
    node = MapNode(context=context, parameter_overrides=[Parameter('scenario', value=str(path)),
                                                         Parameter('seed', value=3),
                                                         Parameter('use_sim_time', value=True)])   # t = 0
    try:
        known = DynamicWorld(scenario.world.workspace, scenario.obstacle_specs).planner_map(map_generator(3))
        published = convert.marker_array_to_obstacles(node.obstacles_msg)
        # The still ones the map knows, the misplaced one where fastep-sim's map puts it for seed 3; no unknown.
        assert published == list(known.world.obstacle_list) and len(published) == 2
        assert math.dist(published[1].center, (15, 18)) > 0.01   # type: ignore[union-attr]  # a Circle
        sent: list[MarkerArray] = []
        assert node.movers_pub is not None
        node.movers_pub.publish = sent.append  # type: ignore[method-assign]  # keep what it publishes
        node.publish_movers()
        movers = convert.marker_array_to_movers(sent[-1])
        assert [m.name for m in movers] == ['mover 1'] and all(m.mover for m in movers)   # the known one only
        assert movers[0].position == pytest.approx(known.others(0.0)[0].position)
        assert movers[0].velocity == pytest.approx((0.0, 0.5))
    finally:
        node.destroy_node()


def test_a_plant_with_a_sensor_scans_the_truth_as_fastep_sim_does(context: Any, tmp_path: Path) -> None:
    from fastep_ros.plant import PlantNode
    path = tmp_path / 'v2.yaml'
    path.write_text(yaml.safe_dump(V2))
    scenario = parse_scenario(V2)
    node = PlantNode(context=context, parameter_overrides=[
        Parameter('start', value=[5.0, 25.0]), Parameter('use_sim_time', value=True),
        Parameter('sensor', value=[8.0, 6.2832, 90.0, 0.01]), Parameter('scenario', value=str(path)),
        Parameter('seed', value=2), Parameter('robot_index', value=0)])
    try:
        sent: list[Any] = []
        assert node.scan_pub is not None
        node.scan_pub.publish = sent.append  # type: ignore[method-assign]  # keep what it publishes
        assert node.advance(0.02) and node.advance(0.04)
        node.publish()
        assert len(sent) == 1 and sent[0].header.frame_id == 'base_link'   # the root namespace's
        truth = DynamicWorld(scenario.world.workspace, scenario.obstacle_specs)
        spec = scenario.robots[0].sensor
        assert spec is not None
        expected = truth.scan(spec, (5.0, 25.0, 0.0), 0.04, sensor_generator(2, 0))
        got = convert.laser_scan_to_scan(sent[0])
        assert np.allclose(got.ranges, expected.ranges, atol=1e-5, equal_nan=True)   # float32 on the wire
        assert np.isfinite(got.ranges).sum() == np.isfinite(expected.ranges).sum()
        # The unknown circle at (12, 30) is in it: the scanner sees the truth, not the map.
        seen = np.isfinite(got.ranges)   # no return: inf (inf times a cosine of 0 would be nan)
        angles, ranges = got.angles()[seen], got.ranges[seen]
        hits = np.column_stack([5.0 + ranges * np.cos(angles), 25.0 + ranges * np.sin(angles)])
        assert (np.abs(np.hypot(*(hits - (12.0, 30.0)).T) - 1.5) < 0.05).any()
    finally:
        node.destroy_node()


def test_a_plant_refuses_a_sensor_without_a_world_in_one_line(context: Any) -> None:
    from fastep_ros.common import StartupError
    from fastep_ros.plant import PlantNode
    with pytest.raises(StartupError, match='parameter scenario is required with a sensor'):
        PlantNode(context=context, parameter_overrides=[Parameter('sensor', value=[8.0, 6.28, 90.0, 0.01])])
    with pytest.raises(StartupError, match=r'parameter sensor must be \[range, fov, beams, noise\]'):
        PlantNode(context=context, parameter_overrides=[Parameter('sensor', value=[8.0, 6.28])])


def test_a_planner_avoids_the_known_movers_of_movers_predicted_to_now(context: Any) -> None:
    from fastep_core.planning.others import OtherRobot
    from fastep_ros.planner import PlannerNode
    node = PlannerNode(context=context, parameter_overrides=[Parameter('workspace', value=[0.0, 0.0, 50.0, 50.0])])
    try:
        mover = OtherRobot('mover 1', (25.0, 40.0), (0.0, -0.5), 1.0, mover=True)
        now = node.now()   # one time for the whole test: a loaded machine let 0.07 s pass between two calls
        node.inputs.on_movers(convert.movers_to_marker_array([mover], convert.seconds_to_stamp(now - 0.1)))
        seen = node.inputs.other_robots(now)
        assert len(seen) == 1 and seen[0].mover and seen[0].name == 'mover 1'
        assert seen[0].position[1] == pytest.approx(40.0 - 0.05, abs=0.02)   # predicted 0.1 s on
        # The map node went quiet: kept where last seen, its reach widened by 0.5 m/s (issue "Faults", item 2).
        [stale] = node.inputs.other_robots(now + 10.0)
        assert stale.position == (25.0, 40.0) and stale.velocity == (0.0, 0.0)
        assert stale.radius == pytest.approx(1.0 + 0.5 * 10.1, abs=0.02)
    finally:
        node.destroy_node()


