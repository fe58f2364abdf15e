"""Benchmark: the CPU fastep-foxglove costs while N robots publish 50 Hz odometry and a Foxglove client watches.

    python -m benchmarks.foxglove_load [--robots 2,16] [--seconds 30] [--odom-rate 50] [--scene-rate 10]
    python -m benchmarks.foxglove_load --launch case_study_1 [--rtf 5]

For each N, on an isolated DDS domain: a synthetic graph publishing N robots' odometry (plus plans, waypoints
and the latched obstacles), fastep-foxglove, and for comparison a plain callback subscriber of the same topics.
A WebSocket client here subscribes to every channel fastep-foxglove advertises. After a 5 s warm-up, the CPU
time of each process (/proc) over --seconds, as a percentage of one core, with the load average.

--launch SCENARIO: fastep-foxglove's CPU during `fastep-launch SCENARIO --rtf X --foxglove PORT` with the same
client watching.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

from fastep_testing.graph import free_domain, isolated_env, stop_process

ROOT = Path(__file__).resolve().parents[1]
WARM_UP = 5.0


def cpu_seconds(pid: int) -> float:
    with open(f'/proc/{pid}/stat') as f:
        fields = f.read().rsplit(')', 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf('SC_CLK_TCK')


# ----------------------------------------------------------------------------------------------- child modes

def publish(robots: int, rate: float) -> None:
    """The synthetic graph: N robots' odometry at `rate` Hz, plans and waypoints at 1 Hz, latched obstacles."""
    import rclpy
    from geometry_msgs.msg import PoseStamped
    from nav_msgs.msg import Odometry
    from nav_msgs.msg import Path as PathMsg
    from visualization_msgs.msg import MarkerArray

    from fastep_core.scenario import load_scenario
    from msg_tools import convert, interface

    rclpy.init()
    node = rclpy.create_node('synthetic_graph')
    world = load_scenario('table2_s2').world
    node.create_publisher(MarkerArray, interface.OBSTACLES, interface.LATCHED).publish(
        convert.obstacles_to_marker_array(world.obstacle_list))
    names = [f'r{k + 1}' for k in range(robots)]
    odom = {n: node.create_publisher(Odometry, interface.robot_topic(n, interface.ODOM), interface.RELIABLE)
            for n in names}
    plans = {n: node.create_publisher(PathMsg, interface.robot_topic(n, interface.PLAN), interface.RELIABLE)
             for n in names}
    waypoints = {n: node.create_publisher(PoseStamped, interface.robot_topic(n, interface.WAYPOINT),
                                          interface.RELIABLE) for n in names}
    ticks = [0]

    def on_tick() -> None:
        ticks[0] += 1
        t = ticks[0] / rate
        stamp = convert.seconds_to_stamp(t)
        for k, n in enumerate(names):
            phase = 2.0 * math.pi * k / robots + 0.1 * t
            x, y = 25.0 + 20.0 * math.cos(phase), 25.0 + 20.0 * math.sin(phase)
            odom[n].publish(convert.state_to_odometry([x, y], stamp, linear=(1.0, 0.0)))
            if ticks[0] % int(rate) == 0:
                plan = [(x + 2.0 * j, y + 1.0 * j) for j in range(1, 8)]
                plans[n].publish(convert.waypoints_to_path(plan, stamp))
                waypoints[n].publish(convert.point_to_pose_stamped(plan[0], stamp))

    node.create_timer(1.0 / rate, on_tick)
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, rclpy.executors.ExternalShutdownException):
        pass


def listen(robots: int) -> None:
    """The comparison: every odometry message through an executor callback (keep-last 1)."""
    import rclpy
    from nav_msgs.msg import Odometry

    from msg_tools import interface

    rclpy.init()
    node = rclpy.create_node('callback_listener')
    count = [0]

    def on_odom(msg: Any) -> None:
        count[0] += 1

    for k in range(robots):
        node.create_subscription(Odometry, interface.robot_topic(f'r{k + 1}', interface.ODOM), on_odom,
                                 interface.LATEST)
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, rclpy.executors.ExternalShutdownException):
        pass


# ----------------------------------------------------------------------------------------------- the client

class Watcher(threading.Thread):
    """A Foxglove client: subscribes to every advertised channel, counts messages and bytes."""

    def __init__(self, port: int) -> None:
        super().__init__(daemon=True)
        self.port = port
        self.messages = 0
        self.bytes = 0
        self.channels: set[str] = set()
        self.stop = threading.Event()

    def run(self) -> None:
        from websockets.exceptions import ConnectionClosed
        try:
            self._watch()
        except ConnectionClosed:   # the server stopped first (a launch that ended)
            pass

    def _watch(self) -> None:
        from websockets.sync.client import connect
        end = time.monotonic() + 60.0
        while True:
            try:
                ws = connect(f'ws://127.0.0.1:{self.port}', subprotocols=['foxglove.sdk.v1'])
                break
            except OSError:
                if time.monotonic() > end:
                    raise
                time.sleep(0.2)
        with ws:
            while not self.stop.is_set():
                try:
                    frame = ws.recv(timeout=0.5)
                except TimeoutError:
                    continue
                if isinstance(frame, str):
                    doc = json.loads(frame)
                    if doc['op'] == 'advertise':
                        new = [c for c in doc['channels'] if c['topic'] not in self.channels]
                        self.channels.update(c['topic'] for c in new)
                        ws.send(json.dumps({'op': 'subscribe', 'subscriptions': [
                            {'id': c['id'], 'channelId': c['id']} for c in new]}))
                else:
                    self.messages += 1
                    self.bytes += len(frame)


