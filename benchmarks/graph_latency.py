"""Benchmark: odometry-to-cmd_vel latency of one fastep planner node on wall time (a ROS 2 graph benchmark).

    python -m benchmarks.graph_latency [--seconds 20] [--scenario table2_s3] [--motion follow|line|stand]
                                       [--phase both|process|inprocess] [--stamped] [--profile] [--json OUT]

The planner keeps the newest odometry and decides on its 20 Hz control timer, so the latency has two parts:
(a) processing, the wall and thread CPU time of the control callback and of Navigator.update inside it, measured
on an instrumented PlannerNode subclass in this process (phase `inprocess`; ticks that planned a FAStep step
reported apart); (b) the age of the odometry each command was computed from, which is mostly the phase between
the driver's and the planner's 20 Hz timers, so `inprocess` also splits it into transport, wait and processing.
A driver node publishes /r1/odom at 20 Hz (--motion follow: a point mass integrating the commands) to a map
process and, in phase `process`, an unmodified planner process, all on an isolated DDS domain. --profile runs
cProfile around every inprocess callback; --stamped reads the cmd_vel transport from TwistStamped stamps.
The load average is printed with the numbers: the machine may be shared.
"""

from __future__ import annotations

import argparse
import cProfile
import io
import json
import math
import os
import pstats
import resource
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from fastep_testing.graph import Graph, Helper

TARGET_P99_MS = 5.0


def load() -> str:
    one, five, fifteen = os.getloadavg()
    return f'load average {one:.2f}, {five:.2f}, {fifteen:.2f} ({os.cpu_count()} cores)'


def cpu_seconds(pid: int) -> float:
    """utime + stime of a process from /proc/<pid>/stat (psutil is not needed)."""
    with open(f'/proc/{pid}/stat') as f:
        fields = f.read().rsplit(')', 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf('SC_CLK_TCK')


def stats_ms(samples: Any) -> dict[str, float]:
    a = np.asarray(samples, dtype=float) * 1e3
    if a.size == 0:
        return {'n': 0}
    return {'n': int(a.size), 'p50': float(np.percentile(a, 50)), 'p99': float(np.percentile(a, 99)),
            'max': float(a.max()), 'mean': float(a.mean())}


def fmt(s: dict[str, float]) -> str:
    if not s.get('n'):
        return 'no samples'
    return f'p50 {s["p50"]:.2f} ms, p99 {s["p99"]:.2f} ms, max {s["max"]:.2f} ms (n={s["n"]})'


# --------------------------------------------------------------------------------------------- the driver

class Driver:
    """Odometry source (20 Hz), goal sender and cmd_vel recorder for robot /r1, on a helper node."""

    def __init__(self, helper: Any, start: tuple[float, float], goal: tuple[float, float], motion: str,
                 speed: float, rate: float, stamped: bool = False) -> None:
        from geometry_msgs.msg import Twist, TwistStamped
        from nav_msgs.msg import Odometry
        from rclpy.qos import QoSProfile, ReliabilityPolicy

        from msg_tools import convert
        from msg_tools.interface import RELIABLE

        self.convert = convert
        self.helper = helper
        self.node = helper.node
        self.start = np.array(start, dtype=float)
        self.goal = np.array(goal, dtype=float)
        self.motion = motion
        self.speed = speed
        self.period = 1.0 / rate
        self.state = self.start.copy()
        self.velocity = np.zeros(2)
        self.command = np.zeros(2)
        self.direction = 1.0         # line motion: towards the goal (1) or back (-1)
        self.last = time.perf_counter()
        self.recording = False
        self.odom_pub_times: list[float] = []   # perf_counter just before publish
        self.odom_stamps: dict[int, float] = {}  # stamp (ns) -> perf_counter at publish
        self.cmd_times: list[float] = []
        self.cmd_wall: list[tuple[float, int]] = []  # stamped cmd_vel: (receipt wall time, header stamp ns)
        self.odom_pub = self.node.create_publisher(Odometry, '/r1/odom', RELIABLE)
        self.node.create_subscription(TwistStamped if stamped else Twist, '/r1/cmd_vel', self.on_cmd,
                                      QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE))
        self.status = helper.record_status('/r1')
        self.timer = self.node.create_timer(self.period, self.on_timer)
        self.targets = [tuple(goal), tuple(start)]
        self.goals_sent = 0

    def on_cmd(self, msg: Any) -> None:
        now, wall = time.perf_counter(), time.time()
        twist = getattr(msg, 'twist', msg)
        self.command = np.array([twist.linear.x, twist.linear.y])
        if self.recording:
            self.cmd_times.append(now)
            if hasattr(msg, 'header'):
                self.cmd_wall.append((wall, msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec))

    def on_timer(self) -> None:
        now = time.perf_counter()
        dt, self.last = now - self.last, now
        if self.motion == 'follow':
            self.velocity = self.command.copy()
            self.state = self.state + self.velocity * dt
        elif self.motion == 'line':
            axis = (self.goal - self.start) / np.hypot(*(self.goal - self.start))
            self.velocity = self.direction * self.speed * axis
            self.state = self.state + self.velocity * dt
            along = float((self.state - self.start) @ axis)
            if along > np.hypot(*(self.goal - self.start)) or along < 0.0:
                self.direction = -self.direction
        stamp = self.node.get_clock().now().to_msg()
        msg = self.convert.state_to_odometry(self.state, stamp, child_frame_id='r1/base_link', frame_id='map',
                                             linear=(float(self.velocity[0]), float(self.velocity[1])))
        t = time.perf_counter()
        self.odom_pub.publish(msg)
        if self.recording:
            self.odom_pub_times.append(t)
            self.odom_stamps[stamp.sec * 1_000_000_000 + stamp.nanosec] = t

    def mode(self) -> str:
        return self.helper.status('/r1').get('message', '')

    def send_next_goal(self) -> None:
        target = self.targets[self.goals_sent % 2]
        self.goals_sent += 1
        self.helper.send_goal('/r1', target)

    def stamped_split(self) -> dict[str, Any]:
        """Stamped cmd_vel (its stamp is the planner's clock when it published): cmd_vel transport (receipt wall
        time - stamp) and the odometry's age when the command was published (stamp - latest odom stamp)."""
        if not self.cmd_wall:
            return {}
        odom = np.array(sorted(self.odom_stamps), dtype=np.int64)
        transport, age = [], []
        for wall, stamp in self.cmd_wall:
            transport.append(wall - stamp * 1e-9)
            k = int(np.searchsorted(odom, stamp, side='right')) - 1
            if k >= 0:
                age.append((stamp - int(odom[k])) * 1e-9)
        return {'cmd_transport_stamped': stats_ms(transport), 'odom_age_at_cmd_publish': stats_ms(age)}

    def ages(self) -> np.ndarray:
        """For each cmd_vel received: receipt time minus publish time of the latest odometry before it."""
        pubs = np.asarray(self.odom_pub_times)
        cmds = np.asarray(self.cmd_times)
        if not len(pubs) or not len(cmds):
            return np.zeros(0)
        index = np.searchsorted(pubs, cmds, side='right') - 1
        ok = index >= 0
        return cmds[ok] - pubs[index[ok]]


