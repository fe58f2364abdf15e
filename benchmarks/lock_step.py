"""Lock-step runs of fastep-launch: wall time of the whole command, and whether the run is fastep-sim's.

    python -m benchmarks.lock_step                                   # make demo's run, each executor x layout
    python -m benchmarks.lock_step --robots 16 --layouts graph robot --executors events
    python -m benchmarks.lock_step --scenario case_study_1 --algorithm fastep --record

Each row runs `python -m fastep_ros.launch SCENARIO --rtf RTF --seed 0 --json ...` with the interpreter and
PYTHONPATH of this process (so the code under test is the one PYTHONPATH points at: run it with another
checkout's path to measure that one) and times it from outside: the whole command (what a user waits for),
start-up (until the launcher says the robots are on their way) and the run (until it reports the last robot),
and the CPU seconds (user + system) of the command and every process it started.
RTF is simulated time (the last arrival) over each. `exact` compares every robot with `fastep-sim` of the same
scenario, algorithm and seed: the arrival time, path length and clearance as --json rounds them, and the
position at every time both trajectories hold a row (`max |d|`). The load average is read before each row.
--robots N runs benchmarks.graph_scaling's circle of N robots swapping places instead of a scenario.

--targets runs the two runs the project's speed targets name, each recorded, in the launcher's default layout and
executor, beside `fastep-sim` of the same run (its whole command timed too), and prints each one's real-time
factor, its target and the launch's wall time over fastep-sim's:

    python -m benchmarks.lock_step --targets     # make demo's launch (>= 20x whole), 16 robots (>= 2x)
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from fastep_core.scenario import load_scenario
from fastep_core.simulator import simulate
from fastep_testing.runs import circle_yaml, compare


def result_path(out: Path, layout: str | None, executor: str | None) -> Path:
    """Where run() has fastep-launch write its --json for `layout` x `executor` (None: the default)."""
    return out / f'{layout}_{executor}.json'


def circle_scenario(out: Path, robots: int, step_iterations: int = 0) -> str:
    """benchmarks.graph_scaling's circle of `robots` robots swapping places, written in `out`: its path."""
    scenario = out / f'circle_{robots}.yaml'
    scenario.write_text(circle_yaml(robots, 20.0, 2.0, step_iterations))
    return str(scenario)


def run(scenario: str, algorithm: str, layout: str | None, executor: str | None, rtf: float, record: bool,
        out: Path) -> dict[str, Any]:
    """One fastep-launch row; layout / executor None: the launcher's default."""
    result = result_path(out, layout, executor)
    cmd = [sys.executable, '-m', 'fastep_ros.launch', scenario, '--algorithm', algorithm, '--rtf', str(rtf),
           '--seed', '0', '--no-progress', '--json', str(result)]
    cmd += ['--layout', layout] if layout is not None else []
    cmd += ['--executor', executor] if executor is not None else []
    if record:
        cmd += ['--record', str(out / f'{layout}_{executor}.mcap')]
    load = os.getloadavg()[0]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    started = finished = None
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            stdin=subprocess.DEVNULL)
    assert proc.stdout is not None
    for line in proc.stdout:
        if 'on their way' in line:
            started = time.perf_counter() - start
        elif ': arrived' in line or ': failed' in line or ': timeout' in line:
            finished = time.perf_counter() - start if finished is None else finished
    code = proc.wait()
    whole = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    # The launcher waits for every node process it starts, so their CPU is in its children's usage.
    cpu = after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime
    row: dict[str, Any] = {'layout': layout, 'executor': executor, 'code': code, 'load': round(load, 2),
                           'whole_s': round(whole, 2), 'cpu_s': round(cpu, 2)}
    if started is not None and finished is not None and result.is_file():
        robots = json.loads(result.read_text())['runs'][0]['robots']
        simulated = max(r['sim_time'] or 0.0 for r in robots)
        row.update(simulated_s=simulated, startup_s=round(started, 2), run_s=round(finished - started, 2),
                   rtf_whole=round(simulated / whole, 2), rtf_run=round(simulated / (finished - started), 2),
                   arrived=sum(r['reached'] for r in robots), robots=len(robots))
    return row


