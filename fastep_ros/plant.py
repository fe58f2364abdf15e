"""fastep-plant: one simulated robot. It integrates the robot's kinematic model and publishes its odometry.

    fastep-plant --ros-args -r __ns:=/r1 -p model:=point_mass -p start:=[5.0,25.0] [-p use_sim_time:=true]
    fastep-plant --ros-args -r __ns:=/d1 -p model:=diff_drive -p start:=[5.0,25.0,1.57]

Subscribes `cmd_vel` (body frame), publishes `odom` (REP-105), `trailer_pose` for tractor-trailers, TF (map -> odom
the identity unless publish_map_to_odom is false, odom -> base_link; fastep_ros.live_tf) and, for a robot with a
`sensor`, `scan` of the true world. The model is integrated in fixed steps of 1 / rate_hz on the node clock and
odometry stamped with the integrated time, so several plants line up. Until simulated time starts it repeats its
start state once cmd_vel has a publisher, because DDS matches the two ends of a link each on its own and a launcher
must see both ends up (docs/robustness.md, "A loaded machine"). A command's age counts from when it was sent, so a
command that waited while the plant was descheduled does not act for a fresh cmd_timeout. In lock step the robot
moves exactly as fastep-sim moves it. Details: docs/guide.md, "The plant node"; frames: docs/frames.md.

With `dynamics` (a diff_drive base with mass: fastep_core/dynamics) it steps a MuJoCo physics plant instead, 500
physics steps a second behind the base's own controller, and publishes the wheel-encoder odometry on `odom` (a
pose that drifts in `odom`, the twist measured); `ground_truth_topic` then carries the true pose in `map`
(geometry_msgs/PoseWithCovarianceStamped), the localizer a planner reads through its `localization_topic`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, Sequence

import numpy as np
from builtin_interfaces.msg import Time
from diagnostic_msgs.msg import DiagnosticStatus
from geometry_msgs.msg import PoseStamped, PoseWithCovarianceStamped, Twist, TwistStamped
from nav_msgs.msg import Odometry
from rclpy.clock import Clock, ClockType, ROSClock
from rclpy.qos import qos_profile_sensor_data
from rclpy.serialization import deserialize_message
from sensor_msgs.msg import LaserScan

from fastep_core.dynamic_world import DynamicWorld
from fastep_core.dynamics.params import dynamics_from_text
from fastep_core.dynamics.plant import PhysicsPlant, odometry_generator
from fastep_core.errors import FastepError
from fastep_core.kinematics import PointMass, TractorTrailer
from fastep_core.kinematics.diff_drive import DiffDrive
from fastep_core.planning.params import PlannerParams
from fastep_core.scenario import MODELS, load_scenario
from fastep_core.sensing.laser import LaserSpec
from fastep_ros.common import (
    PERIOD_RANGE,
    RATE_RANGE,
    StartupError,
    check_range,
    declare,
    guard_clock,
    node_main,
    quiet_at_stop,
)
from fastep_ros.diagnostics import Diagnostics, Task
from fastep_ros.executors import MessageInfoCallback
from fastep_ros.lifecycle import ManagedNode
from fastep_ros.live_tf import TfBroadcaster
from fastep_ros.lock_step import LOCK_WAIT, STAMP_EPS
from fastep_ros.parameters import DynamicParameters
from fastep_ros.sim_time import SimTimeWatch
from msg_tools import cdr, convert, frames, interface
from msg_tools.interface import LATEST, offered_qos

__all__ = ['PlantNode', 'main']

MAX_CATCH_UP = 100_000  # integration steps done in one go at most (a clock jump beyond that is skipped)
DIAGNOSTICS_PERIOD = 1.0  # wall seconds between /diagnostics arrays
AT_REST_PERIOD = 0.05   # wall seconds between start-state odometry messages before simulated time starts (a launch
                        # waits for them: the recorder and the planner have matched the odometry)
LOCK_CHECK_PERIOD = 0.25  # lock step: wall seconds between looks at a step waiting for its command
TUNABLE = ('cmd_timeout', 'clock_timeout')   # the parameters set at runtime (the rest is the robot's)


@dataclass
class _Scanner:
    """A plant's laser: what it is, the true world it scans, its noise stream, and when it scans next."""

    spec: LaserSpec
    truth: DynamicWorld
    rng: np.random.Generator
    period: float
    next_time: float = 0.0


