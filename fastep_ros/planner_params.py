"""The planner node's parameters, one table: every PlannerParams field (Table 1 of the paper and the rest, tunable),
then the node's own, then the lifecycle's `autostart`, each with its unit and component (its section of the
reference page: every parameter needs one of fastep_ros.reference.COMPONENTS). PlannerNode declares them in this
order in one loop; the reference pages (fastep_ros.reference) show what the declarations give. `planner_params`
makes the navigator's PlannerParams of their values: its `dt` is the control period, 1 / control_rate_hz.
"""

from __future__ import annotations

import math
from dataclasses import fields
from typing import Any, Collection, Mapping

from rclpy.node import Node

from fastep_core.errors import ParameterError
from fastep_core.planning.algorithms import ALGORITHMS, DEFAULT_ALGORITHM, algorithm_name
from fastep_core.planning.params import PlannerParams
from fastep_core.scenario import MODELS
from fastep_ros.common import PERIOD_RANGE, RATE_RANGE, Param
from fastep_ros.lifecycle import AUTOSTART
from fastep_ros.sensors import MOUNT_MARGIN, SCAN_MODES
from msg_tools import convert, interface

__all__ = ['PARAMETERS', 'PERIOD_TOLERANCE', 'TUNABLE', 'control_period', 'given_names', 'planner_params']

_DEFAULTS = PlannerParams()
PERIOD_TOLERANCE = 1e-9
"""A dt within this relative difference of 1 / control_rate_hz agrees with it (1 / (1 / dt) is dt to rounding)."""


