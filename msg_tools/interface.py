"""The fastep ROS 2 interface, defined once: topic names, message types, QoS and the recording's metadata.

This module is the contract of the ROS 2 interface (docs/guide.md, "The ROS 2 graph"); every node (fastep_ros),
the launcher, the recorder, fastep-sim's recordings (sim_mcap), replay and fastep-report take names, types and QoS
from here.

Topics: per robot in a one-level namespace (`/r1/odom`; nodes use relative names and are started with
`__ns:=/r1`), and /obstacles, /map, /clock in the root namespace. QoS: each topic has the one profile its
publishers offer (OFFERED_QOS), from which a recording's `offered_qos_profiles` are derived so a replay
re-creates them (liveliness written out as AUTOMATIC, the profile in effect). Recording metadata: one MCAP
metadata record named METADATA_NAME with string values (scenario_metadata): the scenario, its robots and their
models, radii, starts and goals, and for a v2 world the whole scenario as JSON.
"""

from __future__ import annotations

import json
import re
from typing import TYPE_CHECKING, Any

from rclpy.qos import DurabilityPolicy, HistoryPolicy, LivelinessPolicy, QoSProfile, ReliabilityPolicy

from msg_tools.ros2_profile import qos_profile_to_dict

if TYPE_CHECKING:
    from fastep_core.scenario import Scenario

__all__ = [
    'CLOCK', 'CLOCK_ACK', 'CMD_VEL', 'COST', 'FOOTPRINT', 'GOAL_POSE', 'LATCHED', 'LATEST', 'MAP', 'MAP_FRAME',
    'METADATA_NAME', 'MOVERS', 'OBSTACLES', 'ODOM', 'OFFERED_QOS', 'PLAN', 'RECORDING', 'RELIABLE', 'ROBOT_TOPICS',
    'ROBOT_TOPIC_PATTERN', 'SCAN', 'SCENARIO_DATA', 'SHARED_TOPICS', 'SPEED_LIMIT', 'STAMPED_CMD_VEL_TYPE', 'STATUS',
    'STATUS_QOS',
    'TRACKED_OBSTACLES', 'TRAILER_POSE', 'TYPES', 'WAYPOINT', 'is_interface_topic', 'message_type', 'metadata_key',
    'offered_qos', 'offered_qos_profiles', 'robot_topic', 'scenario_metadata', 'split_robot_topic',
]

# ----------------------------------------------------------------------------------------------- topic names

# Per robot, relative to the robot's namespace.
ODOM = 'odom'                  # plant: the robot's pose and twist
CMD_VEL = 'cmd_vel'            # planner: the command
GOAL_POSE = 'goal_pose'        # user / launcher: where to go
WAYPOINT = 'waypoint'          # planner: the point driven to now
PLAN = 'plan'                  # planner: the waypoints planned so far and the goal
COST = 'cost'                  # planner: fitness of the step in use
STATUS = 'status'              # planner: mode and reasons
TRAILER_POSE = 'trailer_pose'  # plant, tractor-trailers only: the trailer axle and heading
FOOTPRINT = 'footprint'        # planner, latched: its safety circle; announces a robot of this graph
ROBOT_TOPICS = (ODOM, CMD_VEL, GOAL_POSE, WAYPOINT, PLAN, COST, STATUS, TRAILER_POSE, FOOTPRINT)
# A robot's laser (any sensor_msgs/LaserScan; the planner perceives with it) and what its planner believes
# (visualization_msgs/MarkerArray); neither is recorded yet.
SCAN = 'scan'
SPEED_LIMIT = 'speed_limit'   # nav2_msgs/msg/SpeedLimit into the planner (Nav2's speed filter publishes it)
TRACKED_OBSTACLES = 'tracked_obstacles'
# The known movers of a format-v2 world where the map puts them, at >= 10 Hz (visualization_msgs/MarkerArray,
# reliable, volatile: only the newest matters); fastep-map publishes it, planners avoid them. Not recorded yet.
MOVERS = '/movers'

# Shared, in the root namespace.
OBSTACLES = '/obstacles'   # map node: circles and walls
MAP = '/map'               # map node: occupancy grid of the workspace
CLOCK = '/clock'           # fastep-clock (or a replay): simulated time
CLOCK_ACK = '~/clock_ack'  # an observer in lock step (fastep-record, fastep-launch): the /clock time it has taken
SHARED_TOPICS = (OBSTACLES, MAP, CLOCK)

# fastep-record's own status, in its node's namespace (`/recorder/recording`; not recorded by default): a
# DiagnosticStatus (STATUS_QOS) whose values count the messages received per topic, so a launcher can tell the
# recorder hears a robot before the run starts.
RECORDING = '~/recording'

MAP_FRAME = 'map'          # frame of goals, waypoints, plans and obstacles; odometry is `<name>/odom` ->
                           # `<name>/base_link` (REP-105: msg_tools.frames)

# '/<robot>/<topic>' with a robot name of one level (a ROS name token) and a per-robot topic.
ROBOT_TOPIC_PATTERN = re.compile(r'^/([A-Za-z_][A-Za-z0-9_]*)/(' + '|'.join(ROBOT_TOPICS) + r')$')


def robot_topic(robot: str, topic: str) -> str:
    """The full name of a robot's topic: robot_topic('r1', ODOM) == '/r1/odom'."""
    return f'/{robot}/{topic}'


def split_robot_topic(topic: str) -> tuple[str, str] | None:
    """('r1', 'odom') for '/r1/odom'; None for a name that is not a per-robot topic of the interface."""
    match = ROBOT_TOPIC_PATTERN.match(topic)
    return None if match is None else (match.group(1), match.group(2))


