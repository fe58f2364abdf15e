"""`fastep-sim --mcap`: an in-process run written with the same topics, types and QoS as a live recording.

Why: report, replay, Foxglove and `ros2 bag play` should not care whether a run came from the live graph or the
in-process simulator, and offline runs are fast and reproducible. So this writes what the live nodes publish
(msg_tools/interface.py, converted by msg_tools.convert): per robot odom (every step and the start pose at t = 0),
cmd_vel and cost (every step), waypoint and plan (when they change), status (when level, mode or reason change, with
the planner's values plus robot_radius), trailer_pose, goal_pose at t = 0; /obstacles and /map at t = 0 and /clock
every step; TF as in docs/frames.md (/tf_static map -> <name>/odom, the identity; /tf odom -> base_link, trailer_link).
Time: log_time = publish_time = header.stamp = simulated seconds since the start (t = 0 is the ROS time 0), as a live
graph on simulated time records; a decision at t (cmd_vel, cost, waypoint, plan, status) is logged at t, the odometry
it leads to at t + dt, as the live planner and plant do. Messages are buffered and written in log-time order at the
end. A metadata record `fastep` holds what the topics do not: scenario, algorithm, seed, each robot's model and radius.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import IO, Any

import numpy as np
from geometry_msgs.msg import Twist
from rosgraph_msgs.msg import Clock
from std_msgs.msg import Float64

from fastep_core.planning.navigator import Mode
from fastep_core.scenario import RobotSpec, Scenario
from fastep_core.simulator import Run, Tick, simulate
from msg_tools import convert, frames
from msg_tools.footprint import base_frame, circle_footprint, polygon_footprint
from msg_tools.interface import (
    CLOCK,
    CMD_VEL,
    COST,
    FOOTPRINT,
    GOAL_POSE,
    MAP,
    MAP_FRAME,
    METADATA_NAME,
    OBSTACLES,
    ODOM,
    PLAN,
    STATUS,
    TRAILER_POSE,
    WAYPOINT,
    offered_qos_profiles,
    robot_topic,
    scenario_metadata,
)
from msg_tools.mcap_writer import DEFAULT_CHUNK_SIZE, McapWriter

__all__ = ['SimRecorder', 'record_run']



def _ns(t: float) -> int:
    return int(round(t * 1e9))


@dataclass
class _RobotState:
    spec: RobotSpec
    target: tuple[float, ...] | None = None
    plan: tuple[tuple[float, float], ...] | None = None
    status: tuple[str, str, str] | None = None
    last_t: float = 0.0


@dataclass
class SimRecorder:
    """Observer for fastep_core.simulator.simulate that collects the messages of a live recording."""

    scenario: Scenario
    algorithm: str
    seed: int
    items: list[tuple[int, int, str, Any]] = field(default_factory=list)  # (log_time, order, topic, message)
    robots: dict[str, _RobotState] = field(default_factory=dict)
    last_clock: int = -1

    def __post_init__(self) -> None:
        world = self.scenario.world
        stamp = convert.seconds_to_stamp(0.0)
        self.dt = self.scenario.planner.dt
        self._clock(0.0)
        self._add(0.0, OBSTACLES, convert.obstacles_to_marker_array(world.obstacle_list, stamp, MAP_FRAME))
        # The automatic cell size, as fastep-map's default: 0.1 m, coarser beyond 4 million cells.
        self._add(0.0, MAP, convert.world_to_occupancy_grid(world, None, stamp, MAP_FRAME))
        for spec in self.scenario.robots:
            state = _RobotState(spec)
            self.robots[spec.name] = state
            self._add(0.0, frames.TF_STATIC, frames.tf_message_cdr(
                [frames.static_map_to_odom(MAP_FRAME, frames.odom_frame(spec.name), stamp)]))
            self._add(0.0, robot_topic(spec.name, GOAL_POSE),
                      convert.point_to_pose_stamped(spec.goal, stamp, MAP_FRAME))
            self._odom(spec, 0.0, np.array(spec.start, dtype=float), np.zeros(2))
            frame = base_frame(f'/{spec.name}')   # as each live planner announces its robot: its outline, or circle
            self._add(0.0, robot_topic(spec.name, FOOTPRINT),
                      circle_footprint(spec.radius, frame, stamp) if spec.footprint is None else
                      polygon_footprint(spec.footprint.vertices, frame, stamp))
            goal = (float(spec.goal[0]), float(spec.goal[1]))
            state.plan = (goal,)
            self._add(0.0, robot_topic(spec.name, PLAN), convert.waypoints_to_path([goal], stamp, MAP_FRAME))

    # ------------------------------------------------------------------------------------------- helpers
    def _add(self, t: float, topic: str, message: Any) -> None:
        self.items.append((_ns(t), len(self.items), topic, message))

    def _clock(self, t: float) -> None:
        ns = _ns(t)
        if ns > self.last_clock:
            self.last_clock = ns
            self._add(t, CLOCK, Clock(clock=convert.seconds_to_stamp(t)))

    def _odom(self, spec: RobotSpec, t: float, state: np.ndarray, command: np.ndarray) -> None:
        stamp = convert.seconds_to_stamp(t)
        if spec.model == 'tractor_trailer':
            v, omega = float(command[0]), float(command[1])
            linear: tuple[float, float] = (v, 0.5 * spec.length * omega)
            angular = omega
        elif spec.model == 'diff_drive':   # body-frame twist: the axle midpoint moves along the heading
            linear, angular = (float(command[0]), 0.0), float(command[1])
        else:
            linear, angular = (float(command[0]), float(command[1])), 0.0
        odom_frame = frames.odom_frame(spec.name)
        odom = convert.state_to_odometry(state, stamp, child_frame_id=frames.base_frame(spec.name),
                                         frame_id=odom_frame, linear=linear, angular=angular)
        self._add(t, robot_topic(spec.name, ODOM), odom)
        trailer = None
        if spec.model == 'tractor_trailer':
            trailer = convert.trailer_pose(state, spec.trailer_length, spec.hitch_offset, stamp, odom_frame)
            self._add(t, robot_topic(spec.name, TRAILER_POSE), trailer)
        self._add(t, frames.TF, frames.tf_message_cdr(
            frames.odometry_transforms(odom, trailer, frames.trailer_frame(spec.name))))

    def _status(self, robot: _RobotState, t: float, mode: str, reason: str, activations: int,
                waypoint: Any, cost: float) -> None:
        level = 'error' if mode == Mode.FAILED.value else 'ok'
        key = (level, mode, reason)
        if key == robot.status:
            return
        robot.status = key
        spec = robot.spec
        others = ' '.join(sorted(r for r in self.robots if r != spec.name))
        values = {'reason': reason, 'activations': activations, 'waypoint': waypoint, 'goal': spec.goal,
                  'cost': float(cost), 'others': others, 'algorithm': self.algorithm, 't': t,
                  'robot_radius': float(spec.radius)}
        self._add(t, robot_topic(spec.name, STATUS), convert.make_status(f'/{spec.name}', mode, level, values))

    def _plan(self, robot: _RobotState, t: float, points: list[tuple[float, float]]) -> None:
        key = tuple(points)
        if key != robot.plan:
            robot.plan = key
            self._add(t, robot_topic(robot.spec.name, PLAN),
                      convert.waypoints_to_path(points, convert.seconds_to_stamp(t), MAP_FRAME))

    # ------------------------------------------------------------------------------------------- observer
    def observe(self, tick: Tick) -> None:
        """Called by simulate() after each step of one robot: tick.t is the time after the step."""
        robot = self.robots[tick.name]
        spec, nav = robot.spec, tick.navigator
        t = tick.t
        decided = max(0.0, round(t - self.dt, 9))
        stamp = convert.seconds_to_stamp(decided)
        # What the planner published at the decision time...
        self._add(decided, robot_topic(spec.name, CMD_VEL), convert.command_to_twist(tick.command, spec.model))
        self._add(decided, robot_topic(spec.name, COST), Float64(data=float(nav.cost)))
        target = nav.target
        key = None if target is None else tuple(float(v) for v in target)
        if key is not None and key != robot.target:
            self._add(decided, robot_topic(spec.name, WAYPOINT),
                      convert.point_to_pose_stamped(key, stamp, MAP_FRAME))
        robot.target = key
        goal = (float(spec.goal[0]), float(spec.goal[1]))
        self._plan(robot, decided, [(float(p[0]), float(p[1])) for p in nav.plan] + [goal])
        self._status(robot, decided, nav.mode.value, nav.reason, nav.activations, nav.waypoint, nav.cost)
        # ... and what the plant published after the step.
        self._clock(t)
        self._odom(spec, t, tick.state, tick.command)
        robot.last_t = t

    def finish(self, run: Run) -> None:
        """Final status (arrived / failed), plan and a stop command of every robot, at the time it ended."""
        for result in run.robots:
            robot = self.robots[result.name]
            t = result.sim_time if result.sim_time is not None else robot.last_t
            mode, _, reason = result.status.partition(': ')
            goal = (float(robot.spec.goal[0]), float(robot.spec.goal[1]))
            self._plan(robot, t, [(float(w[0]), float(w[1])) for w in result.waypoints] + [goal])
            self._status(robot, t, mode, reason, result.activations, None, 0.0)
            self._add(t, robot_topic(result.name, CMD_VEL), Twist())
            self._add(t, robot_topic(result.name, COST), Float64(data=0.0))

    def write(self, output: str | os.PathLike[str] | IO[bytes], chunk_size: int = DEFAULT_CHUNK_SIZE) -> int:
        """Write the collected messages in log-time order; return how many."""
        with McapWriter(output, chunk_size=chunk_size) as writer:
            meta = scenario_metadata(self.scenario)
            meta.update(algorithm=self.algorithm, seed=str(self.seed), source='fastep-sim',
                        time_base='simulated seconds since the start of the run')
            writer.add_metadata(METADATA_NAME, meta)
            for log_time, _, topic, message in sorted(self.items, key=lambda item: item[:2]):
                if topic == frames.TF or topic == frames.TF_STATIC:
                    writer.write(topic, message, log_time, type_name=frames.TF_TYPE,
                                 qos=frames.TF_QOS if topic == frames.TF else frames.TF_STATIC_QOS)
                else:
                    writer.write(topic, message, log_time, qos=offered_qos_profiles(topic))
            return writer.message_count


def record_run(scenario: Scenario, algorithm: str, seed: int,
               output: str | os.PathLike[str] | IO[bytes]) -> tuple[Run, int]:
    """Simulate one run and write it as MCAP; returns the run and the number of messages written."""
    recorder = SimRecorder(scenario, algorithm, seed)
    run = simulate(scenario, algorithm, seed, observer=recorder.observe)
    recorder.finish(run)
    return run, recorder.write(output)