PARAMETERS: tuple[Param, ...] = (
    *(Param.of_field(f, getattr(_DEFAULTS, f.name)) for f in fields(PlannerParams)),
    Param('algorithm', DEFAULT_ALGORITHM, 'planner: ' + ', '.join(f'{a} ({algorithm_name(a)})' for a in ALGORITHMS),
          constraints=' | '.join(ALGORITHMS), component='node'),
    Param('model', 'point_mass', 'robot model: ' + ' | '.join(MODELS), constraints=' | '.join(MODELS),
          component='robot'),
    Param('robot_radius', 0.5, 'safety radius: centre-to-obstacle-surface distance that counts as collision',
          constraints='> 0', unit='m', component='robot'),
    Param('footprint', '', 'the robot\'s outline in base_link, in Nav2\'s form "[[x, y], [x, y], ...]" (m; either '
          'turning order; base_link inside it); empty or "[]": the circle of robot_radius. A diff_drive only; it '
          'replaces robot_radius, which becomes its circumscribed radius: collisions are checked with the outline, '
          'and it is what the robot announces on `footprint`', unit='m', component='robot'),
    Param('length', 1.0, 'tractor-trailer: tractor mid-axle length L', unit='m', component='robot'),
    Param('trailer_length', 1.0, 'tractor-trailer: trailer length Lt', unit='m', component='robot'),
    Param('hitch_offset', 0.0, 'tractor-trailer: hitch offset c', unit='m', component='robot'),
    Param('seed', 0, 'seed of the swarm\'s random numbers', component='node'),
    Param('seed_stream', -1, 'if >= 0: use stream k of SeedSequence(seed).spawn, as fastep-sim does for the k-th '
          'robot of a scenario; -1: default_rng(seed)', component='node'),
    Param('control_rate_hz', 20.0, 'control ticks per second of the node clock (1 / dt of the in-process '
          'simulator); the planner\'s dt, the period its controller, velocity smoother and DWA work with, is '
          '1 / control_rate_hz', value_range=RATE_RANGE, unit='Hz', read_only=False, component='node'),
    Param('odom_timeout', 1.0, 'odometry older than this (s, node clock) is stale: the robot is stopped',
          constraints='> 0', read_only=False, unit='s', component='node'),
    Param('clock_timeout', 3.0, 'on simulated time: no /clock for this many wall seconds is a warning on status '
          'and /diagnostics, and the robot is stopped', value_range=PERIOD_RANGE, unit='s', read_only=False,
          component='node'),
    Param('use_stamped_cmd_vel', False, 'publish cmd_vel as TwistStamped, not Twist', component='node'),
    Param('other_robot_radius', 0.0, 'safety radius assumed for other robots; 0: the radius each announces (its '
          'footprint), robot_radius until it is heard', value_range=(0.0, math.inf), read_only=False,
          unit='m', component='robot'),
    Param('other_robot_timeout', 3.0, 'another robot whose odometry has not come for this long (s, node clock) is '
          'stale (status `stale`); from odom_timeout on it is avoided where last seen, widened by its last speed '
          'times up to this long', constraints='> 0', unit='s', component='robot'),
    Param('max_extrapolation', 0.25, 'latency compensation: odometry (own and other robots\') is predicted forward '
          'from its stamp to the control time by at most this much; own odometry stamped longer ago is stale: '
          'the robot is held still; 0 disables both', value_range=(0.0, math.inf), read_only=False,
          unit='s', component='node'),
    Param('workspace', None, '[xmin, ymin, xmax, ymax]; empty: the extent of /map', unit='m', component='node'),
    Param('laser_mount', None, '[x (m), y (m), yaw (rad)]: where the scanner sits in base_link, for robots without '
          'TF: scans in a frame of their own are placed there; empty: from /tf_static and /tf at each scan\'s stamp '
          '(base_link -> the scan\'s frame, as robot_state_publisher publishes it). A mount farther from base_link '
          f'than robot_radius (or the footprint) plus {MOUNT_MARGIN:g} m is refused',
          unit='m, m, rad', component='perception'),
    Param('scan_mode', 'auto', 'how the planner depends on `scan`: auto (scans are required once one has been '
          'heard: scans that cannot be used hold the robot still, status `blind`) | required (from the start) | '
          'ignored (not subscribed: the robot drives on its map alone)', constraints=' | '.join(SCAN_MODES),
          component='perception'),
    Param('scan_timeout', 1.0, 'required scans: none usable for this long (s, node clock) holds the robot still; '
          'a scan stamped farther than this from the node clock is stale', value_range=(0.05, 60.0), unit='s',
          read_only=False, component='perception'),
    Param('transform_tolerance', 0.3, 'how long a scan waits for the transform of its stamp to come on /tf (s, '
          'node clock) before it is given up, and how old map -> odom from TF may be beyond the 1 s a localizer may '
          'take between two (map_to_odom_from_tf: an older one is not used, the robot waits), as Nav2\'s '
          'transform_tolerance', value_range=(0.0, 10.0),
          unit='s',
          read_only=False, component='perception'),
    Param('obstacle_source', 'markers', 'where the obstacles come from: markers (the /obstacles MarkerArray of '
          'fastep-map: circles and walls) | map (the occupied cells of the /map OccupancyGrid, as Nav2\'s '
          'map_server publishes it: their outline, as walls)', constraints='markers | map', component='node'),
    Param('scan_noise', 0.01, 'standard deviation of the laser\'s range noise (m), which a LaserScan does not '
          'carry: the perception of `scan` clusters and fits with it', value_range=(0.0, 1.0), unit='m',
          component='perception'),
    Param('localization_tolerance', [0.03, 0.02], '[translation (m), yaw (rad)]: how far the robot\'s map pose '
          'may be off besides what the localization pose\'s covariance says: a surface the laser sees within that '
          '(turned into metres at each return\'s range) of a mapped obstacle is that obstacle, not a new one; '
          '[0, 0]: the pose is the truth (simulation)', unit='m, rad', component='perception'),
    Param('odometry_drift', [0.01, 0.002], '[translation (m per m), yaw (rad per m)]: how far the odometry may '
          'drift per metre driven since the last localization pose (since the start without one): added to '
          'localization_tolerance, growing as the robot drives', unit='m/m, rad/m', component='perception'),
    Param('localization_sigmas', 3.0, 'the localization pose\'s covariance bounds the pose this many standard '
          'deviations out', value_range=(0.0, 10.0), component='perception'),
    Param('occupied_threshold', convert.OCCUPIED_THRESHOLD, 'with obstacle_source map: a cell is occupied from this '
          'value (0-100) on; unknown cells (-1) are free (map_server\'s occupied_thresh 0.65)', value_range=(1, 100),
          component='node'),
    Param('frame_id', interface.MAP_FRAME, 'frame of goals, waypoints and plans', component='node'),
    Param('odom_frame_id', '', 'the robot\'s odometry frame (REP-105); empty: <ns>/odom (root namespace: odom). '
          'Odometry in it or in frame_id is taken, in any other frame refused', component='node'),
    Param('localization_topic', '', 'localization pose topic (geometry_msgs/PoseWithCovarianceStamped, the map pose '
          'of base_link, e.g. amcl_pose) giving map -> odom; empty: map -> odom is the identity (simulation)',
          component='node'),
    Param('goal_frames_from_tf', True, 'follow /tf (polled, taken when used) to move goals given in other frames '
          '(odom, base_link) into map; false: only /tf_static is followed (fastep-launch, whose goals are in map: '
          'every plant publishes /tf at its rate)', component='node'),
    Param('map_to_odom_from_tf', False, 'take map -> odom from /tf and /tf_static (AMCL and slam_toolbox publish it) '
          'at each control tick; localization_topic, when set, is taken instead', component='node'),
    Param('lock_step', False, 'on simulated time: act once per own odometry stamp, when the other robots\' odometry '
          '(and the scan) of that time are in, and stamp cmd_vel with it, so a graph steps like fastep-sim '
          '(fastep-launch sets it; needs use_stamped_cmd_vel and plants in lock step)', component='node'),
    Param('planning_thread', True, 'plan on a thread of its own, so that the control loop never waits for planning '
          '(it drives on the newest plan, guarded every tick); false: every control tick plans, the clock of a '
          'simulation waiting for it. Lock step plans on the tick (unless realtime)', component='node'),
    Param('exclusive_cmd_vel', True, 'another publisher on cmd_vel (a second planner started in this namespace, a '
          'teleop) stops this planner\'s commands after one zero: status ERROR `conflict` until it is gone; false: '
          'command anyway', read_only=False, component='node'),
    Param('stop_on_failure', False, 'follow_waypoints: true: a waypoint that fails ends the goal (ABORTED, error '
          'code 0 as Nav2\'s waypoint follower gives it, the waypoint in missed_waypoints with its code); false (as '
          'in Nav2\'s stock nav2_params.yaml): it is missed and the robot goes on to the next', read_only=False,
          component='node'),
    Param('realtime', False, 'in lock step, plan on the planning thread as on wall time: a pass\'s plan reaches the '
          'control loop when it is done, the simulated clock going on meanwhile (fastep-launch --realtime: planning '
          'latency counted; not deterministic)', component='node'),
    Param('max_plan_age', 2.0, 'a plan older than this (s, node clock) is not driven on: the robot stops, status '
          'ERROR, until a planning pass ends (planning_thread)', value_range=(0.1, 60.0), unit='s',
          read_only=False, component='node'),
    Param('planning_timeout', 10.0, 'a goal under way whose planning has left no plan for this long (s, node clock: '
          'a pass that does not end, an exact path searched for ever) fails: status ERROR `failed`, an action goal '
          'ABORTED with Nav2\'s ComputePathToPose TIMEOUT (207), as Nav2\'s progress checker ends a goal that '
          'makes none; 0: never (planning_thread)', value_range=(0.0, 3600.0), unit='s', read_only=False,
          component='recovery'),
    AUTOSTART,
)