def run_window(helper: Any, driver: Driver, seconds: float, warmup: float, on_start: Any) -> dict[str, Any]:
    """Wait for the planner to know the world, send the goal, record for `seconds` after `warmup`
    (on_start() is called when the recording starts)."""
    helper.spin_until(lambda: driver.mode() == 'idle', 120.0, 'the planner to know the world (status idle)')
    driver.send_next_goal()
    helper.spin_until(lambda: driver.mode() in ('kinematic', 'avoiding'), 30.0, 'the planner to take the goal')
    helper.spin_for(warmup)
    on_start()
    driver.recording = True
    modes: dict[str, int] = {}
    deadline = time.monotonic() + seconds
    arrivals = 0
    while time.monotonic() < deadline:
        helper.executor.spin_once(timeout_sec=0.05)
        mode = driver.mode()
        modes[mode] = modes.get(mode, 0) + 1
        if mode == 'arrived' and driver.motion == 'follow':
            arrivals += 1
            driver.send_next_goal()
            helper.spin_until(lambda: driver.mode() != 'arrived', 10.0, 'the planner to take the next goal')
    driver.recording = False
    return {'arrivals': arrivals, 'final_status': helper.status('/r1'), **driver.stamped_split()}


def cmd_periods(driver: Driver) -> dict[str, Any]:
    gaps = np.diff(np.asarray(driver.cmd_times))
    span = driver.cmd_times[-1] - driver.cmd_times[0] if len(driver.cmd_times) > 1 else 0.0
    return {'rate_hz': (len(driver.cmd_times) - 1) / span if span > 0 else 0.0,
            'late_fraction': float(np.mean(gaps > 1.5 * 0.05)) if len(gaps) else 0.0,
            'period': stats_ms(gaps)}


# --------------------------------------------------------------------------------------------- phases