def is_interface_topic(topic: str) -> bool:
    """Whether a full topic name belongs to the fastep interface (what fastep-record takes by default)."""
    return topic in SHARED_TOPICS or ROBOT_TOPIC_PATTERN.match(topic) is not None


def _relative(topic: str) -> str:
    """The key of a full or relative topic name in the tables below ('/r1/status' -> 'status')."""
    if topic in SHARED_TOPICS:
        return topic
    parts = split_robot_topic(topic)
    if parts is not None:
        return parts[1]
    if topic in ROBOT_TOPICS:
        return topic
    raise KeyError(f'{topic} is not a topic of the fastep interface')


# ----------------------------------------------------------------------------------------------- types

TYPES: dict[str, str] = {
    ODOM: 'nav_msgs/msg/Odometry',
    CMD_VEL: 'geometry_msgs/msg/Twist',   # geometry_msgs/msg/TwistStamped with use_stamped_cmd_vel
    GOAL_POSE: 'geometry_msgs/msg/PoseStamped',
    WAYPOINT: 'geometry_msgs/msg/PoseStamped',
    PLAN: 'nav_msgs/msg/Path',
    COST: 'std_msgs/msg/Float64',
    STATUS: 'diagnostic_msgs/msg/DiagnosticStatus',
    TRAILER_POSE: 'geometry_msgs/msg/PoseStamped',
    FOOTPRINT: 'geometry_msgs/msg/PolygonStamped',
    OBSTACLES: 'visualization_msgs/msg/MarkerArray',
    MAP: 'nav_msgs/msg/OccupancyGrid',
    CLOCK: 'rosgraph_msgs/msg/Clock',
}
STAMPED_CMD_VEL_TYPE = 'geometry_msgs/msg/TwistStamped'


def message_type(topic: str) -> str:
    """The type name ('pkg/msg/Name') of a full or relative topic name of the interface."""
    return TYPES[_relative(topic)]


# ----------------------------------------------------------------------------------------------- QoS

def _profile(depth: int, latched: bool = False) -> QoSProfile:
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=depth, reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.TRANSIENT_LOCAL if latched else DurabilityPolicy.VOLATILE,
                      liveliness=LivelinessPolicy.AUTOMATIC)


# The shared map and obstacles: reliable + transient-local, so late joiners get them (Nav2's map QoS).
LATCHED = _profile(1, latched=True)
# Everything else a node publishes.
RELIABLE = _profile(10)
# Status is latched too, so a monitor that subscribes late sees the current state at once; 10 deep.
STATUS_QOS = _profile(10, latched=True)
# Inputs where only the newest message matters (odometry into a controller, commands into a plant): a
# deeper queue would make a busy node act on old messages, i.e. add delay to the control loop. Subscriptions
# only: no topic is published with it.
LATEST = _profile(1)

OFFERED_QOS: dict[str, QoSProfile] = {
    ODOM: RELIABLE,
    CMD_VEL: RELIABLE,
    # The planner also takes latched goals (fastep-launch sends them latched; fastep_ros.goals), but goals come
    # from anyone (`ros2 topic pub`, RViz), volatile: a recorder that asked for transient-local would miss those.
    GOAL_POSE: RELIABLE,
    WAYPOINT: RELIABLE,
    PLAN: RELIABLE,
    COST: RELIABLE,
    STATUS: STATUS_QOS,
    TRAILER_POSE: RELIABLE,
    # Latched: a planner that starts later learns the robots already there (and their radii) at once.
    FOOTPRINT: LATCHED,
    OBSTACLES: LATCHED,
    MAP: LATCHED,
    CLOCK: RELIABLE,
}


def offered_qos(topic: str) -> QoSProfile:
    """The QoS the fastep nodes publish a topic with (full or relative name)."""
    return OFFERED_QOS[_relative(topic)]


def offered_qos_profiles(topic: str) -> list[dict[str, Any]]:
    """A recording's `offered_qos_profiles` of a topic (rosbag2's YAML form): the one profile of offered_qos."""
    return [qos_profile_to_dict(offered_qos(topic))]


# ----------------------------------------------------------------------------------------------- metadata

METADATA_NAME = 'fastep'
SCENARIO_DATA = 'scenario_data'   # metadata key of a v2 run's whole scenario (JSON)


def metadata_key(field: str, robot: str) -> str:
    """The metadata key of one robot's value: metadata_key('radius', 'r1') == 'radius/r1'."""
    return f'{field}/{robot}'


def scenario_metadata(scenario: Scenario) -> dict[str, str]:
    """The METADATA_NAME entries describing a scenario and its robots (fastep-sim --mcap, fastep-record)."""
    out = {'scenario': scenario.name, 'robots': ','.join(r.name for r in scenario.robots),
           'workspace': ','.join(f'{v:g}' for v in scenario.world.workspace)}
    for r in scenario.robots:
        out[metadata_key('model', r.name)] = r.model
        out[metadata_key('radius', r.name)] = f'{r.radius:g}'
        out[metadata_key('start', r.name)] = ','.join(f'{v:g}' for v in r.start)
        out[metadata_key('goal', r.name)] = ','.join(f'{v:g}' for v in r.goal)
        if r.model == 'tractor_trailer':
            out[metadata_key('length', r.name)] = f'{r.length:g}'
        if r.footprint is not None:   # judged by its outline (fastep-report)
            out[metadata_key('footprint', r.name)] = json.dumps(r.footprint.to_list())
    if not scenario.is_static:
        # A format-v2 world: the whole scenario (JSON of fastep_core.scenario.scenario_data), so a report judges
        # the run against the truth (movers over time, obstacles missing from or misplaced on the map), not
        # against the map the recording's /obstacles holds.
        from fastep_core.scenario import scenario_data
        out[SCENARIO_DATA] = json.dumps(scenario_data(scenario), separators=(',', ':'))
    return out
