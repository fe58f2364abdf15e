"""fastep-plant: one simulated robot. It integrates the robot's kinematic model and publishes its odometry.

    fastep-plant --ros-args -r __ns:=/r1 -p model:=point_mass -p start:=[5.0,25.0] [-p use_sim_time:=true]

Subscribes `cmd_vel` (geometry_msgs/Twist, or TwistStamped when `use_stamped_cmd_vel` is true): for a point
mass linear.x/y are the map-frame velocity (vx, vy); for a tractor-trailer linear.x is the speed v and
angular.z the yaw rate omega. Publishes `odom` (nav_msgs/Odometry in the `map` frame, child `<ns>/base_link`)
and, for tractor-trailers, `trailer_pose` (geometry_msgs/PoseStamped, the trailer axle, yaw theta1).

Time: the model is integrated in fixed steps of 1 / rate_hz seconds of the node's clock (simulated time with
use_sim_time, wall time otherwise) up to "now", on a timer and before each new command takes effect (a
zero-order hold: a command acts from the step after it arrived). Odometry is stamped with the integrated
time, which is always a whole number of steps, so the odometry of several plants lines up. Until simulated time
has started (the clock holds time 0, or has not been heard), the plant publishes its start state stamped 0 once
every AT_REST_PERIOD wall seconds, from when its cmd_vel subscription has matched a publisher: odometry and
commands are volatile, and DDS matches the two ends of a connection each on its own (under load, seconds apart),
so this is how its planner and a launcher learn, before the run begins, that both ends of both paths are up
(docs/robustness.md, "A loaded machine").
A command older than cmd_timeout, or one that is not finite, counts as zero. Its age counts from when it was
sent, not from when this node took it, so a command that waited while the plant was descheduled does not act
for a fresh cmd_timeout after it (docs/robustness.md, "A loaded machine"): sent is the header stamp of a
TwistStamped, and for a Twist the DDS source timestamp (the sender's system clock, hence on wall time only; on
simulated time lock step holds the clock while a node is late, and a Twist's age counts from when it is taken).
"""

from __future__ import annotations

import math
from typing import Any, Sequence

import numpy as np
from geometry_msgs.msg import PoseStamped, Twist, TwistStamped
from nav_msgs.msg import Odometry
from rclpy.clock import Clock, ClockType, ROSClock
from rclpy.node import Node

from fastep_core.kinematics import PointMass, TractorTrailer
from fastep_ros.common import RATE_RANGE, StartupError, check_range, declare, guard_clock, node_main
from fastep_ros.limits import GRAPH_MODELS as MODELS  # diff_drive: not on the graph yet (limits.py)
from msg_tools import convert, interface
from msg_tools.interface import LATEST, offered_qos

__all__ = ['PlantNode', 'main']

MAX_CATCH_UP = 100_000  # integration steps done in one go at most (a clock jump beyond that is skipped)
AT_REST_PERIOD = 0.25   # wall seconds between start-state odometry messages before simulated time starts


