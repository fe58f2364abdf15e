"""The ROS interface module: names and patterns, message types, QoS and the recording metadata layout.

Whether the nodes publish with exactly these names, types and QoS is tested with the nodes themselves
(tests/fastep_ros/test_nodes_inprocess.py).
"""

from __future__ import annotations

import pytest
from rclpy.qos import DurabilityPolicy, LivelinessPolicy, ReliabilityPolicy

from fastep_core.scenario import load_scenario
from msg_tools import interface
from msg_tools.ros2_profile import message_class, qos_dict

# The ROS 2 interface (docs/guide.md, "The ROS 2 graph"): the contract,
# written out again on purpose so a change to the module shows here.
DESIGN = {
    'odom': 'nav_msgs/msg/Odometry', 'cmd_vel': 'geometry_msgs/msg/Twist', 'goal_pose': 'geometry_msgs/msg/PoseStamped',
    'waypoint': 'geometry_msgs/msg/PoseStamped', 'plan': 'nav_msgs/msg/Path', 'cost': 'std_msgs/msg/Float64',
    'status': 'diagnostic_msgs/msg/DiagnosticStatus', 'trailer_pose': 'geometry_msgs/msg/PoseStamped',
    '/obstacles': 'visualization_msgs/msg/MarkerArray', '/map': 'nav_msgs/msg/OccupancyGrid',
    '/clock': 'rosgraph_msgs/msg/Clock', 'footprint': 'geometry_msgs/msg/PolygonStamped',
}


def test_topics_and_types_are_design_md_s_table() -> None:
    assert set(interface.ROBOT_TOPICS) | set(interface.SHARED_TOPICS) == set(DESIGN)
    assert interface.TYPES == DESIGN
    for type_name in (*DESIGN.values(), interface.STAMPED_CMD_VEL_TYPE):
        message_class(type_name)   # every type is installed
    assert interface.message_type('/r2/status') == DESIGN['status']
    assert interface.message_type('/map') == DESIGN['/map']


@pytest.mark.parametrize('topic, parts', [
    ('/r1/odom', ('r1', 'odom')),
    ('/robot_2/trailer_pose', ('robot_2', 'trailer_pose')),
    ('/_x/status', ('_x', 'status')),
    ('/r1/odometry', None),        # not an interface topic
    ('/fleet/r1/odom', None),      # robots live in a namespace of one level
    ('/1r/odom', None),            # not a ROS name token
    ('r1/odom', None),             # relative
    ('/odom', None),
    ('/map', None),
])
def test_split_robot_topic(topic: str, parts: tuple[str, str] | None) -> None:
    assert interface.split_robot_topic(topic) == parts
    if parts is not None:
        assert interface.robot_topic(*parts) == topic


def test_interface_topics_are_the_shared_and_per_robot_ones() -> None:
    for topic in ('/obstacles', '/map', '/clock', '/r1/cmd_vel', '/r1/goal_pose'):
        assert interface.is_interface_topic(topic), topic
    for topic in ('/rosout', '/parameter_events', '/r1/r2/odom', 'map', '/r1/scan'):
        assert not interface.is_interface_topic(topic), topic
    with pytest.raises(KeyError):
        interface.offered_qos('/r1/scan')


def test_qos_per_topic() -> None:
    latched = {'/map', '/obstacles', 'status', 'footprint'}
    for topic in DESIGN:
        profile = interface.offered_qos(topic)
        assert profile.reliability == ReliabilityPolicy.RELIABLE, topic
        assert profile.liveliness == LivelinessPolicy.AUTOMATIC, topic
        assert (profile.durability == DurabilityPolicy.TRANSIENT_LOCAL) == (topic in latched), topic
    assert interface.offered_qos('/r1/status') is interface.STATUS_QOS
    assert (interface.LATCHED.depth, interface.STATUS_QOS.depth, interface.RELIABLE.depth) == (1, 10, 10)
    assert interface.LATEST.depth == 1 and interface.LATEST.durability == DurabilityPolicy.VOLATILE


def test_recorded_qos_is_derived_from_the_profiles() -> None:
    # rosbag2's YAML form of the same profiles (what recordings made before this module held).
    assert interface.offered_qos_profiles('/map') == [qos_dict(depth=1, transient_local=True)]
    assert interface.offered_qos_profiles('/obstacles') == [qos_dict(depth=1, transient_local=True)]
    assert interface.offered_qos_profiles('/r1/status') == [qos_dict(depth=10, transient_local=True)]
    assert interface.offered_qos_profiles('/r1/footprint') == [qos_dict(depth=1, transient_local=True)]
    for topic in ('/clock', '/r1/odom', '/r1/cmd_vel', '/r1/goal_pose', '/r1/plan', '/r1/cost', '/r1/waypoint',
                  '/r1/trailer_pose'):
        assert interface.offered_qos_profiles(topic) == [qos_dict(depth=10)], topic


def test_scenario_metadata_layout() -> None:
    scenario = load_scenario('application')   # two tractor-trailers
    meta = interface.scenario_metadata(scenario)
    names = [r.name for r in scenario.robots]
    assert meta['scenario'] == 'application' and meta['robots'] == ','.join(names)
    assert [float(v) for v in meta['workspace'].split(',')] == list(scenario.world.workspace)
    for spec in scenario.robots:
        assert meta[interface.metadata_key('model', spec.name)] == 'tractor_trailer'
        assert float(meta[f'radius/{spec.name}']) == spec.radius
        assert [float(v) for v in meta[f'start/{spec.name}'].split(',')] == pytest.approx(list(spec.start))
        assert [float(v) for v in meta[f'goal/{spec.name}'].split(',')] == pytest.approx(list(spec.goal))
        assert float(meta[f'length/{spec.name}']) == spec.length
    assert all(isinstance(v, str) for v in meta.values())
