"""Ranges the nodes and fastep-launch accept for rates, periods and the real-time factor (no ROS import here: the
launcher checks its command line with them before it starts anything). docs/robustness.md lists them."""

from __future__ import annotations

from fastep_core.scenario import MODELS, Scenario

__all__ = ['ACK_PERIOD_RANGE', 'CLOCK_JUMP_LIMIT', 'GRAPH_MODELS', 'OBSERVER_LAG_MAX', 'PERIOD_RANGE', 'RATE_RANGE',
           'ROBOT_NAME_MAX', 'RTF_RANGE', 'STEP_RANGE', 'ACTION_RESULT_TIMEOUT', 'GOAL_POSES_MAX', 'graph_problem',
           'robot_name_problem', 'INLINE_WORLD_ITEMS', 'WORLD_OBSTACLES_MAX',
           'TF_MESSAGE_TRANSFORMS', 'TF_POLL_TRANSFORMS', 'TF_STAMP_AHEAD', 'SPEED_LIMIT_LOG_PERIOD',
           'LOCALIZATION_MARGIN', 'LOCALIZATION_EXTENT_MAX', 'TF_LOCALIZER_INTERVAL']

GRAPH_MODELS: tuple[str, ...] = MODELS
"""Robot models the ROS plant and planner nodes run: every model (diff_drive included)."""

RATE_RANGE = (0.1, 10_000.0)
"""Timer rates a node accepts (Hz): the planners' 1 / dt range (PlannerParams.dt is [1e-4, 10] s). Beyond it rclpy's
create_timer overflowed (1e-12 Hz: a traceback) or a node spent itself on its timer (1e12 Hz)."""

PERIOD_RANGE = (0.01, 3600.0)
"""Wall periods (s) of housekeeping timers (the recorder's flush and discovery)."""

STEP_RANGE = (1e-4, 10.0)
"""Simulated seconds per tick of fastep-clock: PlannerParams.dt's range (the launcher passes dt)."""

RTF_RANGE = (1e-3, 1e4)
"""Real-time factors of fastep-clock and fastep-launch --rtf. 1e-300 overflowed rclpy's create_timer (the tick
period is step / rtf): at 1e-3 a tick of the largest step takes 10^4 wall seconds. fastep-clock also refuses a
tick of more than CLOCK_JUMP_LIMIT simulated seconds (what a node takes from one /clock message unconfirmed)."""

OBSERVER_LAG_MAX = 500
"""Ticks an observer of the lock step (fastep-clock's observer_topics) may lag behind: half the 1000-message queues
in which fastep-record and fastep-launch's monitor keep what they have not taken yet (a topic sends one message a
tick at most), so that none is dropped."""

ACK_PERIOD_RANGE = (0.0, 60.0)
"""Simulated seconds between fastep-record's clock_ack messages (0: one for every /clock time)."""

CLOCK_JUMP_LIMIT = 3600.0
"""Simulated seconds a /clock message may run ahead of the last one and be taken at once (fastep_ros.common)."""

ROBOT_NAME_MAX = 200
"""Characters of a robot name on the live graph. The name is a ROS namespace, and the longest name in it, the
planner's `/<name>/planner/set_parameters_atomically` service, may have 247 characters: 212 for the name at most
(a 250-character name was an InvalidTopicNameException traceback in fastep-launch)."""


WORLD_OBSTACLES_MAX = 4_000
"""Obstacles the planner builds its world of: walls outlining the occupied cells of /map (obstacle_source map), or
circles and segments of /obstacles. Every planning pass measures against all of them, the exact shortest path
(trap escapes, fastep_route) more than linearly: its first pass took 2.4 s over 4,028 walls (about max_plan_age),
4.3 s over 5,014 and 43 s over 19,640 (the control tick then up to 161 ms, waiting for the GIL), and a 1000 x 1000
map of random clutter outlined 477,810 walls (792 MB, 4-12 s without a command). A room's outline at 0.05 m is a
few hundred walls; the planners are measured with up to 2,000 obstacles. Beyond it a /map's cells are merged
(msg_tools.occupancy_grid.grid_walls: the fewest n x n that fit, a merged cell occupied where any of its cells is,
never less obstacle than the map) and status says so; an /obstacles message is refused (one line, status, the
world before kept). A /map of more than MAX_GRID_CELLS (msg_tools.occupancy_grid) cells is refused likewise."""

INLINE_WORLD_ITEMS = 4096
"""Items of a world message (cells of /map; markers plus line points of /obstacles; obstacles when only the
workspace changed) the planner's executor turns into a world itself: ~10 ms at worst (a 64 x 64 checkerboard's
8,320 walls). A larger message is copied and built on the world builder thread (fastep_ros.world_builder) while the
control tick drives on the world before; without a planning thread (lock step, planning_thread:=false, where every
pass runs on the executor anyway) every world is built on the executor, at the tick it came."""

GOAL_POSES_MAX = 2000
"""Poses of one navigation action goal (navigate_through_poses, follow_waypoints: fastep_ros.navigate_actions).
rclpy converts a goal's message before anything can look at it (about 40 us a pose on a 2-core machine; on the
action thread, fastep_ros.action_thread), and every pose is then checked at once on the planner's executor, before
the robot moves: 2000 poses (a 1 km route at a pose every 0.5 m) keep that under the 0.1 s a cmd_vel may wait.
100,000 poses had the control loop at 1.6-5.6 Hz for 20 s. A goal with more is ABORTED at once (200,
ComputePathToPose UNKNOWN), its message saying how many it had and this bound; the robot does not move."""

