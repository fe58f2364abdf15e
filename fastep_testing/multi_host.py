"""Robots on separate computers: fastep-launch with its hosts in Linux network namespaces (fastep_testing.hosts).

    python -m benchmarks.multi_host --hosts 2 --robots 4 [--radius 20]   # as root
    python -m benchmarks.multi_host --hosts 3 --robots 4 --peers    # discovery by ROS_STATIC_PEERS, multicast off
    python -m benchmarks.multi_host --hosts 3 --robots 4 --no-clock --drop 2 --drop-for 3   # a link drops out

Host 0 runs fastep-launch, the map, the clock and the recorder; each robot's plant and planner run on host
1 + i mod (hosts - 1). Between hosts DDS goes over the bridge and UDP only (no shared memory), found by multicast
or, with --peers, through ROS_STATIC_PEERS. In lock step (the default) the run is compared with fastep-sim's tick
for tick. --drop K takes host K's link down for --drop-for seconds (on wall time, --no-clock). Exit 0 only if
every robot arrived (and, in lock step, the run is fastep-sim's), 2 for what cannot be set up (not root, no `ip`).
Details: docs/multi_host.md.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any, Sequence

from fastep_testing.hosts import Hosts, HostsError

ROOT = Path(__file__).resolve().parent.parent
SET_OFF = 'robot(s) on their way'   # fastep-launch's line when the goals are out and time runs


def placement_hosts(robots: Sequence[str], hosts: int) -> dict[str, int]:
    """The host of each robot (by name): hosts 1.. in turn, host 0 when there is only one."""
    return {name: (1 + i % (hosts - 1)) if hosts > 1 else 0 for i, name in enumerate(robots)}


def _inside(config: dict[str, Any]) -> int:
    """On host 0: fastep-launch, each robot's process started on its host."""
    from fastep_ros.launch import main as launch_main
    from fastep_ros.layouts import Member

    prefixes: dict[str, list[str]] = config['prefixes']   # robot namespace ('/r1') -> its command prefix

    def placement(members: Sequence[Member]) -> list[str]:
        return prefixes.get(members[0].namespace, [])
    return launch_main(config['argv'], placement)


def _drop_link(hosts: Hosts, k: int, after: float, seconds: float, log: list[str]) -> None:
    time.sleep(after)
    hosts.drop(k)
    log.append(f'host {k} link down at {time.monotonic():.2f}')
    time.sleep(seconds)
    hosts.restore(k)
    log.append(f'host {k} link up at {time.monotonic():.2f}')


def largest_gap(trajectory: list[list[float]], end: float | None) -> float:
    """The longest time between two odometry rows the launcher got up to `end` (the robot's arrival; None: all),
    from time 0 on: what a dropped link kept from it."""
    times = [row[0] for row in trajectory if row[0] >= 0.0 and (end is None or row[0] <= end)]
    return max((b - a for a, b in zip(times, times[1:])), default=0.0)


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog='python -m benchmarks.multi_host', description=__doc__.split('\n')[0])
    p.add_argument('--hosts', type=int, default=2, help='hosts (network namespaces), the map on the first (default 2)')
    p.add_argument('--robots', type=int, default=4, help='robots of the circle scenario (default 4)')
    p.add_argument('--radius', type=float, default=20.0, help='radius of the circle the robots cross (m, default 20)')
    p.add_argument('--scenario', help='a built-in name or scenario file instead of the circle')
    p.add_argument('--algorithm', default='fastep_route', help='planner (default fastep_route)')
    p.add_argument('--seed', type=int, default=0)
    p.add_argument('--rtf', type=float, default=10.0, help='lock step: real-time factor at most (default 10)')
    p.add_argument('--no-clock', action='store_true', help='wall time: every node on its own clock, as on robots')
    p.add_argument('--peers', action='store_true', help='multicast off on every link: discovery by ROS_STATIC_PEERS')
    p.add_argument('--drop', type=int, metavar='K', help='take host K\'s link down during the run')
    p.add_argument('--drop-at', type=float, default=2.0, help='wall seconds after the robots set off (default 2)')
    p.add_argument('--drop-for', type=float, default=3.0, help='wall seconds the link stays down (default 3)')
    p.add_argument('--json', type=Path, help='fastep-launch\'s JSON, and this harness\'s findings under "multi_host"')
    p.add_argument('--inside', help=argparse.SUPPRESS)
    return p