class PlantNode(ManagedNode):
    """Integrates one robot's model from the commands on cmd_vel; publishes odom (and trailer_pose). The constructor
    declares the parameters and builds the simulated robot (model, state, physics, scanner), which lives as long as
    the node; configure makes its publishers, subscription and timers, cleanup releases them (fastep_ros.lifecycle)."""

    def __init__(self, node_name: str = 'plant', **kwargs: Any) -> None:
        super().__init__(node_name, **kwargs)
        self.clock_guard = guard_clock(self)   # a bad /clock message is ignored, never the end of the node
        self.model_name = declare(self, 'model', 'point_mass', 'robot model: ' + ' | '.join(MODELS),
                                  constraints=' | '.join(MODELS), component='robot')
        start = declare(self, 'start', None, 'start state: [x, y] (point_mass), [x, y, theta] (diff_drive) or '
                        '[x, y, theta0, theta1] (tractor_trailer; metres, radians, map frame = odom frame at the '
                        'start)', unit='m, rad', component='robot')
        length = declare(self, 'length', 1.0, 'tractor-trailer: tractor mid-axle length L', unit='m', component='robot')
        trailer_length = declare(self, 'trailer_length', 1.0, 'tractor-trailer: trailer length Lt',
                                 unit='m', component='robot')
        hitch_offset = declare(self, 'hitch_offset', 0.0, 'tractor-trailer: hitch offset c',
                               unit='m', component='robot')
        base = PlannerParams()
        max_speed = declare(self, 'max_speed', base.max_speed, 'diff_drive: the base\'s speed limit |v|; 0 '
                            'means unlimited', constraints='>= 0', unit='m/s', component='robot')
        max_turn_rate = declare(self, 'max_turn_rate', base.max_turn_rate, 'diff_drive: the base\'s turn-rate '
                                'limit |omega|; 0 means unlimited', constraints='>= 0', unit='rad/s', component='robot')
        self.rate_hz = declare(self, 'rate_hz', 50.0, 'integration rate: fixed steps of 1/rate_hz s of the '
                               'node clock (simulated time with use_sim_time)', value_range=RATE_RANGE, unit='Hz',
                               component='node')
        odom_rate = declare(self, 'odom_rate_hz', 0.0, 'odometry messages per second of the node clock, each of the '
                            'step integrated last; 0: one per integration step. Every planner of a graph takes '
                            'every robot\'s odometry: a rate of its own (the planners\' control rate) cuts that '
                            'fan-in without coarsening the integration', value_range=(0.0, RATE_RANGE[1]),
                            unit='Hz', component='node')
        self.cmd_timeout = declare(self, 'cmd_timeout', 0.5, 'a cmd_vel acts for at most this long after it '
                                   'was sent (its stamp; for a Twist on wall time its DDS source time): stop '
                                   '(zero velocity) when no newer one came (s, node clock)', constraints='> 0',
                                   read_only=False, unit='s', component='node')
        stamped = declare(self, 'use_stamped_cmd_vel', False, 'subscribe cmd_vel as TwistStamped, not Twist',
                          component='node')
        lock_step = declare(self, 'lock_step', False, 'on simulated time: integrate each step with the command '
                            'stamped at its start, waiting for it (rate_hz must be the planner\'s control rate; '
                            'fastep-launch sets it)', component='node')
        frame_id = declare(self, 'frame_id', '', 'frame of the odometry pose; empty: <ns>/odom (REP-105; root '
                           'namespace: odom)', component='node')
        self.publish_map_to_odom = declare(self, 'publish_map_to_odom', True, 'publish map -> odom as the identity on '
                                           '/tf_static (simulated odometry does not drift); false when a '
                                           'localization node publishes it', component='node')
        declare(self, 'clock_timeout', 3.0, 'on simulated time: no /clock for this many wall '
                'seconds is a warning on /diagnostics', value_range=PERIOD_RANGE, unit='s', read_only=False,
                component='node')
        sensor = declare(self, 'sensor', None, 'a laser scanner: [range (m), fov (rad), beams, noise (m)] or with '
                         'its mount on the robot [range, fov, beams, noise, x (m), y (m), yaw (rad)] (a scenario '
                         'robot\'s `sensor`); empty: none. It scans the world of `scenario`, the truth; a mounted '
                         'one\'s scans are in <ns>/laser (base_link -> laser on /tf_static where TF is published)',
                         component='sensor')
        scenario = declare(self, 'scenario', '', 'with a sensor: the scenario file or built-in name whose true world '
                           '(every still obstacle, known or not, where it is; every mover where it is at the '
                           'integrated time) the scanner sees', component='sensor')
        seed = declare(self, 'seed', 0, 'with a sensor: the run\'s seed; the scanner\'s noise is drawn from its '
                       'stream robot_index, as fastep-sim draws it', component='sensor')
        robot_index = declare(self, 'robot_index', 0, 'with a sensor: this robot\'s index in the scenario',
                              component='sensor')
        scan_rate = declare(self, 'scan_rate_hz', 20.0, 'with a sensor: scans per second of integrated time',
                            value_range=(0.1, 1000.0), unit='Hz', component='sensor')
        dynamics = declare(self, 'dynamics', '', 'diff_drive: a base with mass, simulated by MuJoCo behind its own '
                           'controller (fastep_core/dynamics): a preset name (nominal | heavy | limited_controller | '
                           'slippery) or a YAML/JSON mapping of its fields ({preset: heavy, mass: 45}, a scenario '
                           'robot\'s `dynamics`); its controller times out commands after cmd_timeout; odom carries '
                           'its wheel odometry (it drifts). Empty: the kinematic model, integrated as commanded',
                           component='robot')
        ground_truth = declare(self, 'ground_truth_topic', '', 'with dynamics: publish the true pose on this topic '
                               '(geometry_msgs/PoseWithCovarianceStamped in map, with each odometry; a planner\'s '
                               'localization_topic); empty: not published', component='robot')

        if self.model_name not in MODELS:
            raise StartupError(f'parameter model must be one of {", ".join(MODELS)}, got {self.model_name!r}')
        check_range('rate_hz', self.rate_hz, *RATE_RANGE, ' Hz')
        if self.cmd_timeout <= 0.0:
            raise StartupError(f'parameter cmd_timeout must be > 0, got {self.cmd_timeout:g}')
        self.model: PointMass | TractorTrailer | DiffDrive
        if self.model_name == 'point_mass':
            self.model = PointMass()
            size = 2
        elif self.model_name == 'diff_drive':
            if max_speed < 0.0 or max_turn_rate < 0.0:
                raise StartupError('diff_drive needs max_speed >= 0 and max_turn_rate >= 0')
            self.model = DiffDrive(max_speed, max_turn_rate)
            size = 3
        else:
            if length <= 0.0 or trailer_length <= 0.0 or hitch_offset < 0.0:
                raise StartupError('tractor-trailer needs length > 0, trailer_length > 0, hitch_offset >= 0')
            self.model = TractorTrailer(length, trailer_length, hitch_offset)
            size = 4
        if not start:
            start = [0.0] * size
        if len(start) != size:
            raise StartupError(f'parameter start must have {size} values for {self.model_name}, got {start}')
        self.state = np.array(start, dtype=float)
        self.physics = self._physics(dynamics, seed, robot_index)
        self.scanner = self._scanner(sensor, scenario, seed, robot_index, scan_rate)

        self.frame_id = frame_id or frames.odom_frame(self.get_namespace())
        self.child_frame_id = frames.base_frame(self.get_namespace())
        self.trailer_frame_id = frames.trailer_frame(self.get_namespace())
        self.scan_frame_id = self.child_frame_id   # <ns>/laser for a scanner mounted off the reference point
        if self.scanner is not None and any(self.scanner.spec.mount):
            self.scan_frame_id = frames.frame_name(self.get_namespace(), 'laser')
        self.step = 1.0 / self.rate_hz
        self.odom_period = 1.0 / odom_rate if odom_rate > 0.0 else 0.0
        self.tick: int | None = None           # integrated time = tick * step
        self.published_tick: int | None = None  # tick of the last odometry published
        self.command = np.zeros(2)
        self.command_time: float | None = None  # node-clock time the current command was sent
        self.applied = np.zeros(2)              # command used in the last step (for the odometry twist)
        self.lock_step = bool(lock_step)
        self.command_stamp: float | None = None  # lock step: the stamp of the command held, taken while time ran
        self.waiting_since: float | None = None  # lock step: steady seconds the next step began waiting
        self.planner_gone = False                 # lock step: a step waited LOCK_WAIT for its command in vain
        self.steady = Clock(clock_type=ClockType.STEADY_TIME)
        self.cmd_type = TwistStamped if stamped else Twist
        self.ground_truth_topic = ground_truth if self.physics is not None else ''

        physics = '' if self.physics is None else f' (physics: {self.physics.dynamics.preset} base)'
        self.get_logger().info(f'{self.model_name}{physics} at {np.round(self.state, 3).tolist()}, '
                               f'integrating at {self.rate_hz:g} Hz')
        self.start_lifecycle()   # autostart: active at once (fastep_ros.lifecycle)

    # ------------------------------------------------------------------------------------------- lifecycle
    def _physics(self, text: str, seed: int, index: int) -> PhysicsPlant | None:
        """The physics plant of `dynamics` (None: kinematic); its encoder noise from the run's seed stream index."""
        try:
            dynamics = dynamics_from_text(text)
        except FastepError as exc:
            raise StartupError(f'parameter {exc}') from None
        if dynamics is None:
            return None
        if self.model_name != 'diff_drive':
            raise StartupError(f'parameter dynamics is only for model diff_drive, got {self.model_name}')
        # One timeout: the node's cmd_timeout is the controller's (a stale command is a stop it ramps).
        dynamics = replace(dynamics, cmd_timeout=self.cmd_timeout)
        return PhysicsPlant(dynamics, self.state, odometry_generator(max(seed, 0), max(index, 0)))

    def _scanner(self, sensor: list[float], source: str, seed: int, index: int, rate: float) -> _Scanner | None:
        """The laser scanner of `sensor` on the true world of `source`; None without a sensor."""
        if not sensor:
            return None
        if len(sensor) not in (4, 7):
            raise StartupError(f'parameter sensor must be [range, fov, beams, noise] or [range, fov, beams, noise, '
                               f'x, y, yaw], got {sensor}')
        if not source:
            raise StartupError('parameter scenario is required with a sensor (the world it scans)')
        if seed < 0 or index < 0:
            raise StartupError(f'parameters seed and robot_index must be >= 0, got {seed} and {index}')
        try:
            mount = (float(sensor[4]), float(sensor[5]), float(sensor[6])) if len(sensor) == 7 else (0.0, 0.0, 0.0)
            spec = LaserSpec(float(sensor[0]), float(sensor[1]), int(sensor[2]), float(sensor[3]), mount)
        except ValueError as exc:
            raise StartupError(f'parameter sensor: {exc}') from None
        try:
            scenario = load_scenario(source)
        except FastepError as exc:
            raise StartupError(str(exc)) from None
        from fastep_core.perception.belief import sensor_generator  # here: only a plant with a sensor needs scipy
        truth = DynamicWorld(scenario.world.workspace, scenario.obstacle_specs)
        return _Scanner(spec, truth, sensor_generator(seed, index), 1.0 / rate)

    def configure(self) -> None:
        """The publishers, the cmd_vel subscription, TF, the timers (integration off until activate) and the
        parameter callbacks, with the timeouts' values now (set while unconfigured too). The simulated robot, its
        state included, is the node's from its construction: a cleanup does not move it."""
        timeouts = {name: self.get_parameter(name).value for name in TUNABLE}
        self.odom_pub = self.create_publisher(Odometry, interface.ODOM, offered_qos(interface.ODOM))
        self.scan_pub = (self.create_publisher(LaserScan, interface.SCAN, qos_profile_sensor_data)
                         if self.scanner is not None else None)
        self.truth_pub = (self.create_publisher(PoseWithCovarianceStamped, self.ground_truth_topic, LATEST)
                          if self.ground_truth_topic else None)
        self.trailer_pub = (self.create_publisher(PoseStamped, interface.TRAILER_POSE,
                                                  offered_qos(interface.TRAILER_POSE))
                            if self.model_name == 'tractor_trailer' else None)
        # rclpy passes (message, MessageInfo) to a callback of two parameters (on either executor: MessageInfoCallback).
        # Taken as bytes (msg_tools.cdr): a command a lock-step tick, and a TwistStamped costs ~20 us to build.
        take_cmd_vel: Any = MessageInfoCallback(self._take_cmd_vel)
        self.cmd_sub = self.create_subscription(self.cmd_type, interface.CMD_VEL, take_cmd_vel, LATEST, raw=True)
        self.tf = TfBroadcaster(self)
        statics = [frames.static_map_to_odom(interface.MAP_FRAME, self.frame_id)] \
            if self.publish_map_to_odom and self.frame_id != interface.MAP_FRAME else []
        if self.scan_frame_id != self.child_frame_id and self.scanner is not None:
            statics.append(frames.transform_stamped(self.child_frame_id, self.scan_frame_id, self.scanner.spec.mount,
                                                    Time()))
        if statics:
            self.tf.send_static(statics)   # one message: /tf_static keeps the last one
        self.timer = self.create_timer(self.step, self.on_timer, autostart=False)   # on while active
        self.at_rest_timer = self.create_timer(AT_REST_PERIOD, self.on_at_rest_tick, clock=self.steady)
        # Lock step: a step that waits for its command is looked at again on wall time (simulated time may hold).
        self.lock_timer = self.create_timer(LOCK_CHECK_PERIOD, self.on_lock_check, clock=self.steady) \
            if self.lock_step else None
        self.sim_time = SimTimeWatch(self, self.clock_guard, timeouts['clock_timeout'])
        self.diagnostics = Diagnostics(self)
        self.diagnostics_timer = self.create_timer(DIAGNOSTICS_PERIOD, self.publish_diagnostics,
                                                   clock=Clock(clock_type=ClockType.STEADY_TIME))
        # Only the command timeout changes while running: the step is what the odometry of a group of plants
        # lines up on (stamps are whole steps), the start is the start, and the body and the topics are the robot's.
        self.dynamic = DynamicParameters(self, TUNABLE, self.apply_parameters)
        reason = self.apply_parameters(timeouts)
        if reason:
            raise StartupError(reason)

    def activate(self) -> None:
        if self.tick is not None:   # the robot stood still while inactive: integrate from now on
            self.tick = int(math.floor(self.now() / self.step + 1e-9))
        self.timer.reset()

    def deactivate(self) -> None:
        self.timer.cancel()
        self.command, self.command_time = np.zeros(2), None

    def cleanup(self, forget: bool = True) -> None:
        """Release what configure made: its timers, subscription, publishers and parameter callbacks (`forget`:
        dropped too; the simulated robot is the node's, kept)."""
        made = vars(self)
        for member in ('dynamic', 'tf', 'diagnostics'):
            if member in made:
                made[member].destroy()
        for name in ('timer', 'at_rest_timer', 'lock_timer', 'diagnostics_timer'):
            if made.get(name) is not None:
                self.destroy_timer(made[name])
        if 'cmd_sub' in made:
            self.destroy_subscription(made['cmd_sub'])
        for name in ('odom_pub', 'scan_pub', 'truth_pub', 'trailer_pub'):
            if made.get(name) is not None:
                self.destroy_publisher(made[name])
        if forget:
            for name in ('dynamic', 'tf', 'diagnostics', 'timer', 'at_rest_timer', 'lock_timer', 'diagnostics_timer',
                         'cmd_sub', 'odom_pub', 'scan_pub', 'truth_pub', 'trailer_pub', 'sim_time'):
                made.pop(name, None)

    def apply_parameters(self, changes: dict[str, Any]) -> str:
        """DynamicParameters' apply: '' when applied, else why not (nothing changed)."""
        cmd_timeout = changes.get('cmd_timeout', self.cmd_timeout)
        if cmd_timeout <= 0.0:
            return f'parameter cmd_timeout must be > 0, got {cmd_timeout:g}'
        self.cmd_timeout = cmd_timeout
        if self.physics is not None:
            self.physics.controller.dynamics = replace(self.physics.controller.dynamics, cmd_timeout=cmd_timeout)
        self.sim_time.timeout = changes.get('clock_timeout', self.sim_time.timeout)
        return ''

    # ------------------------------------------------------------------------------------------- time
    def check_clock(self) -> None:
        """use_sim_time switched: the command's time is on the other clock. From simulated time (~0) to wall time
        it looked years old (dropped: fine); from wall time to simulated time it looked sent in the far future and
        would have acted until then: it is dropped, and the robot waits for a command sent on this clock."""
        if self.sim_time.switched():
            self.get_logger().warning(f'use_sim_time is now {str(self.sim_time.active).lower()}: the last command '
                                      'is dropped')
            self.command, self.command_time = np.zeros(2), None

    def now(self) -> float:
        return self.get_clock().now().nanoseconds * 1e-9

    def locked(self) -> bool:
        """Lock step is on: asked for, and the node runs on simulated time."""
        return self.lock_step and self.sim_time.active

    def command_for(self, t: float) -> bool:
        """Lock step: may the step starting at t be integrated? Yes with the command stamped t (or later), or when
        no command will come: no planner publishes cmd_vel, or one waited LOCK_WAIT wall seconds in vain."""
        if self.command_stamp is not None and self.command_stamp >= t - STAMP_EPS:
            self.waiting_since = None
            return True
        if self.planner_gone or self.cmd_sub.get_publisher_count() == 0:
            return True
        wall = self.steady.now().nanoseconds * 1e-9
        if self.waiting_since is None:
            self.waiting_since = wall
        if wall - self.waiting_since <= LOCK_WAIT:
            return False
        self.get_logger().warning(f'lock step: no cmd_vel stamped {t:g} s after {LOCK_WAIT:g} s of wall time; '
                                  'integrating with the command held until a command comes again')
        self.planner_gone, self.waiting_since = True, None
        return True

    def advance(self, now: float) -> bool:
        """Integrate in fixed steps up to `now`; True if the state moved on."""
        target = int(math.floor(now / self.step + 1e-9))
        if self.tick is None:
            if now <= 0.0:
                return False  # simulated time has not started yet
            # In lock step the first step starts at 0, as in fastep-sim (its command is the planner's first, at 0).
            self.tick = 0 if self.locked() else target
            if self.tick == target:
                return True
        steps = target - self.tick
        if steps < 0:
            # The clock went back (restarted; fastep_ros.common's guard lets through only a confirmed one): go on
            # from the new time, or no odometry would come until the clock is back where it was.
            self.get_logger().warning(f'clock went back {-steps * self.step:g} s; integrating from the new time',
                                      throttle_duration_sec=5.0)
            self.tick = target
            return True
        if steps == 0:
            return False
        if steps > MAX_CATCH_UP:
            self.get_logger().warning(f'clock jumped {steps * self.step:g} s ahead; not integrating the gap',
                                      throttle_duration_sec=5.0)
            self.tick = target - 1
            steps = 1
        moved = False
        for _ in range(steps):
            if self.locked() and not self.command_for(self.tick * self.step):
                return moved   # the step waits for the command its planner computes at its start
            moved = True
            physics = self.physics
            if physics is not None:   # its controller holds the command until cmd_timeout after it was sent
                physics.set_time(self.tick * self.step)
                physics.step(None if self.command_time is None else self.command, self.step, self.command_time)
                self.tick += 1
                self.state = physics.state
                continue
            self.tick += 1
            t = self.tick * self.step
            command = self.command
            if self.command_time is None or t - self.command_time > self.cmd_timeout:
                command = np.zeros(2)
            self.state = self.model.integrate(self.state, command, self.step)
            self.applied = command
        return moved

    def sent_time(self, msg: Twist | TwistStamped, source_timestamp_ns: int) -> float | None:
        """When a command was sent, on this node's clock; None when that is not known (then: when it is taken).

        A TwistStamped carries it (a zero stamp means unset). For a Twist, DDS's source timestamp is the sender's
        system clock, which is this node's clock only when it does not run on simulated time.
        """
        if isinstance(msg, TwistStamped):
            stamp = convert.stamp_to_seconds(msg.header.stamp)
            return stamp if stamp > 0.0 else None
        return self.source_time(source_timestamp_ns)

    def source_time(self, source_timestamp_ns: int) -> float | None:
        """sent_time of a Twist: its DDS source timestamp where that is this node's clock."""
        clock = self.get_clock()
        on_simulated_time = isinstance(clock, ROSClock) and clock.ros_time_is_active
        if source_timestamp_ns > 0 and not on_simulated_time:
            return source_timestamp_ns * 1e-9
        return None

    # ------------------------------------------------------------------------------------------- callbacks
    def _take_cmd_vel(self, data: bytes, info: dict[str, Any]) -> None:
        """The subscription's callback: the message's bytes, and its info (with its DDS source timestamp)."""
        stamped = self.cmd_type is TwistStamped
        try:
            fields = cdr.twist_stamped_fields(data) if stamped else cdr.twist_fields(data)
        except cdr.CdrError as exc:
            self.get_logger().warning(f'ignoring cmd_vel: {exc}', throttle_duration_sec=5.0)
            return
        if fields is None:   # not little-endian CDR: rclpy reads it
            msg = deserialize_message(data, self.cmd_type)
            self.on_cmd_vel(msg, self.sent_time(msg, int(info.get('source_timestamp', 0))))
        elif stamped:
            sec, nanosec = cdr.header_stamp(data)
            stamp = sec + nanosec * 1e-9
            self.on_cmd_vel(fields, stamp if stamp > 0.0 else None)
        else:
            self.on_cmd_vel(fields, self.source_time(int(info.get('source_timestamp', 0))))

    def on_cmd_vel(self, msg: Twist | TwistStamped | tuple[float, float, float], sent: float | None = None) -> None:
        """Take a command sent at `sent` (node clock; None: now). It acts until cmd_timeout after it was sent.
        `msg` is a message or its (linear.x, linear.y, angular.z) as msg_tools.cdr reads them."""
        if not self.is_active:
            return   # an inactive robot takes no commands
        self.check_clock()
        now = self.now()
        if not self.locked():
            self.advance(now)  # the old command holds until now
        try:
            if isinstance(msg, tuple):
                command = convert.twist_values_to_command(msg[0], msg[1], msg[2], self.model_name)
            else:
                command = convert.twist_to_command(msg, self.model_name)
        except ValueError as exc:
            self.get_logger().warning(f'ignoring cmd_vel: {exc}; treating it as zero', once=True)
            command = np.zeros(2)
        if sent is not None and now - sent > self.cmd_timeout:
            self.get_logger().warning(f'cmd_vel sent {now - sent:.2f} s ago, more than cmd_timeout '
                                      f'{self.cmd_timeout:g} s: treated as zero (a late node, or clocks apart)',
                                      throttle_duration_sec=5.0)
        self.command, self.command_time = command, now if sent is None else min(sent, now)
        if self.locked():
            # The command for the step starting at its stamp; one sent while time held answers no step.
            self.command_stamp = (now if sent is None else sent) if now > 0.0 else None
            self.planner_gone = False
            self.on_timer()   # the step it was waiting for

    @quiet_at_stop
    def on_timer(self) -> None:
        self.check_clock()
        self.advance(self.now())
        # Publish when the state moved on since the last odometry, here, in on_cmd_vel or on the lock timer.
        if self.tick is not None and self.tick != self.published_tick and self.odometry_due():
            self.published_tick = self.tick
            self.publish()

    def odometry_due(self) -> bool:
        """With odom_rate_hz: the step integrated last is the first in a new odometry period (stamps stay on the
        step grid, so the odometry of several plants lines up)."""
        if not self.odom_period or self.published_tick is None or self.tick is None:
            return True
        period = self.odom_period
        return math.floor(self.tick * self.step / period + 1e-9) > math.floor(self.published_tick * self.step / period
                                                                               + 1e-9)

    @quiet_at_stop
    def on_lock_check(self) -> None:
        """Lock step, on wall time: a step still waiting for its command is integrated once LOCK_WAIT is over."""
        if self.is_active and self.waiting_since is not None:
            self.on_timer()

    @quiet_at_stop
    def on_at_rest_tick(self) -> None:
        """Before the first integration step (simulated time at 0), once this plant can hear commands: publish
        the start state, stamped 0."""
        if self.tick is not None:
            self.at_rest_timer.cancel()   # integrating: on_timer publishes from now on
        elif self.now() <= 0.0 and self.cmd_sub.get_publisher_count() > 0:
            self.publish()

    @quiet_at_stop
    def publish_diagnostics(self) -> None:
        """/diagnostics once a wall second: the integration (odometry published), the command, the clock."""
        self.check_clock()
        t = self.now()
        if self.tick is None:
            odometry = Task('odometry', DiagnosticStatus.OK, 'at rest', {'state': self.state.tolist()})
        else:
            odometry = Task('odometry', DiagnosticStatus.OK, 'integrating', {'state': self.state.tolist(),
                                                                              't': self.tick * self.step})
        if self.command_time is None:
            command = Task('cmd_vel', DiagnosticStatus.OK, 'none yet', {})
        elif t - self.command_time > self.cmd_timeout:
            why = f'none for {t - self.command_time:.2f} s (cmd_timeout {self.cmd_timeout:g} s): holding still'
            command = Task('cmd_vel', DiagnosticStatus.STALE, 'stale', {'reason': why})
        else:
            command = Task('cmd_vel', DiagnosticStatus.OK, 'fresh', {'command': self.command.tolist()})
        problem = self.sim_time.problem()
        clock = Task('clock', DiagnosticStatus.WARN if problem else DiagnosticStatus.OK,
                     'simulated time' if self.sim_time.active else 'wall time', {'reason': problem, 't': t})
        self.diagnostics.publish([odometry, command, clock])

    def publish(self) -> None:
        """Odometry (and trailer pose) of the state at the integrated time (0 before the first step)."""
        stamp = convert.seconds_to_stamp(0.0 if self.tick is None else max(0.0, self.tick * self.step))
        state = [float(v) for v in self.state]
        linear: Sequence[float]
        if self.physics is not None:   # the wheel odometry (drifting), the truth to the localizer stand-in
            if self.truth_pub is not None:
                self.truth_pub.publish(self.ground_truth(state, stamp))
            odom_pose, twist = self.physics.odometry()
            state = [float(v) for v in odom_pose]
            linear, angular = (float(twist[0]), 0.0), float(twist[1])
        elif self.model_name == 'tractor_trailer':
            assert isinstance(self.model, TractorTrailer)
            v, omega = (float(c) for c in self.applied)
            linear = (v, 0.5 * self.model.length * omega)
            angular = omega
        elif isinstance(self.model, DiffDrive):   # what the base executed: (v, omega) saturated
            v, angular = self.model.saturate(self.applied)
            linear = (v, 0.0)
        else:
            linear, angular = (float(self.applied[0]), float(self.applied[1])), 0.0
        yaw = state[2] if len(state) > 2 else 0.0
        if not all(math.isfinite(v) for v in (*state, *linear, angular)):
            # Cannot happen with finite commands, but never crash a plant.
            self.get_logger().error(f'not publishing odometry: state {state} or velocity {linear}, {angular} is '
                                    f'not finite', throttle_duration_sec=5.0)
            return
        # Sent as its bytes (msg_tools.cdr): the message convert.state_to_odometry makes, without building it.
        self.odom_pub.publish(cdr.odometry_cdr(
            (stamp.sec, stamp.nanosec), self.frame_id, self.child_frame_id, (state[0], state[1]),
            convert.yaw_quaternion(yaw), (float(linear[0]), float(linear[1])),
            float(angular)))
        trailer = None
        if self.trailer_pub is not None:
            assert isinstance(self.model, TractorTrailer)
            trailer = convert.trailer_pose(self.state, self.model.trailer_length, self.model.hitch_offset, stamp,
                                           self.frame_id)
            self.trailer_pub.publish(trailer)
        # TF only while someone reads it: what a publisher with no matched reader sends is lost anyway, and the
        # transforms cost most of this call (a lock-step tick with nobody on /tf: 16 robots' of them, for nothing).
        tf_pub = self.tf.dynamic_pub
        if tf_pub is not None and tf_pub.get_subscription_count() > 0:
            odom = convert.state_to_odometry(state, stamp, child_frame_id=self.child_frame_id,
                                             frame_id=self.frame_id, linear=linear, angular=angular)
            self.tf.send(frames.odometry_transforms(odom, trailer, self.trailer_frame_id))
        scanner = self.scanner
        if scanner is not None and self.scan_pub is not None and self.tick is not None:
            t = self.tick * self.step
            if t + 1e-9 >= scanner.next_time:
                scanner.next_time = t + scanner.period
                # The scanner where it is mounted on the robot (a point mass's frame looks along +x:
                # perception.belief.heading); a mounted one's scans are in its own frame, <ns>/laser.
                yaw = 0.0 if self.model_name == 'point_mass' else float(self.state[2])
                pose = scanner.spec.pose_on((float(self.state[0]), float(self.state[1]), yaw))
                reading = scanner.truth.scan(scanner.spec, pose, t, scanner.rng)
                self.scan_pub.publish(convert.scan_to_laser_scan(reading, stamp, self.scan_frame_id))

    @staticmethod
    def ground_truth(state: Sequence[float], stamp: Time) -> PoseWithCovarianceStamped:
        """The true pose in map, as a localizer reports it (a covariance of 1 mm and 1 mrad: it is exact)."""
        msg = PoseWithCovarianceStamped()
        msg.header.stamp = stamp
        msg.header.frame_id = interface.MAP_FRAME
        msg.pose.pose.position.x, msg.pose.pose.position.y = float(state[0]), float(state[1])
        qx, qy, qz, qw = convert.yaw_quaternion(float(state[2]))
        orientation = msg.pose.pose.orientation
        orientation.x, orientation.y, orientation.z, orientation.w = qx, qy, qz, qw
        msg.pose.covariance = [1e-6 if i in (0, 7, 14, 21, 28, 35) else 0.0 for i in range(36)]
        return msg


def main(args: Sequence[str] | None = None) -> int:
    return node_main('fastep-plant', PlantNode, args)


if __name__ == '__main__':
    raise SystemExit(main())
