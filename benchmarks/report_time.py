"""Benchmark: wall time of fastep-report on a 10-minute recording of 8 robots at live rates.

    python -m benchmarks.report_time [--minutes 10] [--robots 8] [--keep FILE.mcap]

The recording is synthesised with msg_tools.mcap_io.McapWriter and the msg_tools.convert messages, at the
rates of a live graph (fastep-launch + fastep-record): per robot odom at 50 Hz (the plant's rate_hz),
cmd_vel and cost at 20 Hz (the planner's control rate), status every 5 s, waypoint and plan every 10 s; /clock
at 20 Hz; /obstacles and /map once. Robots drive circles among 12 obstacles. Then `python -m msg_tools.report`
runs on it in a fresh process (so the time includes start-up: imports, reading, deserialising, metrics and the
three figures); also timed with --no-figures.
"""

from __future__ import annotations

import argparse
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from rosgraph_msgs.msg import Clock
from std_msgs.msg import Float64

from fastep_core.geometry import Circle
from fastep_core.world import World
from msg_tools import convert
from msg_tools.interface import offered_qos_profiles
from msg_tools.mcap_writer import McapWriter

ROOT = Path(__file__).resolve().parents[1]


def synthesise(path: Path, minutes: float, robots: int) -> int:
    world = World.from_obstacles([0, 0, 50, 50], [Circle((5.0 + 8.0 * (k % 6), 12.0 + 26.0 * (k // 6)), 1.5)
                                                  for k in range(12)])
    end = int(minutes * 60 * 1000)  # ms
    with McapWriter(path) as w:
        def put(topic: str, msg: object, ms: int) -> None:
            w.write(topic, msg, ms * 1_000_000, qos=offered_qos_profiles(topic))
        stamp0 = convert.seconds_to_stamp(0.0)
        put('/obstacles', convert.obstacles_to_marker_array(world.obstacle_list, stamp0), 0)
        put('/map', convert.world_to_occupancy_grid(world, 0.1, stamp0), 0)
        for k in range(robots):
            put(f'/r{k}/goal_pose', convert.point_to_pose_stamped((25.0, 25.0), stamp0), 0)
        for ms in range(0, end + 1, 10):  # 100 Hz base tick
            t = ms / 1000.0
            stamp = convert.seconds_to_stamp(t)
            if ms % 50 == 0:
                put('/clock', Clock(clock=stamp), ms)
            for k in range(robots):
                ns = f'/r{k}'
                angle = 0.05 * t + k
                x, y = 25.0 + 15.0 * math.cos(angle), 25.0 + 15.0 * math.sin(angle)
                if ms % 20 == 0:
                    put(f'{ns}/odom', convert.state_to_odometry((x, y), stamp, linear=(-0.75 * math.sin(angle),
                                                                0.75 * math.cos(angle))), ms)
                if ms % 50 == 0:
                    put(f'{ns}/cmd_vel', convert.command_to_twist((-0.75 * math.sin(angle), 0.75 * math.cos(angle))),
                        ms)
                    put(f'{ns}/cost', Float64(data=abs(math.sin(t))), ms)
                if ms % 5000 == 0:
                    put(f'{ns}/status', convert.make_status(ns, 'avoiding', 'ok', {
                        'reason': 'stepping around an obstacle', 'activations': ms // 5000, 'goal': (25.0, 25.0),
                        'algorithm': 'fastep', 't': t}), ms)
                if ms % 10000 == 0:
                    put(f'{ns}/waypoint', convert.point_to_pose_stamped((x, y), stamp), ms)
                    put(f'{ns}/plan', convert.waypoints_to_path([(x, y), (25.0, 25.0)], stamp), ms)
        return w.message_count


def timed(cmd: list[str]) -> float:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(x for x in (str(ROOT), os.environ.get('PYTHONPATH', '')) if x))
    start = time.perf_counter()
    subprocess.run(cmd, env=env, cwd=ROOT, check=True, stdout=subprocess.DEVNULL)
    return time.perf_counter() - start


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument('--minutes', type=float, default=10.0)
    p.add_argument('--robots', type=int, default=8)
    p.add_argument('--keep', type=Path, help='also keep the synthesised recording here')
    args = p.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        path = args.keep or Path(tmp) / 'ten_minutes.mcap'
        start = time.perf_counter()
        count = synthesise(path, args.minutes, args.robots)
        made = time.perf_counter() - start
        print(f'synthesised {path.name}: {args.minutes:g} min, {args.robots} robots, {count} messages, '
              f'{path.stat().st_size / 1e6:.1f} MB in {made:.1f} s')
        report = [sys.executable, '-m', 'msg_tools.report', str(path), '--out', str(Path(tmp) / 'report')]
        full = timed(report)
        bare = timed(report + ['--no-figures'])
        print(f'fastep-report: {full:.1f} s with the three figures, {bare:.1f} s for report.json only')


if __name__ == '__main__':
    main()