def planner_params(scenario: Any, index: int, algorithm: str, seed: int, sim_time: bool,
                   stamped: bool) -> dict[str, Any]:
    """The parameters fastep-launch gives a planner (plus use_stamped_cmd_vel with --stamped)."""
    from fastep_ros import launch
    params = launch.planner_params(scenario, index, algorithm, seed, sim_time)
    if stamped:
        params['use_stamped_cmd_vel'] = True
    return params


def phase_process(args: argparse.Namespace, tmp: Path) -> dict[str, Any]:
    """The unmodified planner as its own process: (b) end-to-end age, cmd period, planner CPU."""
    from fastep_core.scenario import load_scenario

    scenario = load_scenario(args.scenario)
    graph = Graph(tmp)
    try:
        graph.start('map', 'map_server', '/', scenario=args.scenario)
        graph.start('planner', 'planner', '/r1',
                    **planner_params(scenario, 0, 'fastep', args.seed, False, args.stamped))
        graph.helper = Helper(graph.domain)
        spec = scenario.robots[0]
        driver = Driver(graph.helper, spec.start, spec.goal, args.motion, args.speed, 20.0, args.stamped)
        pid = graph.procs['planner'].pid
        load_before = load()
        start: list[float] = []

        def begin() -> None:  # CPU is counted over the recording window only
            start[:] = [cpu_seconds(pid), time.monotonic()]
        info = run_window(graph.helper, driver, args.seconds, args.warmup, begin)
        cpu0, wall0 = start
        cpu = (cpu_seconds(pid) - cpu0) / (time.monotonic() - wall0)
        return {'phase': 'process', 'domain': graph.domain, 'load_before': load_before, 'load_after': load(),
                'age': stats_ms(driver.ages()), 'cmd': cmd_periods(driver), 'planner_cpu_percent': 100.0 * cpu,
                **info}
    finally:
        graph.close()


def make_timed_planner(profile: cProfile.Profile | None) -> type:
    from fastep_ros.planner import PlannerNode

    class TimedPlanner(PlannerNode):
        """PlannerNode with its control callback, Navigator.update and odometry receipt timed."""

        def __init__(self, **kwargs: Any) -> None:
            # (start, end, Navigator.update s, odom stamp ns, activations, thread CPU s) per control tick
            self.bench_ticks: list[tuple[float, float, float, int, int, float]] = []
            self.bench_odom_rx: dict[int, float] = {}   # odom stamp (ns) -> perf_counter at on_odom
            self.bench_cmd_pub: list[float] = []         # perf_counter right after cmd_vel publish
            self.bench_record = False
            self._update_time = 0.0
            super().__init__(**kwargs)
            self.inputs.odom_sub.callback = self.bench_on_odom   # the odometry handler is the inputs member's

        def update_world(self) -> None:
            had = self.navigator
            super().update_world()
            nav = self.navigator
            if nav is not None and had is None:
                inner = nav.update

                def timed_update(*a: Any, **k: Any) -> Any:
                    t0 = time.perf_counter()
                    try:
                        return inner(*a, **k)
                    finally:
                        self._update_time += time.perf_counter() - t0
                nav.update = timed_update  # type: ignore[method-assign]  # time each call

        def bench_on_odom(self, msg: Any) -> None:
            t = time.perf_counter()
            self.inputs.on_odom(msg)
            if self.bench_record:
                self.bench_odom_rx[msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec] = t

        def publish_command(self, command: Any) -> None:
            super().publish_command(command)
            if self.bench_record:
                self.bench_cmd_pub.append(time.perf_counter())

        def on_control(self) -> None:
            self._update_time = 0.0
            before = self.navigator.activations if self.navigator is not None else 0
            c0 = time.thread_time()
            t0 = time.perf_counter()
            if profile is not None and self.bench_record:
                profile.enable()
                try:
                    super().on_control()
                finally:
                    profile.disable()
            else:
                super().on_control()
            t1 = time.perf_counter()
            c1 = time.thread_time()
            if self.bench_record:
                odom = self.inputs.odom
                stamp = -1 if odom is None else odom.header.stamp.sec * 1_000_000_000 + odom.header.stamp.nanosec
                after = self.navigator.activations if self.navigator is not None else 0
                self.bench_ticks.append((t0, t1, self._update_time, stamp, after - before, c1 - c0))

    return TimedPlanner