def main(argv: Sequence[str] | None = None) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    if args.inside:
        return _inside(json.loads(args.inside))
    if args.hosts < 1 or args.robots < 1:
        parser.error('--hosts and --robots must be >= 1')
    if not 1.0 <= args.radius <= 24.0:
        parser.error(f'--radius must be in [1, 24] m (the circle lies in a 50 m square), got {args.radius:g}')
    if args.drop is not None and not 0 <= args.drop < args.hosts:
        parser.error(f'--drop must be a host in 0..{args.hosts - 1}, got {args.drop}')
    from fastep_core.scenario import load_scenario

    with tempfile.TemporaryDirectory(prefix='fastep_multi_host_') as tmp:
        if args.scenario:
            source = args.scenario
        else:
            from fastep_testing.runs import circle_yaml
            source = str(Path(tmp) / f'circle_{args.robots}.yaml')
            Path(source).write_text(circle_yaml(args.robots, args.radius, 2.0))
        try:
            scenario = load_scenario(source)
        except Exception as exc:   # a FastepError: its own line
            print(f'multi_host: error: {exc}', file=sys.stderr)
            return 2
        out = args.json or Path(tmp) / 'run.json'
        try:
            with Hosts(args.hosts, multicast=not args.peers) as hosts:
                return _run(args, hosts, source, scenario, out)
        except HostsError as exc:
            print(f'multi_host: error: {exc}', file=sys.stderr)
            return 2


def _run(args: argparse.Namespace, hosts: Hosts, source: str, scenario: Any, out: Path) -> int:
    names = [spec.name for spec in scenario.robots]
    where = placement_hosts(names, args.hosts)
    launch_argv = [source, '--layout', 'robot', '--algorithm', args.algorithm, '--seed', str(args.seed),
                   '--no-progress', '--json', str(out)]
    launch_argv += ['--no-clock'] if args.no_clock else ['--rtf', str(args.rtf)]
    config = {'argv': launch_argv,
              'prefixes': {f'/{name}': hosts.exec_prefix(k) if k else [] for name, k in where.items()}}
    env = dict(os.environ, FASTDDS_BUILTIN_TRANSPORTS='UDPv4', ROS_AUTOMATIC_DISCOVERY_RANGE='SUBNET',
               PYTHONPATH=os.pathsep.join(p for p in (str(ROOT), os.environ.get('PYTHONPATH', '')) if p))
    if args.peers:
        env['ROS_STATIC_PEERS'] = hosts.peers
    else:
        env.pop('ROS_STATIC_PEERS', None)
    print(f'multi_host: {args.hosts} host(s) on a bridge ({", ".join(hosts.addresses)}), discovery by '
          f'{"ROS_STATIC_PEERS, multicast off" if args.peers else "multicast"}; the map on host 0, '
          + ', '.join(f'{name} on host {k}' for name, k in where.items()), flush=True)
    cmd = [*hosts.exec_prefix(0), sys.executable, '-m', 'fastep_testing.multi_host', '--inside', json.dumps(config)]
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            stdin=subprocess.DEVNULL, cwd=ROOT)
    drops: list[str] = []
    dropper: threading.Thread | None = None
    assert proc.stdout is not None
    try:
        for line in proc.stdout:
            if args.json is not None or line.strip() != f'wrote {out}':   # (not a temporary file's name)
                print(line, end='', flush=True)
            if SET_OFF in line and args.drop is not None and dropper is None:
                dropper = threading.Thread(target=_drop_link, args=(hosts, args.drop, args.drop_at, args.drop_for,
                                                                     drops), daemon=True)
                dropper.start()
        code = proc.wait()
    except KeyboardInterrupt:
        proc.terminate()   # the launcher stops its nodes on SIGTERM as on Ctrl-C
        proc.wait()
        return 1
    finally:
        if dropper is not None:
            dropper.join()
    return _judge(args, code, source, out, drops)


def _judge(args: argparse.Namespace, code: int, source: str, out: Path, drops: list[str]) -> int:
    """The harness's line: the run against fastep-sim's (lock step), what a dropped link left out."""
    if not out.is_file():
        print(f'multi_host: fastep-launch wrote no results (exit {code})')
        return code or 1
    data = json.loads(out.read_text())
    robots = data['runs'][0]['robots']
    findings: dict[str, Any] = {'hosts': args.hosts, 'peers': args.peers, 'launch_exit': code}
    if args.drop is not None:
        findings['drop'] = {'host': args.drop, 'at': args.drop_at, 'for': args.drop_for, 'events': drops,
                            'largest_odometry_gap': {r['name']: round(largest_gap(r['trajectory'], r['sim_time']), 3)
                                                     for r in robots}}
        print(f'multi_host: host {args.drop}\'s link down for {args.drop_for:g} s; min clearance '
              + ', '.join(f'{r["name"]} {r["min_clearance"]:.2f} m' for r in robots)
              + '; longest odometry gap at the launcher '
              + ', '.join(f'{k} {v:.2f} s' for k, v in findings['drop']['largest_odometry_gap'].items()))
    same = True
    if not args.no_clock:
        from fastep_core.scenario import load_scenario
        from fastep_core.simulator import simulate
        from fastep_testing.runs import compare
        reference = simulate(load_scenario(source), args.algorithm, args.seed).to_json()['robots']
        same, worst = compare(robots, reference)
        findings['same_as_fastep_sim'], findings['max_position_difference'] = same, worst
        print(f'multi_host: the run is {"" if same else "NOT "}fastep-sim\'s (largest position difference '
              f'{worst:.2g} m)')
    if args.json is not None:
        data['multi_host'] = findings
        args.json.write_text(json.dumps(data, indent=1))
    return code if code else (0 if same else 1)


if __name__ == '__main__':
    raise SystemExit(main())
