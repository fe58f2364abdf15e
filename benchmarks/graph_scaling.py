"""Benchmark: how many robots one ROS 2 graph runs at real time with 20 Hz control (and the demo's real-time factor).

    python -m benchmarks.graph_scaling [--max-robots 12] [--counts 1,2,4,6,8,10,12] [--seconds 20] [--json OUT]
    python -m benchmarks.graph_scaling --fan-in 0,3,7,11 [--seconds 20]
    python -m benchmarks.graph_scaling --demo-rtf [--demo case_study_1] [--rtf 50] [--seed 0]
    every mode: [--layout node|robot|graph] [--executor single|events]

Scaling: N point masses on a circle swap places in an empty 50 x 50 m world; the map, N plants and N planners run
as separate processes on wall time on an isolated DDS domain. A monitor records every /rK/cmd_vel for --seconds:
rate (target 20 Hz), late control periods (> 1.5 x 50 ms), CPU per process (/proc) and the load average. N passes
when every robot keeps >= 19 Hz and < 5 % late periods; the answer is the largest passing N.
--fan-in: one planner's CPU against the number K of other robots whose 50 Hz odometry it follows, the messages
staggered or in bursts. --demo-rtf: real-time factor of `fastep_ros.launch case_study_1 --rtf 50`, over the whole
command and over the run alone.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from fastep_ros.executors import EXECUTORS
from fastep_ros.layouts import LAYOUTS, Member, command, group
from fastep_ros.processes import ros_value
from fastep_testing.graph import Graph, Helper, free_domain, isolated_env, stop_process
from fastep_testing.runs import circle_yaml

ROOT = Path(__file__).resolve().parents[1]
PERIOD = 0.05            # control period of the planners (s)
LATE = 1.5 * PERIOD      # a period longer than this is late
MIN_RATE = 19.0
MAX_LATE_FRACTION = 0.05


def loadavg() -> tuple[float, float, float]:
    return os.getloadavg()


def load_text(avg: tuple[float, float, float] | None = None) -> str:
    one, five, fifteen = avg or os.getloadavg()
    return f'load average {one:.2f}, {five:.2f}, {fifteen:.2f}'


def cpu_seconds(pid: int) -> float:
    """utime + stime of a process (psutil not needed); NaN if it is gone."""
    try:
        with open(f'/proc/{pid}/stat') as f:
            fields = f.read().rsplit(')', 1)[1].split()
    except OSError:
        return math.nan
    return (int(fields[11]) + int(fields[12])) / os.sysconf('SC_CLK_TCK')


def machine_cpu() -> tuple[float, float]:
    """(busy, total) jiffies of all cores from /proc/stat."""
    with open('/proc/stat') as f:
        values = [int(v) for v in f.readline().split()[1:]]
    idle = values[3] + values[4]  # idle + iowait
    return sum(values) - idle, sum(values)


def period_stats(times: list[float], seconds: float) -> dict[str, float]:
    t = np.asarray(times, dtype=float)
    gaps = np.diff(t)
    return {'count': int(t.size), 'rate_hz': t.size / seconds,
            'late_fraction': float(np.mean(gaps > LATE)) if gaps.size else 1.0,
            'max_gap_ms': float(gaps.max() * 1e3) if gaps.size else math.inf,
            'p99_gap_ms': float(np.percentile(gaps, 99) * 1e3) if gaps.size else math.inf}


def run_n(n: int, args: argparse.Namespace, tmp: Path) -> dict[str, Any]:
    from geometry_msgs.msg import Twist, TwistStamped
    from rclpy.qos import QoSProfile, ReliabilityPolicy

    from fastep_core.scenario import load_scenario
    from fastep_ros import launch

    path = tmp / f'circle_{n}.yaml'
    path.write_text(circle_yaml(n, args.radius, args.max_speed, args.step_iterations))
    scenario = load_scenario(str(path))
    stamped = not args.unstamped
    graph = Graph(tmp)
    t_start = time.monotonic()
    try:
        members = [Member('map', 'map_server', '/', {'scenario': str(path)})]
        for i, spec in enumerate(scenario.robots):
            plant = launch.plant_params(spec, False)
            planner = launch.planner_params(scenario, i, args.algorithm, args.seed, False)
            if stamped:
                plant['use_stamped_cmd_vel'] = planner['use_stamped_cmd_vel'] = True
            members += [Member(f'plant/{spec.name}', 'plant', f'/{spec.name}', plant),
                        Member(f'planner/{spec.name}', 'planner', f'/{spec.name}', planner)]
        start_layout(graph, args.layout, args.executor, members)
        # The measuring node spins on the EventsExecutor: on the SingleThreadedExecutor it took 35-70 % of a core
        # (every robot's cmd_vel and status) from the 2 the graph is measured on.
        graph.helper = helper = Helper(graph.domain, executor='events')
        names = [spec.name for spec in scenario.robots]
        receipts: dict[str, list[float]] = {name: [] for name in names}
        stamps: dict[str, list[float]] = {name: [] for name in names}
        recording = [False]

        def on_cmd(name: str, msg: Any) -> None:
            now = time.monotonic()
            if recording[0]:
                receipts[name].append(now)
                if stamped:
                    stamps[name].append(msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9)
        qos = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
        for name in names:
            helper.record_status(f'/{name}')
            helper.node.create_subscription(TwistStamped if stamped else Twist, f'/{name}/cmd_vel',
                                            lambda m, k=name: on_cmd(k, m), qos)

        def ready() -> bool:
            for name in names:
                status = helper.status(f'/{name}')
                if status.get('message') != 'idle':
                    return False
                if not set(names) - {name} <= set(str(status.get('others', '')).split()):
                    return False
            for proc in graph.procs.values():
                if proc.poll() is not None:
                    raise RuntimeError(f'a node exited with code {proc.returncode} during start-up')
            return True
        helper.spin_until(ready, args.startup_timeout + 10.0 * n, 'every planner to see the world and the others')
        startup = time.monotonic() - t_start
        for spec in scenario.robots:
            helper.send_goal(f'/{spec.name}', spec.goal)
        helper.spin_until(lambda: all(helper.status(f'/{k}').get('message') not in ('idle', None) for k in names),
                          30.0, 'every planner to take its goal')

        pids = {label: proc.pid for label, proc in graph.procs.items()}
        load_before = loadavg()
        cpu0 = {label: cpu_seconds(pid) for label, pid in pids.items()}
        machine0 = machine_cpu()
        self0 = resource.getrusage(resource.RUSAGE_SELF)
        wall0 = time.monotonic()
        recording[0] = True
        modes: dict[str, set[str]] = {name: set() for name in names}
        while time.monotonic() - wall0 < args.seconds:
            helper.executor.spin_once(timeout_sec=0.02)
            for name in names:
                modes[name].add(str(helper.status(f'/{name}').get('message')))
        recording[0] = False
        wall = time.monotonic() - wall0
        cpu1 = {label: cpu_seconds(pid) for label, pid in pids.items()}
        machine1 = machine_cpu()
        self1 = resource.getrusage(resource.RUSAGE_SELF)
        load_after = loadavg()
        # The window starts when recording starts: measure from the first receipt on, over `seconds`.
        robots = {}
        for name in names:
            entry: dict[str, Any] = {'receipt': period_stats(receipts[name], wall)}
            if stamped:
                entry['stamp'] = period_stats(sorted(stamps[name]), wall)
            status = helper.status(f'/{name}')
            entry['modes'] = sorted(modes[name])
            entry['final'] = f'{status.get("message")}: {status.get("reason")}'
            entry['activations'] = status.get('activations')
            # The planner's control callback, wall time of its last 200 (10 s): "p50 / p99 / max" ms (status).
            entry['control_ms'] = [float(v) for v in str(status.get('control_ms', '')).split(' / ') if v]
            # ... and the CPU time of the planner's thread in them (the wall time less the waits for a core).
            entry['control_cpu_ms'] = [float(v) for v in str(status.get('control_cpu_ms', '')).split(' / ') if v]
            robots[name] = entry
        cpu = {label: 100.0 * (cpu1[label] - cpu0[label]) / wall for label in pids}
        # Per node only where each node has a process of its own (--layout node).
        planners = [cpu.get(f'planner/{k}', math.nan) for k in names]
        plants = [cpu.get(f'plant/{k}', math.nan) for k in names]
        monitor = 100.0 * (self1.ru_utime + self1.ru_stime - self0.ru_utime - self0.ru_stime) / wall
        busy = (machine1[0] - machine0[0]) / max(1, machine1[1] - machine0[1])
        worst_rate = min(r['receipt']['rate_hz'] for r in robots.values())
        worst_late = max(r['receipt']['late_fraction'] for r in robots.values())
        result = {
            'n': n, 'layout': args.layout, 'executor': args.executor, 'algorithm': args.algorithm,
            'domain': graph.domain, 'processes': len(pids), 'startup_s': startup, 'window_s': wall,
            'load_before': load_before, 'load_after': load_after, 'robots': robots,
            'cpu_percent': {'planner_mean': float(np.mean(planners)), 'planner_max': float(np.max(planners)),
                            'plant_mean': float(np.mean(plants)), 'plant_max': float(np.max(plants)),
                            'map': cpu.get('map', math.nan), 'monitor': monitor,
                            'graph_total': float(sum(cpu.values())),
                            'per_robot': float(sum(cpu.values()) - cpu.get('map', 0.0)) / n,
                            'machine_busy_percent_of_all_cores': 100.0 * busy},
            'worst_rate_hz': worst_rate, 'worst_late_fraction': worst_late,
            'passed': worst_rate >= MIN_RATE and worst_late < MAX_LATE_FRACTION,
        }
        timed = [r['control_ms'] for r in robots.values() if len(r['control_ms']) == 3]
        if timed:
            result['control_p99_ms_worst'] = max(t[1] for t in timed)
            result['control_max_ms_worst'] = max(t[2] for t in timed)
            result['control_p99_ms_median'] = float(np.median([t[1] for t in timed]))
        timed_cpu = [r['control_cpu_ms'] for r in robots.values() if len(r['control_cpu_ms']) == 3]
        if timed_cpu:
            result['control_cpu_p99_ms_worst'] = max(t[1] for t in timed_cpu)
            result['control_cpu_p99_ms_median'] = float(np.median([t[1] for t in timed_cpu]))
        if stamped:
            result['worst_stamp_rate_hz'] = min(r['stamp']['rate_hz'] for r in robots.values())
            result['worst_stamp_late_fraction'] = max(r['stamp']['late_fraction'] for r in robots.values())
        return result
    finally:
        t_stop = time.monotonic()
        graph.close()
        if args.verbose:
            print(f'  stopped {len(graph.procs)} processes in {time.monotonic() - t_stop:.1f} s', flush=True)


def print_result(r: dict[str, Any]) -> None:
    c = r['cpu_percent']
    print(f'N={r["n"]:2d} (layout {r["layout"]}, executor {r["executor"]}, {r["processes"]} node processes,'
          f' domain {r["domain"]}, start-up {r["startup_s"]:.1f} s, '
          f'{load_text(r["load_before"])} before / {load_text(r["load_after"])} after): '
          f'{"PASS" if r["passed"] else "FAIL"}', flush=True)
    line = (f'    cmd_vel at the monitor: worst rate {r["worst_rate_hz"]:.2f} Hz, worst late fraction '
            f'{100 * r["worst_late_fraction"]:.2f} %')
    if 'worst_stamp_rate_hz' in r:
        line += (f'; by stamp (planner side): worst {r["worst_stamp_rate_hz"]:.2f} Hz, '
                 f'{100 * r["worst_stamp_late_fraction"]:.2f} % late')
    print(line)
    worst = max(r['robots'].items(), key=lambda kv: kv[1]['receipt']['late_fraction'])
    print(f'    worst robot {worst[0]}: {worst[1]["receipt"]} modes {worst[1]["modes"]}')
    per_node = ''
    if not math.isnan(c['planner_mean']):   # only where each node has a process of its own (--layout node)
        per_node = (f'planner mean {c["planner_mean"]:.1f} (max {c["planner_max"]:.1f}), '
                    f'plant mean {c["plant_mean"]:.1f} (max {c["plant_max"]:.1f}), map {c["map"]:.1f}, ')
    print(f'    CPU % of one core over the window: {per_node}'
          f'monitor {c["monitor"]:.1f}; per robot (plant + planner) {c["per_robot"]:.1f} %; '
          f'graph total {c["graph_total"]:.0f} % '
          f'(of {100 * (os.cpu_count() or 1)} %); machine busy {c["machine_busy_percent_of_all_cores"]:.0f} % '
          f'of all cores (incl. other users)')
    if 'control_p99_ms_worst' in r:
        print(f'    planner control callback (wall, last 10 s): worst p99 {r["control_p99_ms_worst"]:.2f} ms '
              f'(median robot {r["control_p99_ms_median"]:.2f}), worst max {r["control_max_ms_worst"]:.2f} ms')
    if 'control_cpu_p99_ms_worst' in r:
        print(f'    ... its thread\'s CPU time: worst p99 {r["control_cpu_p99_ms_worst"]:.2f} ms '
              f'(median robot {r["control_cpu_p99_ms_median"]:.2f})')
    arrived = sum(1 for x in r['robots'].values() if x['final'].startswith('arrived'))
    print(f'    robots arrived by the end of the window: {arrived}/{r["n"]}', flush=True)


def start_layout(graph: Graph, layout: str, executor: str, members: list[Member]) -> None:
    """Start `members` in the processes of a fastep-launch layout (fastep_ros.layouts), on `executor`; each
    process is graph.procs[its label] (a node's label where it has a process of its own)."""
    env = dict(graph.env, FASTEP_EXECUTOR=executor)
    level = os.environ.get('FASTEP_TEST_LOG_LEVEL', 'warn')
    for label, group_members in group(layout, members):
        log = open(graph.tmp / f'{label.replace("/", "_").replace(" ", "_")}.log', 'wb')
        graph.procs[label] = subprocess.Popen(command(group_members, level, ros_value), env=env, stdout=log,
                                              stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
        log.close()


def scaling(args: argparse.Namespace) -> None:
    counts = [int(v) for v in args.counts.split(',')] if args.counts else \
        [n for n in (1, 2, 4, 6, 8, 10, 12, 14, 16) if n <= args.max_robots]
    print(f'graph_scaling: layout {args.layout}, executor {args.executor}; N in {counts}, {args.seconds:g} s each,'
          f' circle radius {args.radius:g} m, max_speed '
          f'{args.max_speed:g} m/s, cmd_vel {"Twist" if args.unstamped else "TwistStamped"}; {load_text()} '
          f'({os.cpu_count()} cores)', flush=True)
    results = []
    with tempfile.TemporaryDirectory(prefix='fastep-graph-scaling-') as tmp:
        for n in counts:
            folder = Path(tmp) / f'n{n}'
            folder.mkdir()
            try:
                r = run_n(n, args, folder)
            except (RuntimeError, AssertionError) as exc:
                print(f'N={n}: could not run: {exc}', flush=True)
                results.append({'n': n, 'error': str(exc), 'passed': False, 'load': os.getloadavg()})
                if args.stop_after_fail:
                    break
                continue
            print_result(r)
            results.append(r)
            if not r['passed'] and args.stop_after_fail:
                break
    passing = [r['n'] for r in results if r.get('passed')]
    largest = 0
    for r in results:  # the largest N below which every tried N passed
        if not r.get('passed'):
            break
        largest = r['n']
    print(f'largest N with every robot >= {MIN_RATE:g} Hz and < {100 * MAX_LATE_FRACTION:g} % late periods: '
          f'{largest} (passing: {passing}); {load_text()}')
    if args.json:
        args.json.write_text(json.dumps({'args': {k: str(v) for k, v in vars(args).items()}, 'results': results},
                                        indent=1, default=str) + '\n')


# --------------------------------------------------------------------------------------------- fan-in

def fan_in(args: argparse.Namespace) -> None:
    """CPU of one planner process against the number of other robots' odometry streams it follows."""
    import threading

    from nav_msgs.msg import Odometry

    from fastep_core.scenario import load_scenario
    from fastep_ros import launch
    from msg_tools import convert
    from msg_tools.interface import RELIABLE

    scenario = load_scenario('open_field')
    spec = scenario.robots[0]
    counts = [int(v) for v in args.fan_in.split(',')]
    print(f'fan-in: one planner (open_field r1, goal sent, own odometry at 50 Hz) following K other robots whose '
          f'odometry (50 Hz each) this process publishes either staggered (K x 50 evenly spaced messages/s, as K '
          f'independent plants do) or in bursts (all K at once, 50 times/s); {args.seconds:g} s each; '
          f'{load_text()}', flush=True)
    rows: dict[str, list[tuple[int, float]]] = {'staggered': [], 'burst': []}
    with tempfile.TemporaryDirectory(prefix='fastep-graph-fanin-') as tmp:
        for k in counts:
            for mode in ('staggered', 'burst') if k else ('staggered',):
                folder = Path(tmp) / f'k{k}-{mode}'
                folder.mkdir()
                graph = Graph(folder)
                stop = threading.Event()
                thread = None
                try:
                    graph.start('map', 'map_server', '/', scenario='open_field')
                    graph.start('planner', 'planner', '/r1',
                                **launch.planner_params(scenario, 0, 'fastep', 0, False))
                    graph.helper = helper = Helper(graph.domain)
                    node = helper.node
                    own = node.create_publisher(Odometry, '/r1/odom', RELIABLE)
                    pubs = [node.create_publisher(Odometry, f'/o{i}/odom', RELIABLE) for i in range(1, k + 1)]
                    # Other robots stand still 20 m off r1's straight line (y = 45).
                    msgs = [convert.state_to_odometry((5.0 + 3.5 * i, 45.0), child_frame_id=f'o{i + 1}/base_link')
                            for i in range(k)]
                    own_msg = convert.state_to_odometry(spec.start, child_frame_id='r1/base_link')

                    streams = [(own, own_msg)] + list(zip(pubs, msgs))

                    # Defaults bind this iteration's objects (the thread is joined before the next one).
                    def publisher(mode: str = mode, node: Any = node, stop: threading.Event = stop,
                                  streams: list[Any] = streams) -> None:
                        slots = len(streams) if mode == 'staggered' else 1
                        step = 0.02 / slots
                        t = time.monotonic()
                        i = 0
                        while not stop.is_set():
                            group = [streams[i % slots]] if mode == 'staggered' else streams
                            stamp = node.get_clock().now().to_msg()
                            for pub, msg in group:
                                msg.header.stamp = stamp
                                pub.publish(msg)
                            i += 1
                            t += step
                            delay = t - time.monotonic()
                            if delay > 0:
                                time.sleep(delay)
                    thread = threading.Thread(target=publisher, daemon=True)
                    thread.start()
                    helper.record_status('/r1')
                    others = {f'o{i}' for i in range(1, k + 1)}
                    def following(helper: Helper = helper, others: set[str] = others) -> bool:
                        status = helper.status('/r1')
                        return status.get('message') == 'idle' and others <= set(str(status.get('others', '')).split())

                    helper.spin_until(following, 60.0, f'the planner to follow {k} robots')
                    helper.send_goal('/r1', spec.goal)
                    helper.spin_for(1.0)
                    pid = graph.procs['planner'].pid
                    load_before = loadavg()
                    c0, w0 = cpu_seconds(pid), time.monotonic()
                    helper.spin_for(args.seconds)
                    cpu = 100.0 * (cpu_seconds(pid) - c0) / (time.monotonic() - w0)
                    status = helper.status('/r1').get('message')
                finally:
                    stop.set()
                    if thread is not None:
                        thread.join()
                    graph.close()
                rows[mode].append((k, cpu))
                print(f'K={k:2d} other robots, {mode:9s}: planner CPU {cpu:5.1f} % of one core (status {status}; '
                      f'{load_text(load_before)})', flush=True)
    rows['burst'] = [r for r in rows['staggered'] if r[0] == 0] + rows['burst']
    for mode, data in rows.items():
        if len(data) >= 2:
            slope, base = np.polyfit([r[0] for r in data], [r[1] for r in data], 1)
            print(f'fit ({mode}): planner CPU ~ {base:.1f} % + {slope:.2f} % per other robot followed '
                  f'({slope / 100 / 50 * 1e3:.2f} ms of CPU per odometry message at 50 Hz)')
    print(load_text())


# --------------------------------------------------------------------------------------------- demo RTF

RESULT = re.compile(r'^(\w+): (arrived|failed|timeout).*?time ([0-9.]+) s')


def demo_rtf(args: argparse.Namespace) -> None:
    domain = free_domain()
    cmd = [sys.executable, '-m', 'fastep_ros.launch', args.demo, '--rtf', f'{args.rtf:g}', '--seed', str(args.seed)]
    cmd += [] if args.demo_launcher_defaults else ['--layout', args.layout, '--executor', args.executor]
    with tempfile.TemporaryDirectory(prefix='fastep-demo-rtf-') as tmp:
        env = isolated_env(domain, Path(tmp) / 'roslog')
        print(f'$ python {" ".join(cmd[1:])}   (ROS_DOMAIN_ID={domain}; {load_text()})', flush=True)
        lines: list[tuple[float, str]] = []
        start = time.perf_counter()
        proc = subprocess.Popen(cmd, env=env, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        try:
            assert proc.stdout is not None
            for line in proc.stdout:
                lines.append((time.perf_counter() - start, line.rstrip('\n')))
                print(f'  [{lines[-1][0]:6.2f} s] {lines[-1][1]}', flush=True)
            code = proc.wait()
        finally:
            stop_process(proc)
        wall = time.perf_counter() - start
    sim = [float(m.group(3)) for _, text in lines if (m := RESULT.match(text))]
    underway = [t for t, text in lines if 'on their way' in text]
    first_result = [t for t, text in lines if RESULT.match(text)]
    print(f'exit code {code}; wall time of the whole command {wall:.2f} s; {load_text()}')
    if not sim:
        print('no robot result lines: cannot compute the RTF')
        return
    print(f'simulated time of the run (last robot\'s time) {max(sim):.1f} s -> RTF {max(sim) / wall:.2f} '
          f'(whole command, requested --rtf {args.rtf:g})')
    if underway and first_result:
        run_wall = first_result[0] - underway[0]
        print(f'run alone ("on their way" to the first result line, {run_wall:.2f} s wall): RTF '
              f'{max(sim) / run_wall:.2f}; start-up {underway[0]:.2f} s, report + shutdown '
              f'{wall - first_result[0]:.2f} s')


def main(argv: list[str] | None = None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument('--max-robots', type=int, default=12)
    p.add_argument('--counts', help='comma-separated robot counts (default 1,2,4,6,8,10,12 up to --max-robots)')
    p.add_argument('--seconds', type=float, default=20.0, help='measurement window per N (wall s)')
    p.add_argument('--radius', type=float, default=20.0)
    p.add_argument('--max-speed', type=float, default=2.0)
    p.add_argument('--seed', type=int, default=0)
    p.add_argument('--algorithm', default='fastep', help='the planners\' algorithm (default fastep, as in the tables '
                   'of docs/benchmarks.md; the planner node\'s own default is fastep_route)')
    p.add_argument('--step-iterations', type=int, default=0, metavar='K', help='the planners\' step_iterations '
                   '(swarm iterations of a step plan per control tick; default 0: the whole plan in one tick)')
    p.add_argument('--layout', choices=LAYOUTS, default='node', help='processes as fastep-launch --layout '
                   '(default node: one per node)')
    p.add_argument('--executor', choices=EXECUTORS, default='single', help='FASTEP_EXECUTOR of every node '
                   '(default single: rclpy\'s SingleThreadedExecutor, as before the option)')
    p.add_argument('--unstamped', action='store_true', help='cmd_vel as Twist (fastep-launch\'s default)')
    p.add_argument('--startup-timeout', type=float, default=60.0, help='wall s (plus 10 s per robot)')
    p.add_argument('--stop-after-fail', action='store_true')
    p.add_argument('--json', type=Path)
    p.add_argument('--verbose', action='store_true')
    p.add_argument('--fan-in', metavar='K,K,...', help='measure one planner\'s CPU against K other robots\' '
                   '50 Hz odometry instead (e.g. 0,3,7,11)')
    p.add_argument('--demo-rtf', action='store_true', help='measure the demo\'s real-time factor instead')
    p.add_argument('--demo', default='case_study_1')
    p.add_argument('--demo-launcher-defaults', action='store_true', help='--demo-rtf with fastep-launch\'s own '
                   'layout and executor instead of --layout / --executor')
    p.add_argument('--rtf', type=float, default=50.0)
    args = p.parse_args(argv)
    if args.demo_rtf:
        demo_rtf(args)
    elif args.fan_in:
        fan_in(args)
    else:
        scaling(args)


if __name__ == '__main__':
    main()