def phase_inprocess(args: argparse.Namespace, tmp: Path) -> dict[str, Any]:
    """The instrumented planner in this process's executor: (a) processing time, and (b) split into parts."""
    import rclpy.logging
    from rclpy.logging import LoggingSeverity
    from rclpy.parameter import Parameter

    from fastep_core.scenario import load_scenario

    scenario = load_scenario(args.scenario)
    graph = Graph(tmp)
    profile = cProfile.Profile() if args.profile else None
    planner = None
    try:
        graph.start('map', 'map_server', '/', scenario=args.scenario)
        graph.helper = helper = Helper(graph.domain)
        params = planner_params(scenario, 0, 'fastep', args.seed, False, args.stamped)
        rclpy.logging.set_logger_level('r1.planner', LoggingSeverity.WARN)
        planner = make_timed_planner(profile)(
            context=helper.context, namespace='/r1',
            parameter_overrides=[Parameter(k, value=v) for k, v in params.items()])
        helper.executor.add_node(planner)
        spec = scenario.robots[0]
        driver = Driver(helper, spec.start, spec.goal, args.motion, args.speed, 20.0, args.stamped)
        load_before = load()
        usage0: list[Any] = []

        def begin() -> None:
            planner.bench_record = True
            usage0[:] = [resource.getrusage(resource.RUSAGE_SELF), time.monotonic()]
        info = run_window(helper, driver, args.seconds, args.warmup, begin)
        planner.bench_record = False
        usage1 = resource.getrusage(resource.RUSAGE_SELF)
        cpu = ((usage1.ru_utime + usage1.ru_stime - usage0[0].ru_utime - usage0[0].ru_stime)
               / (time.monotonic() - usage0[1]))
        ticks = planner.bench_ticks  # stamps stay Python ints: nanoseconds since 1970 do not fit a float64
        total = np.array([t[1] - t[0] for t in ticks])
        update = np.array([t[2] for t in ticks])
        stepped = np.array([t[4] > 0 for t in ticks], dtype=bool)
        thread_cpu = np.array([t[5] for t in ticks])
        # (b) split: for ticks whose odometry was published while recording.
        odom_tx, wait = [], []
        for t0, _, _, key, _, _ in ticks:
            if key in driver.odom_stamps and key in planner.bench_odom_rx:
                odom_tx.append(planner.bench_odom_rx[key] - driver.odom_stamps[key])
                wait.append(t0 - planner.bench_odom_rx[key])
        pubs = np.asarray(planner.bench_cmd_pub)
        cmds = np.asarray(driver.cmd_times)
        cmd_tx = []
        if len(pubs) and len(cmds):
            # Each receipt matches the latest publish before it.
            index = np.searchsorted(pubs, cmds, side='right') - 1
            cmd_tx = list(cmds[index >= 0] - pubs[index[index >= 0]])
        used_age, pipeline = [], []
        starts = np.array([t[0] for t in ticks])
        for c in cmds:
            # cmd receipt minus publish of the odometry the tick that sent it actually used; and the same without
            # the time that odometry waited in the planner for the tick (the timer's phase)
            k = int(np.searchsorted(starts, c, side='right')) - 1
            if k >= 0 and ticks[k][3] in driver.odom_stamps:
                key = ticks[k][3]
                used_age.append(c - driver.odom_stamps[key])
                if key in planner.bench_odom_rx:
                    pipeline.append(planner.bench_odom_rx[key] - driver.odom_stamps[key] + c - ticks[k][0])
        out = {'phase': 'inprocess', 'domain': graph.domain, 'load_before': load_before, 'load_after': load(),
               'callback': stats_ms(total), 'callback_cpu': stats_ms(thread_cpu), 'update': stats_ms(update),
               'callback_step_ticks': stats_ms(total[stepped]), 'callback_other_ticks': stats_ms(total[~stepped]),
               'ros_overhead': stats_ms(total - update), 'step_ticks': int(stepped.sum()),
               'age': stats_ms(driver.ages()), 'age_of_odom_used': stats_ms(used_age), 'pipeline': stats_ms(pipeline),
               'odom_transport': stats_ms(odom_tx), 'wait_for_tick': stats_ms(wait), 'cmd_transport': stats_ms(cmd_tx),
               'cmd': cmd_periods(driver), 'process_cpu_percent': 100.0 * cpu, **info}
        if profile is not None:
            text = io.StringIO()
            stats = pstats.Stats(profile, stream=text)
            stats.sort_stats('cumulative').print_stats(args.profile_lines)
            stats.sort_stats('tottime').print_stats(args.profile_lines)
            out['profile'] = text.getvalue()
            if args.profile_out:
                stats.dump_stats(args.profile_out)
        return out
    finally:
        if planner is not None:
            try:
                if graph.helper is not None:
                    graph.helper.executor.remove_node(planner)
                planner.destroy_node()
            except Exception:
                pass
        graph.close()


# --------------------------------------------------------------------------------------------- main