ACTION_RESULT_TIMEOUT = 5.0
"""Wall seconds (the action servers' node keeps wall time: fastep_ros.action_thread) an ended action goal stays with
its server, its result to be asked for: rclpy's ActionServer result_timeout (Nav2's bt_navigator:
action_server_result_timeout). Clients ask for the result as soon
as the goal is accepted (rclpy's ActionClient, nav2_simple_commander), so a few seconds lose none; rclpy's default,
900 s, kept every ended goal's poses: 40 goals of 10,000 poses cancelled at once held the planner at 398 MB (130 MB
before) 20 s later. A result asked for later than this is UNKNOWN (action_msgs/GoalStatus)."""


TF_MESSAGE_TRANSFORMS = 1000
"""Transforms of one /tf or /tf_static message (tf2_msgs/TFMessage) a node reads whole (fastep_ros.live_tf): about
4 ms of the executor read from its bytes; robot_state_publisher sends a robot's few dozen. rclpy took ~1 s to
turn a neighbour's 20,000 into messages, ten times a second: no command for 24 of 26 s. A larger message is cut
to the transforms of the frames the node looks up (a search of its bytes, ~1.5 ms a frame for 20,000), with a
throttled warning; the rest of it is not read."""

TF_POLL_TRANSFORMS = 2000
"""Transforms a TfListener reads whole per lookup, over every /tf message that came since the last one (at 20 Hz:
40,000 a second, 8 ms of the executor at most). Messages beyond it are cut as larger ones are
(TF_MESSAGE_TRANSFORMS), with a throttled warning: many small messages cost the control loop no more than one
big one."""

TF_STAMP_AHEAD = 2.0
"""Seconds a /tf transform may be stamped ahead of the node's clock: AMCL post-dates map -> odom by its
transform_tolerance (Nav2's default 1 s). A later stamp is refused with a throttled warning: kept, it would stay
the edge's newest for ever, as stamps are honoured (an older transform never replaces a newer). An edge whose
newest stamp is this far ahead (the clock went back: a restarted simulation) starts afresh."""


TF_LOCALIZER_INTERVAL = 1.0
"""Seconds a localizer may take between two map -> odom transforms on /tf (map_to_odom_from_tf): the planner drives
on one until it is this plus transform_tolerance old (1.3 s by default), then holds (status `waiting`: the
localizer stopped). AMCL publishes on each scan and post-dates by its transform_tolerance (1 s) for this reason;
a localizer that does not post-date, or whose transforms ride in a neighbour's flood of 20,000 frames (rclpy took
0.1-0.3 s to serialise one, at ~3.5 Hz), was judged stopped at 0.3 s between two of them, and the robot held.
tf2 and Nav2 read such an edge; odometry over 1.3 s is centimetres off."""

LOCALIZATION_MARGIN = 1.0
"""Metres a localization pose (the localization_topic's, or base_link's map pose from map -> odom on /tf with the
newest odometry) may lie outside the map's workspace (the workspace parameter, else /map's): a robot at the edge of
its map, and a localizer's error there. Farther, it is refused (status says so, a throttled line), the last pose
taken kept (none yet: the robot waits). amcl_pose at (1e300, 1e300) once placed scans there and faulted a plan."""

LOCALIZATION_EXTENT_MAX = 100_000.0
"""Metres from the map frame's origin a localization pose may lie before any map is known (LOCALIZATION_MARGIN
then has no workspace to measure from): 100 km, farther than any map a robot plans in, so only an absurd pose
((1e300, 1e300)) is refused before the map comes."""

SPEED_LIMIT_LOG_PERIOD = 5.0
"""Wall seconds between two log lines of the planner's speed-limit changes (nav2_msgs/SpeedLimit): a change is said
at once after a quiet period, those within it are counted and the newest said when it is over (one line in 5 s is
read by a person; a speed filter's limits change a few times a minute). Beyond it nothing is lost: every change is
in force at once and status' `speed_limit` says the cap of the moment. Unthrottled, a flood of alternating limits
wrote 6,788 lines in 10 s."""

def robot_name_problem(name: str) -> str:
    """Why a robot name the scenario format allows ([A-Za-z_][A-Za-z0-9_]*) cannot be a ROS namespace; '' if it can.

    ROS also refuses '__' anywhere in a name: rcl's argument lexer reads it as the start of a token (`__ns`,
    `__node`), so `-r __ns:=/r__1` fails to parse.
    """
    if '__' in name:
        return "ROS does not allow '__' in a name"
    if len(name) > ROBOT_NAME_MAX:
        return f'{len(name)} characters, more than the {ROBOT_NAME_MAX} a ROS namespace of fastep can have'
    return ''


def graph_problem(scenario: Scenario, robots: bool = True) -> str:
    """What of a scenario the live graph cannot honour; '' if nothing (docs/scenarios.md, v2).

    Format v2 runs: fastep-map publishes what the map knows (known still obstacles, misplaced ones where the map
    says, known movers on /movers), plants of robots with a `sensor` scan the truth (fastep_ros.plant), and
    planners perceive with the scans (fastep_ros.perception). robots=False: the obstacles only (the map node
    publishes no robot); every obstacle runs, so only the robots' models are checked.
    """
    for i, robot in enumerate(scenario.robots):
        if robots and robot.model not in GRAPH_MODELS:
            return f'robots[{i}] ({robot.name}): model {robot.model} does not run on the ROS graph; use fastep-sim'
    return ''