TUNABLE = tuple(param.name for param in PARAMETERS if not param.read_only)
"""What changes while the node runs (fastep_ros.parameters.DynamicParameters); the rest is what it was built with."""


def control_period(rate_hz: float, dt: float | None = None, kept: float | None = None) -> float:
    """PlannerParams.dt of a planner controlling at rate_hz: 1 / rate_hz, or `dt` when given (ParameterError, one
    line naming both, when it disagrees with 1 / rate_hz by more than PERIOD_TOLERANCE), or else `kept` (the dt
    it has) when that agrees. Why a given or kept dt over 1 / rate_hz: fastep-launch gives the scenario's dt and
    1 / dt as the rate, and the planner then steps by the very dt fastep-sim steps by."""
    if not (math.isfinite(rate_hz) and rate_hz > 0.0):
        return dt if dt is not None else kept if kept is not None else _DEFAULTS.dt   # refused by its own range
    period = 1.0 / rate_hz

    def agrees(value: float) -> bool:
        return abs(value - period) <= PERIOD_TOLERANCE * period

    if dt is not None:
        if not agrees(dt):
            raise ParameterError(f'parameter dt={dt:g} disagrees with control_rate_hz={rate_hz:g} (1 / '
                                 f'control_rate_hz = {period:g} s): the control period is one; set dt to '
                                 f'{period:g} with it, or leave dt out')
        return dt
    return kept if kept is not None and agrees(kept) else period


def given_names(node: Node) -> frozenset[str]:
    """The names given to the node at start (`-p name:=value`, a params file, parameter_overrides)."""
    overrides = getattr(node, '_parameter_overrides', None)   # rclpy keeps them there (a private attribute)
    return frozenset(overrides) if isinstance(overrides, dict) else frozenset()


def planner_params(values: Mapping[str, Any], given: Collection[str] = ()) -> PlannerParams:
    """The navigator's PlannerParams of the node's parameter values: every field of the same name, dt the control
    period (control_period of control_rate_hz). The dt value counts as given when its name is in `given` (the
    names given at start: given_names) or it is not the default; a given dt that disagrees with control_rate_hz
    raises ParameterError (one line, naming both). Other bad values raise ParameterError as PlannerParams does."""
    dt = values['dt']
    explicit = dt if 'dt' in given or dt != _DEFAULTS.dt else None
    period = control_period(values['control_rate_hz'], explicit, dt)
    return PlannerParams().with_overrides({**{name: values[name] for name in PlannerParams.names()}, 'dt': period})
