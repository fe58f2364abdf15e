"""A simulated differential-drive base on wall time, as a robot's driver would be: the robot harness's plant.

    python -m fastep_testing.robot_harness base --ros-args -p scenario:=world.yaml -p record:=base.npz

Unlike fastep-plant (lock step, one clock for the graph), nothing waits for anyone: it integrates the unicycle at
`rate_hz` on the steady clock with the last cmd_vel (geometry_msgs/Twist: linear.x, angular.z) applied as it
is, no limits (a base does what it is told; zero after `cmd_timeout` without a command, as ros2_control's
diff_drive_controller does), publishes `odom` (`odom` -> `base_link`, the pose in map coordinates: map -> odom
is the identity) at `odom_rate_hz` and a laser's LaserScan on `scan` (base_link, or <ns>/laser for a laser at
`laser_mount` off the centre, or `laser_frame`; base_link -> it on /tf_static with `laser_tf`) at `scan_rate_hz`,
both stamped
with the system clock, ray-cast on the TRUE world of `scenario` (fastep_core.dynamic_world), and /map once,
latched, rasterised at `map_resolution` from the world the planner may know (`known: false` obstacles left out).
It records what it took and did: each command's arrival (steady seconds) and value, and its state and applied
velocity at every integration step, written to `record` (numpy .npz) when the node stops.

A scenario robot with `dynamics` (docs/scenarios.md) is a base with mass instead (fastep_core/dynamics: MuJoCo
behind its own diff_drive_controller, which times commands out after `cmd_timeout`): the odometry's twist is its
wheel encoders', its pose the true one (a localizer's job, done perfectly), and the record's velocity the true
body-frame (v, omega).
"""

from __future__ import annotations

import math
import time
from typing import Any, Sequence

import numpy as np
from geometry_msgs.msg import Twist
from nav_msgs.msg import OccupancyGrid, Odometry
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from rclpy.qos import qos_profile_sensor_data
from sensor_msgs.msg import LaserScan

from fastep_core.dynamic_world import DynamicWorld, map_generator
from fastep_core.dynamics import PhysicsPlant
from fastep_core.errors import FastepError
from fastep_core.kinematics.diff_drive import DiffDrive
from fastep_core.scenario import load_scenario
from fastep_core.sensing.laser import LaserSpec
from fastep_ros.common import StartupError, declare, node_main, quiet_at_stop
from msg_tools import cdr, convert, frames, interface
from msg_tools.interface import LATEST, offered_qos

__all__ = ['DEFAULT_LASER', 'BaseNode', 'main']

DEFAULT_LASER = [10.0, 1.5 * math.pi, 720.0, 0.01]   # range (m), fov (rad: 270 deg), beams, noise (m)