def sim_robots(scenario: str, algorithm: str) -> list[dict[str, Any]]:
    """fastep-sim's robots of the same run (--json's form), the reference of `exact`."""
    run: dict[str, Any] = simulate(load_scenario(scenario), algorithm, 0).to_json()
    robots: list[dict[str, Any]] = run['robots']
    return robots


def sim_seconds(scenario: str, algorithm: str, out: Path) -> float:
    """Wall seconds of the whole `fastep-sim` command of the same run (its own process, as a user runs it)."""
    start = time.perf_counter()
    subprocess.run([sys.executable, '-m', 'msg_tools.sim_cli', scenario, '--algorithm', algorithm, '--seed', '0',
                    '--json', str(out / 'sim.json')], check=True, stdout=subprocess.DEVNULL, stdin=subprocess.DEVNULL)
    return time.perf_counter() - start


TARGETS = (('make demo\'s launch', 'case_study_1', 'fastep', 0, 'rtf_whole', 20.0),
           ('16 robots swapping places', '', 'fastep_route', 16, 'rtf_run', 2.0))


def targets(rtf: float, out: Path) -> list[dict[str, Any]]:
    """The TARGETS rows: recorded, default layout and executor, beside fastep-sim."""
    rows = []
    for label, scenario, algorithm, robots, measure, target in TARGETS:
        where = out / (scenario or f'circle_{robots}')
        where.mkdir()
        if robots:
            scenario = circle_scenario(where, robots)
        reference = sim_robots(scenario, algorithm)
        row = run(scenario, algorithm, None, None, rtf, True, where)
        result = result_path(where, None, None)
        if result.is_file():
            row['exact'], row['max_d'] = compare(json.loads(result.read_text())['runs'][0]['robots'], reference)
        row['sim_s'] = round(sim_seconds(scenario, algorithm, where), 2)
        row.update(run_of=label, target=f'{measure} >= {target:g}', met=row.get(measure, 0.0) >= target,
                   launch_over_sim=round(row['whole_s'] / row['sim_s'], 2))
        rows.append(row)
        print(json.dumps(row), flush=True)
    return rows


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog='python -m benchmarks.lock_step', description=__doc__.split('\n')[0])
    p.add_argument('--scenario', default='case_study_1')
    p.add_argument('--robots', type=int, default=0, help='the circle of N robots of benchmarks.graph_scaling')
    p.add_argument('--algorithm', default='fastep')
    p.add_argument('--step-iterations', type=int, default=0, metavar='K', help='with --robots: the planners\' '
                   'step_iterations (default 0: a step plan in one tick)')
    p.add_argument('--rtf', type=float, default=50.0)
    p.add_argument('--layouts', nargs='+', default=['robot', 'graph', 'node'])
    p.add_argument('--executors', nargs='+', default=['events', 'single'])
    p.add_argument('--record', action='store_true', help='record each run, as make demo does')
    p.add_argument('--json', type=Path, help='write the rows here')
    p.add_argument('--targets', action='store_true', help='make demo\'s launch and 16 robots, recorded, beside '
                   'fastep-sim, against their targets (the other options but --rtf and --json unused)')
    args = p.parse_args(argv)
    out = Path(tempfile.mkdtemp(prefix='lock_step_'))
    if args.targets:
        rows = targets(args.rtf, out)
        if args.json is not None:
            args.json.write_text(json.dumps({'rtf': args.rtf, 'rows': rows}, indent=1))
        return 0
    scenario = args.scenario
    if args.robots:
        scenario = circle_scenario(out, args.robots, args.step_iterations)
    reference = sim_robots(scenario, args.algorithm)
    rows = []
    for executor in args.executors:
        for layout in args.layouts:
            row = run(scenario, args.algorithm, layout, executor, args.rtf, args.record, out)
            result = result_path(out, layout, executor)
            if result.is_file():
                row['exact'], row['max_d'] = compare(json.loads(result.read_text())['runs'][0]['robots'], reference)
            rows.append(row)
            print(json.dumps(row), flush=True)
    if args.json is not None:
        args.json.write_text(json.dumps({'scenario': scenario, 'algorithm': args.algorithm, 'rtf': args.rtf,
                                         'rows': rows}, indent=1))
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
