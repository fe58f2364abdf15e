"""Benchmark: the planner on a robot while a neighbour sends what it should not.

    python -m benchmarks.hostile_inputs [--world open_room] [--attacks none big_map ...] [--json out.json]

Each attack is one run of the robot harness (fastep_testing.robot_harness: the planner driving a simulated base on
wall time, the base recording every command it takes) with an attacker process beside it on the same DDS domain:

- none: no attacker (the idle memory every other run is compared with);
- big_map, huge_map: the base's /map embedded in a 1000 x 1000 (2000 x 2000) grid, every cell outside the room
  occupied at random (half of them), republished every 5 s as SLAM republishes its map;
- tf_flood: map -> odom on /tf at 10 Hz (the planner takes it from TF in this run), and once the robot drives the
  same in messages of 20,000 transforms;
- many_poses: navigate_through_poses with 100,000 poses along the way to the goal;
- ended_goals: 40 navigate_through_poses goals of 10,000 poses, each cancelled at once;
- speed_limits: nav2_msgs/SpeedLimit alternating 50 % and 100 % as fast as the attacker can send them.

The attacks on the goal (many_poses, ended_goals, speed_limits) begin once the robot drives. Printed per attack:
whether the robot arrived, its true clearance, the longest gap between commands at the base and the gaps over
0.1 s (two control periods), the planner's resident memory when the goal was sent and its peak against the run
without an attacker, and the load average at the start. Targets: no gap over 0.1 s, peak memory within 2x idle.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from dataclasses import asdict
from typing import Any, Callable, Sequence

import numpy as np

ATTACKS = ('none', 'big_map', 'huge_map', 'tf_flood', 'many_poses', 'ended_goals', 'speed_limits')
PLANNER_PARAMS: dict[str, dict[str, Any]] = {'tf_flood': {'map_to_odom_from_tf': 'true'}}
MAP_PERIOD = 5.0       # s between republished maps
TF_FRAMES = 20_000
TF_RATE = 10.0         # Hz
MANY_POSES = 100_000
ENDED_GOALS, ENDED_GOAL_POSES = 40, 10_000


# --------------------------------------------------------------------------------------------- the attacker
def _node(name: str) -> tuple[Any, Any]:
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    rclpy.init()
    node = rclpy.create_node(name)
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    return node, executor


def _driving(node: Any) -> Callable[[], bool]:
    """Whether the planner's status has said it drives (after it was idle: it has taken the harness's goal)."""
    from diagnostic_msgs.msg import DiagnosticStatus

    from msg_tools.interface import STATUS, STATUS_QOS
    seen: list[str] = []
    node.create_subscription(DiagnosticStatus, '/' + STATUS, lambda m: seen.append(m.message), STATUS_QOS)
    return lambda: 'idle' in seen and seen[-1] not in ('idle', 'starting', '')


def _wait_driving(node: Any, executor: Any) -> None:
    driving = _driving(node)
    while not driving():
        executor.spin_once(timeout_sec=0.05)


def _noisy_map(node: Any, executor: Any, cells: int) -> None:
    from nav_msgs.msg import OccupancyGrid

    from msg_tools.interface import MAP, offered_qos
    got: list[OccupancyGrid] = []
    node.create_subscription(OccupancyGrid, MAP, got.append, offered_qos(MAP))
    while not got:
        executor.spin_once(timeout_sec=0.05)
    room = got[0]
    h, w = room.info.height, room.info.width
    rng = np.random.default_rng(0)
    grid = np.where(rng.random((cells, cells)) < 0.5, 100, 0).astype(np.int8)
    grid[:h, :w] = np.asarray(room.data, dtype=np.int8).reshape(h, w)
    big = OccupancyGrid()
    big.header.frame_id = room.header.frame_id
    big.info = room.info
    big.info.width = big.info.height = cells
    big.data = grid.ravel().tolist()
    pub = node.create_publisher(OccupancyGrid, MAP, offered_qos(MAP))
    while True:
        big.header.stamp = node.get_clock().now().to_msg()
        pub.publish(big)
        _spin_for(executor, MAP_PERIOD)


def _tf_flood(node: Any, executor: Any) -> None:
    from geometry_msgs.msg import TransformStamped
    from tf2_msgs.msg import TFMessage
    message = TFMessage()
    frames = []
    for k in range(TF_FRAMES):
        t = TransformStamped()
        t.header.frame_id, t.child_frame_id = ('map', 'odom') if k == 0 else ('clutter', f'clutter_{k}')
        t.transform.rotation.w = 1.0
        frames.append(t)
    message.transforms = frames
    pub = node.create_publisher(TFMessage, '/tf', 100)
    localizer = TFMessage(transforms=frames[:1])   # map -> odom alone until the robot drives, as a localizer sends it
    driving = _driving(node)
    while True:
        stamp = node.get_clock().now().to_msg()
        for t in frames:
            t.header.stamp = stamp
        pub.publish(message if driving() else localizer)
        _spin_for(executor, 1.0 / TF_RATE)


def _poses(start: Sequence[float], goal: Sequence[float], count: int) -> list[tuple[float, float]]:
    xs, ys = np.linspace(start[0], goal[0], count + 1)[1:], np.linspace(start[1], goal[1], count + 1)[1:]
    return list(zip(xs.tolist(), ys.tolist()))


def _many_poses(start: Sequence[float], goal: Sequence[float]) -> None:
    from fastep_ros.navigation_client import NavigationClient
    nav = NavigationClient()
    nav.go_through_poses(_poses(start, goal, MANY_POSES))
    while True:
        nav.is_task_complete(spin=0.5)


def _ended_goals(start: Sequence[float], goal: Sequence[float]) -> None:
    from fastep_ros.navigation_client import NavigationClient
    nav = NavigationClient()
    poses = _poses(start, goal, ENDED_GOAL_POSES)
    for _ in range(ENDED_GOALS):
        if nav.go_through_poses(poses):
            nav.cancel_task()
    while True:
        nav.is_task_complete(spin=0.5)


def _speed_limits(node: Any, executor: Any) -> None:
    from nav2_msgs.msg import SpeedLimit

    from msg_tools.interface import SPEED_LIMIT
    pub = node.create_publisher(SpeedLimit, '/' + SPEED_LIMIT, 10)
    k = 0
    while True:
        pub.publish(SpeedLimit(percentage=True, speed_limit=50.0 if k % 2 else 100.0))
        k += 1
        executor.spin_once(timeout_sec=0.001)


def _spin_for(executor: Any, seconds: float) -> None:
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        executor.spin_once(timeout_sec=min(0.05, max(end - time.monotonic(), 0.0)))


def attack(name: str, start: Sequence[float], goal: Sequence[float]) -> None:
    """Run one attack until stopped (SIGINT from the harness)."""
    if name in ('many_poses', 'ended_goals'):
        node, executor = _node('attacker')
        _wait_driving(node, executor)
        (_many_poses if name == 'many_poses' else _ended_goals)(start, goal)
        return
    node, executor = _node('attacker')
    if name == 'speed_limits':
        _wait_driving(node, executor)
    actions: dict[str, Callable[[], None]] = {
        'big_map': lambda: _noisy_map(node, executor, 1000), 'huge_map': lambda: _noisy_map(node, executor, 2000),
        'tf_flood': lambda: _tf_flood(node, executor), 'speed_limits': lambda: _speed_limits(node, executor)}
    actions[name]()


# --------------------------------------------------------------------------------------------- the runs
def run(attacks: Sequence[str], world: str, timeout: float) -> list[dict[str, Any]]:
    from fastep_testing.robot_harness import run_world
    from fastep_testing.robot_worlds import world as harness_world
    scenario = harness_world(world)
    robot = scenario.robots[0]
    rows = []
    for name in attacks:
        attacker = None if name == 'none' else [
            sys.executable, '-m', 'benchmarks.hostile_inputs', '--attack', name,
            '--start', str(robot.start[0]), str(robot.start[1]), '--goal', str(robot.goal[0]), str(robot.goal[1])]
        result = run_world(scenario, laser=True, timeout=timeout, attacker=attacker,
                           planner_params=PLANNER_PARAMS.get(name))
        rows.append({'attack': name, **asdict(result)})
        print(_line(rows[-1], rows[0] if rows[0]['attack'] == 'none' else None), flush=True)
    return rows


def _line(row: dict[str, Any], idle: dict[str, Any] | None) -> str:
    base = idle['planner_peak_rss_mb'] if idle else math.nan
    ratio = row['planner_peak_rss_mb'] / base if base and not math.isnan(base) else math.nan
    notes = '; '.join(row['notes'])
    return (f"{row['attack']:<13} arrived {str(row['arrived']):<5} clearance {row['min_clearance']:6.2f} m  "
            f"longest gap {row['longest_gap']:6.3f} s  gaps > 0.1 s {row['gaps_over_2_periods']:4d}  "
            f"RSS {row['planner_rss_mb']:6.0f} MB, peak {row['planner_peak_rss_mb']:6.0f} MB ({ratio:4.2f}x idle)  "
            f"status {row['status']!r}{'  ' + notes if notes else ''}")


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--attacks', nargs='+', choices=ATTACKS, default=list(ATTACKS))
    parser.add_argument('--world', default='open_room')
    parser.add_argument('--timeout', type=float, default=90.0, help='s per run')
    parser.add_argument('--json', help='write every run here')
    parser.add_argument('--attack', choices=ATTACKS[1:], help=argparse.SUPPRESS)   # the attacker process
    parser.add_argument('--start', nargs=2, type=float, help=argparse.SUPPRESS)
    parser.add_argument('--goal', nargs=2, type=float, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.attack:
        from rclpy.executors import ExternalShutdownException
        try:
            attack(args.attack, args.start, args.goal)
        except (KeyboardInterrupt, ExternalShutdownException):
            pass
        return 0
    attacks = args.attacks if args.attacks[0] == 'none' else ['none', *[a for a in args.attacks if a != 'none']]
    print(f'load average at the start: {" ".join(f"{v:.2f}" for v in os.getloadavg())}', flush=True)
    rows = run(attacks, args.world, args.timeout)
    if args.json:
        with open(args.json, 'w') as f:
            json.dump(rows, f, indent=1)
    return 0


if __name__ == '__main__':
    sys.exit(main())