def _free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
        probe.bind(('127.0.0.1', 0))
        return int(probe.getsockname()[1])


def measure(robots: int, seconds: float, odom_rate: float, scene_rate: float) -> dict[str, Any]:
    env = isolated_env(free_domain(), Path('/tmp') / f'foxglove_load_{os.getpid()}')
    port = _free_port()
    me = [sys.executable, '-m', 'benchmarks.foxglove_load']
    procs = {
        'graph': subprocess.Popen([*me, '--publish', str(robots), '--odom-rate', str(odom_rate)], env=env,
                                  cwd=ROOT, stdin=subprocess.DEVNULL),
        'fastep-foxglove': subprocess.Popen(
            [sys.executable, '-m', 'fastep_ros.foxglove_bridge', '--ros-args', '-p', f'port:={port}',
             '-p', f'scene_rate_hz:={scene_rate}', '--log-level', 'warn'], env=env, cwd=ROOT,
            stdin=subprocess.DEVNULL),
        'callback listener': subprocess.Popen([*me, '--listen', str(robots)], env=env, cwd=ROOT,
                                              stdin=subprocess.DEVNULL),
    }
    watcher = Watcher(port)
    try:
        watcher.start()
        time.sleep(WARM_UP)
        cpu0 = {name: cpu_seconds(p.pid) for name, p in procs.items()}
        messages0, bytes0, wall0 = watcher.messages, watcher.bytes, time.perf_counter()
        own0 = time.process_time()
        time.sleep(seconds)
        wall = time.perf_counter() - wall0
        cpu = {name: cpu_seconds(p.pid) - cpu0[name] for name, p in procs.items()}
        out = {'robots': robots, 'wall_s': round(wall, 2),
               'cpu_percent': {name: round(100.0 * c / wall, 1) for name, c in cpu.items()},
               'client_cpu_percent': round(100.0 * (time.process_time() - own0) / wall, 1),
               'client_messages_per_s': round((watcher.messages - messages0) / wall, 1),
               'client_kbytes_per_s': round((watcher.bytes - bytes0) / wall / 1e3, 1),
               'channels': sorted(watcher.channels), 'load_average': os.getloadavg()}
    finally:
        watcher.stop.set()
        watcher.join(timeout=5.0)   # the client first: a server that goes away under it ends its thread in an error
        for p in procs.values():
            stop_process(p)
    return out


def measure_launch(scenario: str, rtf: float) -> dict[str, Any]:
    env = isolated_env(free_domain(), Path('/tmp') / f'foxglove_load_{os.getpid()}')
    port = _free_port()
    load = os.getloadavg()
    start = time.perf_counter()
    launch = subprocess.Popen([sys.executable, '-m', 'fastep_ros.launch', scenario, '--rtf', str(rtf),
                               '--foxglove', str(port), '--no-progress'], env=env, cwd=ROOT,
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, stdin=subprocess.DEVNULL)
    watcher = Watcher(port)
    pid: int | None = None
    samples: list[tuple[float, float]] = []
    try:
        watcher.start()
        while launch.poll() is None:
            if pid is None:
                kids = subprocess.run(['ps', '-o', 'pid=,args=', '--ppid', str(launch.pid)], capture_output=True,
                                      text=True).stdout
                pid = next((int(line.split()[0]) for line in kids.splitlines() if 'foxglove_bridge' in line), None)
            if pid is not None:
                try:
                    samples.append((time.perf_counter(), cpu_seconds(pid)))
                except OSError:   # it has just ended
                    pass
            time.sleep(0.5)
        out, err = launch.communicate()
    finally:
        watcher.stop.set()
        watcher.join(timeout=5.0)
        stop_process(launch)
    (t0, c0), (t1, c1) = samples[0], samples[-1]
    return {'command': f'fastep-launch {scenario} --rtf {rtf:g} --foxglove PORT', 'exit': launch.returncode,
            'result': out.strip().splitlines()[1:], 'foxglove_cpu_s': round(c1, 2), 'lived_s': round(t1 - t0, 1),
            'cpu_percent_after_start': round(100.0 * (c1 - c0) / (t1 - t0), 1), 'client_messages': watcher.messages,
            'wall_s': round(time.perf_counter() - start, 1), 'load_average_before': load,
            'load_average_after': os.getloadavg()}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument('--robots', default='2,16', help='robot counts, comma-separated')
    p.add_argument('--seconds', type=float, default=30.0)
    p.add_argument('--odom-rate', type=float, default=50.0)
    p.add_argument('--scene-rate', type=float, default=10.0)
    p.add_argument('--launch', metavar='SCENARIO', help='measure inside fastep-launch SCENARIO --foxglove instead')
    p.add_argument('--rtf', type=float, default=5.0, help='--rtf of the launch (default 5)')
    p.add_argument('--publish', type=int, help=argparse.SUPPRESS)
    p.add_argument('--listen', type=int, help=argparse.SUPPRESS)
    args = p.parse_args()
    if args.publish:
        publish(args.publish, args.odom_rate)
        return
    if args.listen:
        listen(args.listen)
        return
    if args.launch:
        print(json.dumps(measure_launch(args.launch, args.rtf)), flush=True)
        return
    print(f'load average before: {os.getloadavg()}', flush=True)
    for n in (int(v) for v in args.robots.split(',')):
        print(json.dumps(measure(n, args.seconds, args.odom_rate, args.scene_rate)), flush=True)


if __name__ == '__main__':
    main()