def report(result: dict[str, Any]) -> None:
    print(f'--- phase {result["phase"]} (domain {result["domain"]}; {result["load_before"]} before, '
          f'{result["load_after"]} after)')
    if result['phase'] == 'inprocess':
        ok = result['callback'].get('p99', math.inf) <= TARGET_P99_MS
        print(f'(a) control callback (on_control, all of it): {fmt(result["callback"])}  '
              f'[target p99 <= {TARGET_P99_MS:g} ms: {"met" if ok else "NOT met"}]')
        print(f'    its CPU time (time.thread_time: without preemption by other processes): '
              f'{fmt(result["callback_cpu"])}')
        print(f'    of which Navigator.update:               {fmt(result["update"])}')
        print(f'    rest (state, messages, publishing):       {fmt(result["ros_overhead"])}')
        print(f'    ticks that planned a step ({result["step_ticks"]}):         {fmt(result["callback_step_ticks"])}')
        print(f'    other ticks:                              {fmt(result["callback_other_ticks"])}')
        print(f'(b) age of odometry at cmd_vel receipt (latest published): {fmt(result["age"])}')
        print(f'    age of the odometry the tick really used:      {fmt(result["age_of_odom_used"])}')
        print(f'    = odom transport {fmt(result["odom_transport"])}')
        print(f'    + wait for the tick {fmt(result["wait_for_tick"])}')
        print(f'    + processing (a) + cmd_vel transport {fmt(result["cmd_transport"])}')
        print(f'    without the wait for the tick (odom transport + processing + cmd_vel transport): '
              f'{fmt(result["pipeline"])}')
        print(f'    this process (driver + planner + DDS threads): {result["process_cpu_percent"]:.1f} % of one core')
    else:
        print(f'(b) age of odometry at cmd_vel receipt (latest published before it): {fmt(result["age"])}')
        print(f'    planner process CPU: {result["planner_cpu_percent"]:.1f} % of one core')
    if result.get('cmd_transport_stamped'):
        print(f'stamped cmd_vel: transport (receipt - stamp) {fmt(result["cmd_transport_stamped"])}')
        print(f'    odometry age when the command was published {fmt(result["odom_age_at_cmd_publish"])}')
    c = result['cmd']
    print(f'cmd_vel: {c["rate_hz"]:.2f} Hz, period {fmt(c["period"])}, late (> 75 ms) {100 * c["late_fraction"]:.2f} %')
    status = result.get('final_status', {})
    print(f'robot: {result["arrivals"]} arrival(s); last status {status.get("message")} ({status.get("reason")}), '
          f'activations {status.get("activations")}')
    if 'profile' in result:
        print(result['profile'])


def main(argv: list[str] | None = None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument('--seconds', type=float, default=20.0, help='recording window per phase (wall s)')
    p.add_argument('--warmup', type=float, default=1.0, help='wall s after the goal before recording')
    p.add_argument('--scenario', default='table2_s3', help='scenario (robot r1\'s start and goal, the obstacles)')
    p.add_argument('--motion', choices=('follow', 'line', 'stand'), default='follow')
    p.add_argument('--speed', type=float, default=0.5, help='m/s for --motion line')
    p.add_argument('--seed', type=int, default=0)
    p.add_argument('--stamped', action='store_true', help='planner publishes TwistStamped (use_stamped_cmd_vel):'
                   ' cmd_vel transport is then measured from its stamp')
    p.add_argument('--phase', choices=('both', 'process', 'inprocess'), default='both')
    p.add_argument('--profile', action='store_true', help='cProfile the control callback (inprocess phase)')
    p.add_argument('--profile-lines', type=int, default=25)
    p.add_argument('--profile-out', help='write the cProfile stats here (pstats format)')
    p.add_argument('--json', type=Path, help='write the results as JSON')
    args = p.parse_args(argv)
    os.environ.setdefault('FASTEP_TEST_LOG_LEVEL', 'warn')
    print(f'graph_latency: scenario {args.scenario}, motion {args.motion}, {args.seconds:g} s per phase; {load()}',
          flush=True)
    results = []
    with tempfile.TemporaryDirectory(prefix='fastep-graph-latency-') as tmp:
        phases = ['process', 'inprocess'] if args.phase == 'both' else [args.phase]
        for phase in phases:
            folder = Path(tmp) / phase
            folder.mkdir()
            run = phase_process if phase == 'process' else phase_inprocess
            result = run(args, folder)
            report(result)
            results.append(result)
            sys.stdout.flush()
    if args.json:
        args.json.write_text(json.dumps({'args': {k: str(v) for k, v in vars(args).items()},
                                         'results': results}, indent=1, default=str) + '\n')


if __name__ == '__main__':
    main()