class BaseNode(Node):
    """The wall-time base (module docstring): cmd_vel in; odom, scan and a latched /map out; a record at the end."""

    def __init__(self, node_name: str = 'base', **kwargs: Any) -> None:
        super().__init__(node_name, **kwargs)
        source = declare(self, 'scenario', '', 'scenario file or built-in name: the true world and the map')
        start = declare(self, 'start', None, '[x, y, theta] (map = odom frame); empty: the scenario\'s first robot')
        rate = declare(self, 'rate_hz', 100.0, 'integration steps per second (steady clock)', value_range=(1, 1e4))
        odom_rate = declare(self, 'odom_rate_hz', 50.0, 'odometry messages per second', value_range=(1, 1e3))
        scan_rate = declare(self, 'scan_rate_hz', 20.0, 'laser scans per second; 0: no laser',
                            value_range=(0, 1e3))
        laser = declare(self, 'laser', DEFAULT_LASER, 'the laser: [range (m), fov (rad), beams, noise (m)]')
        mount = declare(self, 'laser_mount', [0.0, 0.0, 0.0], 'where the laser sits on the base: [x (m), y (m), '
                        'yaw (rad)] in base_link; off the centre its scans are in <ns>/laser')
        laser_frame = declare(self, 'laser_frame', '', 'the frame its scans are in; empty: base_link, or <ns>/laser '
                              'off the centre')
        laser_tf = declare(self, 'laser_tf', False, 'publish base_link -> the scans\' frame (at laser_mount) on '
                           '/tf_static, as robot_state_publisher does')
        resolution = declare(self, 'map_resolution', 0.05, '/map cell size (m)', constraints='> 0')
        seed = declare(self, 'seed', 0, 'seed of the laser noise and of the map errors')
        self.cmd_timeout = declare(self, 'cmd_timeout', 0.5, 'no cmd_vel for this long (s): the base stops',
                                   constraints='> 0')
        self.record_path = declare(self, 'record', '', 'the .npz file written when the node stops; empty: none')
        try:
            scenario = load_scenario(source)
            self.spec = LaserSpec(float(laser[0]), float(laser[1]), int(laser[2]), float(laser[3]),
                                  (float(mount[0]), float(mount[1]), float(mount[2])))
        except (FastepError, ValueError, IndexError, TypeError) as exc:
            raise StartupError(f'robot base: {exc}') from None
        self.state = np.array(start or scenario.robots[0].start, dtype=float)
        if self.state.shape != (3,):
            raise StartupError(f'parameter start must be [x, y, theta], got {self.state.tolist()}')
        self.truth = DynamicWorld(scenario.world.workspace, scenario.obstacle_specs)
        known = self.truth.planner_map(map_generator(seed)).world
        self.rng = np.random.default_rng(seed)
        self.model = DiffDrive(0.0, 0.0)   # 0: unlimited, the command as it is
        self.step = 1.0 / rate
        self.steady = Clock(clock_type=ClockType.STEADY_TIME)
        self.t = time.monotonic()          # integrated up to (steady seconds)
        dynamics = scenario.robots[0].dynamics
        self.physics = None if dynamics is None else \
            PhysicsPlant(dynamics, self.state, np.random.default_rng(seed), start_time=self.t)
        self.command = np.zeros(2)
        self.command_time = -math.inf
        self.commands: list[tuple[float, float, float]] = []          # (arrival, v, omega)
        self.track: list[tuple[float, ...]] = [(self.t, *self.state, 0.0, 0.0)]   # (t, x, y, theta, v, omega)
        self.scan_cpu: list[float] = []                                # seconds per cast and publish
        self.odom_frame = frames.odom_frame(self.get_namespace())
        self.base_frame = frames.base_frame(self.get_namespace())
        self.scan_frame = laser_frame or \
            (frames.frame_name(self.get_namespace(), 'laser') if any(self.spec.mount) else self.base_frame)
        if laser_tf:
            from fastep_ros.live_tf import TfBroadcaster
            self.tf = TfBroadcaster(self)
            self.tf.send_static([frames.transform_stamped(self.base_frame, self.scan_frame, self.spec.mount,
                                                          self.get_clock().now().to_msg())])

        self.odom_pub = self.create_publisher(Odometry, interface.ODOM, offered_qos(interface.ODOM))
        self.scan_pub = self.create_publisher(LaserScan, interface.SCAN, qos_profile_sensor_data)
        self.map_pub = self.create_publisher(OccupancyGrid, interface.MAP, offered_qos(interface.MAP))
        self.create_subscription(Twist, interface.CMD_VEL, self.on_cmd_vel, LATEST)
        self.map_pub.publish(convert.world_to_occupancy_grid(known, resolution, self.get_clock().now().to_msg(),
                                                             interface.MAP_FRAME))
        self.create_timer(self.step, self.on_step, clock=self.steady)
        self.create_timer(1.0 / odom_rate, self.on_odom, clock=self.steady)
        if scan_rate > 0.0:
            self.create_timer(1.0 / scan_rate, self.on_scan, clock=self.steady)

    def advance(self, now: float) -> None:
        """Integrate from self.t up to `now` in steps of at most 1 / rate_hz, recording each."""
        while self.t < now - 1e-9:
            dt = min(self.step, now - self.t)
            stale = self.t - self.command_time > self.cmd_timeout
            command = np.zeros(2) if stale else self.command
            if self.physics is None:
                self.state = self.model.integrate(self.state, command, dt)
                self.t += dt
                self.track.append((self.t, *self.state, *command))
                continue
            self.physics.step(self.command, dt, self.command_time)   # its controller times the command out
            self.state = self.physics.state
            self.t += dt
            self.track.append((self.t, *self.state, *self.physics.body_twist()))

    def on_cmd_vel(self, msg: Twist) -> None:
        now = time.monotonic()
        self.advance(now)   # the command before holds until now
        v, omega = float(msg.linear.x), float(msg.angular.z)
        if not (math.isfinite(v) and math.isfinite(omega)):
            v = omega = 0.0
        self.commands.append((now, v, omega))
        self.command, self.command_time = np.array([v, omega]), now

    @quiet_at_stop
    def on_step(self) -> None:
        self.advance(time.monotonic())

    @quiet_at_stop
    def on_odom(self) -> None:
        self.advance(time.monotonic())
        stamp = self.get_clock().now().to_msg()
        x, y, theta, v, omega = self.track[-1][1:]
        if self.physics is not None:
            v, omega = (float(c) for c in self.physics.measured_velocity())
        self.odom_pub.publish(cdr.odometry_cdr((stamp.sec, stamp.nanosec), self.odom_frame, self.base_frame, (x, y),
                                               convert.yaw_quaternion(theta), (v, 0.0), omega))

    @quiet_at_stop
    def on_scan(self) -> None:
        began = time.thread_time()
        self.advance(time.monotonic())
        stamp = self.get_clock().now().to_msg()
        pose = self.spec.pose_on((float(self.state[0]), float(self.state[1]), float(self.state[2])))
        scan = self.truth.scan(self.spec, pose, self.t, self.rng)
        self.scan_pub.publish(convert.scan_to_laser_scan(scan, stamp, self.scan_frame))
        self.scan_cpu.append(time.thread_time() - began)

    def destroy_node(self) -> None:
        if self.record_path:
            np.savez(self.record_path, commands=np.array(self.commands, dtype=float).reshape(-1, 3),
                     track=np.array(self.track, dtype=float), scan_cpu=np.array(self.scan_cpu, dtype=float))
        super().destroy_node()


def main(args: Sequence[str] | None = None) -> int:
    return node_main('robot-base', BaseNode, args)