class PlantNode(Node):
    """Integrates one robot's model from the commands on cmd_vel; publishes odom (and trailer_pose)."""

    def __init__(self, node_name: str = 'plant', **kwargs: Any) -> None:
        super().__init__(node_name, **kwargs)
        guard_clock(self)   # a bad /clock message is ignored, never the end of the node
        self.model_name = declare(self, 'model', 'point_mass', 'robot model: point_mass | tractor_trailer',
                                  constraints='point_mass | tractor_trailer')
        start = declare(self, 'start', None, 'start state: [x, y] (point_mass) or [x, y, theta0, theta1] '
                        '(tractor_trailer; metres, radians, map frame)')
        length = declare(self, 'length', 1.0, 'tractor-trailer: tractor mid-axle length L (m)')
        trailer_length = declare(self, 'trailer_length', 1.0, 'tractor-trailer: trailer length Lt (m)')
        hitch_offset = declare(self, 'hitch_offset', 0.0, 'tractor-trailer: hitch offset c (m)')
        self.rate_hz = declare(self, 'rate_hz', 50.0, 'integration rate: fixed steps of 1/rate_hz s of the '
                               'node clock (simulated time with use_sim_time)',
                               constraints=f'range [{RATE_RANGE[0]:g}, {RATE_RANGE[1]:g}]')
        self.cmd_timeout = declare(self, 'cmd_timeout', 0.5, 'a cmd_vel acts for at most this long after it '
                                   'was sent (its stamp; for a Twist on wall time its DDS source time): stop '
                                   '(zero velocity) when no newer one came (s, node clock)', constraints='> 0')
        stamped = declare(self, 'use_stamped_cmd_vel', False, 'subscribe cmd_vel as TwistStamped, not Twist')
        self.frame_id = declare(self, 'frame_id', interface.MAP_FRAME, 'frame of the odometry pose (the simulated '
                                'pose is the map pose)')

        if self.model_name not in MODELS:
            raise StartupError(f'parameter model must be one of {", ".join(MODELS)}, got {self.model_name!r}')
        check_range('rate_hz', self.rate_hz, *RATE_RANGE, ' Hz')
        if self.cmd_timeout <= 0.0:
            raise StartupError(f'parameter cmd_timeout must be > 0, got {self.cmd_timeout:g}')
        self.model: PointMass | TractorTrailer
        if self.model_name == 'point_mass':
            self.model = PointMass()
            size = 2
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

        ns = self.get_namespace().strip('/')
        self.child_frame_id = f'{ns}/base_link' if ns else 'base_link'
        self.step = 1.0 / self.rate_hz
        self.tick: int | None = None           # integrated time = tick * step
        self.published_tick: int | None = None  # tick of the last odometry published
        self.command = np.zeros(2)
        self.command_time: float | None = None  # node-clock time the current command was sent
        self.applied = np.zeros(2)              # command used in the last step (for the odometry twist)

        self.odom_pub = self.create_publisher(Odometry, interface.ODOM, offered_qos(interface.ODOM))
        self.trailer_pub = (self.create_publisher(PoseStamped, interface.TRAILER_POSE,
                                                  offered_qos(interface.TRAILER_POSE))
                            if self.model_name == 'tractor_trailer' else None)
        # rclpy passes (message, MessageInfo) to a callback of two parameters; its type hints know only one.
        take_cmd_vel: Any = self._take_cmd_vel
        self.cmd_sub = self.create_subscription(TwistStamped if stamped else Twist, interface.CMD_VEL, take_cmd_vel,
                                                LATEST)
        self.timer = self.create_timer(self.step, self.on_timer)
        self.at_rest_timer = self.create_timer(AT_REST_PERIOD, self.on_at_rest_tick,
                                               clock=Clock(clock_type=ClockType.STEADY_TIME))
        self.get_logger().info(f'{self.model_name} at {np.round(self.state, 3).tolist()}, '
                               f'integrating at {self.rate_hz:g} Hz')

    # ------------------------------------------------------------------------------------------- time
    def now(self) -> float:
        return self.get_clock().now().nanoseconds * 1e-9

    def advance(self, now: float) -> bool:
        """Integrate in fixed steps up to `now`; True if the state moved on."""
        target = int(math.floor(now / self.step + 1e-9))
        if self.tick is None:
            if now <= 0.0:
                return False  # simulated time has not started yet
            self.tick = target
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
        for _ in range(steps):
            self.tick += 1
            t = self.tick * self.step
            command = self.command
            if self.command_time is None or t - self.command_time > self.cmd_timeout:
                command = np.zeros(2)
            self.state = self.model.integrate(self.state, command, self.step)
            self.applied = command
        return True

    def sent_time(self, msg: Twist | TwistStamped, source_timestamp_ns: int) -> float | None:
        """When a command was sent, on this node's clock; None when that is not known (then: when it is taken).

        A TwistStamped carries it (a zero stamp means unset). For a Twist, DDS's source timestamp is the sender's
        system clock, which is this node's clock only when it does not run on simulated time.
        """
        if isinstance(msg, TwistStamped):
            stamp = convert.stamp_to_seconds(msg.header.stamp)
            return stamp if stamp > 0.0 else None
        clock = self.get_clock()
        on_simulated_time = isinstance(clock, ROSClock) and clock.ros_time_is_active
        if source_timestamp_ns > 0 and not on_simulated_time:
            return source_timestamp_ns * 1e-9
        return None

    # ------------------------------------------------------------------------------------------- callbacks
    def _take_cmd_vel(self, msg: Twist | TwistStamped, info: dict[str, Any]) -> None:
        """The subscription's callback: rclpy passes the message info (with its DDS source timestamp) too."""
        self.on_cmd_vel(msg, self.sent_time(msg, int(info.get('source_timestamp', 0))))

    def on_cmd_vel(self, msg: Twist | TwistStamped, sent: float | None = None) -> None:
        """Take a command sent at `sent` (node clock; None: now). It acts until cmd_timeout after it was sent."""
        now = self.now()
        self.advance(now)  # the old command holds until now
        try:
            command = convert.twist_to_command(msg, self.model_name)
        except ValueError as exc:
            self.get_logger().warning(f'ignoring cmd_vel: {exc}; treating it as zero', once=True)
            command = np.zeros(2)
        if sent is not None and now - sent > self.cmd_timeout:
            self.get_logger().warning(f'cmd_vel sent {now - sent:.2f} s ago, more than cmd_timeout '
                                      f'{self.cmd_timeout:g} s: treated as zero (a late node, or clocks apart)',
                                      throttle_duration_sec=5.0)
        self.command, self.command_time = command, now if sent is None else min(sent, now)

    def on_timer(self) -> None:
        self.advance(self.now())
        # Publish when the state moved on since the last odometry, here or in on_cmd_vel.
        if self.tick is not None and self.tick != self.published_tick:
            self.published_tick = self.tick
            self.publish()

    def on_at_rest_tick(self) -> None:
        """Before the first integration step (simulated time at 0), once this plant can hear commands: publish
        the start state, stamped 0."""
        if self.tick is not None:
            self.at_rest_timer.cancel()   # integrating: on_timer publishes from now on
        elif self.now() <= 0.0 and self.cmd_sub.get_publisher_count() > 0:
            self.publish()

    def publish(self) -> None:
        """Odometry (and trailer pose) of the state at the integrated time (0 before the first step)."""
        stamp = convert.seconds_to_stamp(0.0 if self.tick is None else max(0.0, self.tick * self.step))
        if self.model_name == 'tractor_trailer':
            assert isinstance(self.model, TractorTrailer)
            v, omega = (float(c) for c in self.applied)
            linear: Sequence[float] = (v, 0.5 * self.model.length * omega)
            angular = omega
        else:
            linear, angular = (float(self.applied[0]), float(self.applied[1])), 0.0
        try:
            odom = convert.state_to_odometry(self.state, stamp, child_frame_id=self.child_frame_id,
                                             frame_id=self.frame_id, linear=linear, angular=angular)
        except ValueError as exc:  # cannot happen with finite commands, but never crash a plant
            self.get_logger().error(f'not publishing odometry: {exc}', throttle_duration_sec=5.0)
            return
        self.odom_pub.publish(odom)
        if self.trailer_pub is not None:
            assert isinstance(self.model, TractorTrailer)
            self.trailer_pub.publish(convert.trailer_pose(self.state, self.model.trailer_length,
                                                          self.model.hitch_offset, stamp, self.frame_id))


def main(args: Sequence[str] | None = None) -> int:
    return node_main('fastep-plant', PlantNode, args)


if __name__ == '__main__':
    raise SystemExit(main())
