"""fastep-sim: run a scenario in-process (no ROS) and report what every robot did.

    fastep-sim SCENARIO [--algorithm fastep|aco] [--seed N] [--runs K] [--json OUT] [--plot OUT.png]
               [--mcap OUT.mcap]
    fastep-sim --list

Exit 0 when the runs were simulated (arrived or not), 2 with one line on stderr for bad input.

Why here and not in fastep_core: the simulation is fastep_core's, but --plot draws with msg_tools.plots and
--mcap records ROS messages with msg_tools.sim_mcap, and fastep_core imports nothing above itself.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Sequence

from fastep_core.cli import Parser, fail, guard, positive_int, seed
from fastep_core.planning.algorithms import ALGORITHMS
from fastep_core.scenario import builtin_names, load_scenario
from fastep_core.simulator import Run, simulate

__all__ = ['main']

PROG = 'fastep-sim'


def _parser() -> argparse.ArgumentParser:
    p = Parser(prog=PROG, description='Simulate a scenario with FAStep-Kinematic or ACO-Kinematic.')
    p.add_argument('scenario', nargs='?', help='scenario YAML file or built-in name (see --list)')
    p.add_argument('--algorithm', choices=ALGORITHMS, default='fastep', help='planner (default: fastep)')
    p.add_argument('--seed', type=seed, default=0, help='seed of the first run (default: 0)')
    p.add_argument('--runs', type=positive_int, default=1,
                   help='number of runs, seeds seed..seed+runs-1 (default: 1)')
    p.add_argument('--json', type=Path, metavar='OUT', help='write all runs as JSON')
    p.add_argument('--plot', type=Path, metavar='OUT.png', help='draw the first run like the paper\'s Fig. 2')
    p.add_argument('--mcap', type=Path, metavar='OUT.mcap',
                   help='record the first run as MCAP with the topics of a live run (msg_tools.sim_mcap)')
    p.add_argument('--list', action='store_true', help='list built-in scenarios and exit')
    return p


def _summary(run: Run) -> str:
    lines = []
    for r in run.robots:
        state = 'arrived' if r.reached else 'NOT arrived'
        when = f'{r.sim_time:.1f} s' if r.sim_time is not None else '-'
        lines.append(f'seed {run.seed} {r.name}: {state}{" COLLIDED" if r.collided else ""}, '
                     f'path {r.path_length:.2f} m, time {when}, compute {r.compute_time * 1e3:.0f} ms, '
                     f'min clearance {r.min_clearance:.2f} m, activations {r.activations} ({r.status})')
    return '\n'.join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    return guard(PROG, lambda: _run(argv))


def _run(argv: Sequence[str] | None) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    if args.list:
        print('\n'.join(builtin_names()))
        return 0
    if args.scenario is None:
        parser.error('a SCENARIO is required (a YAML file or one of: ' + ', '.join(builtin_names()) + ')')
    # A FastepError from here on (a bad scenario; RecordingError: the MCAP file cannot be written) is guard's
    # one line and exit 2.
    scenario = load_scenario(args.scenario)
    recorder = None
    if args.mcap is not None:
        try:  # the ROS message packages only when a recording is asked for
            from msg_tools.sim_mcap import SimRecorder
        except ImportError as exc:
            return fail(PROG, f'--mcap needs the ROS 2 message packages: {exc}')
        recorder = SimRecorder(scenario, args.algorithm, args.seed)
    runs = [simulate(scenario, args.algorithm, seed,
                     observer=recorder.observe if recorder is not None and seed == args.seed else None)
            for seed in range(args.seed, args.seed + args.runs)]
    for run in runs:
        print(_summary(run))
    try:
        if args.json is not None:
            doc = {'scenario': scenario.name, 'algorithm': args.algorithm, 'runs': [r.to_json() for r in runs]}
            args.json.parent.mkdir(parents=True, exist_ok=True)
            args.json.write_text(json.dumps(doc) + '\n')
            print(f'wrote {args.json}')
        if args.plot is not None:
            from msg_tools.plots import plot_paths  # matplotlib only when a figure is asked for
            args.plot.parent.mkdir(parents=True, exist_ok=True)
            plot_paths(scenario, runs[0], args.plot)
            print(f'wrote {args.plot}')
        if recorder is not None:
            recorder.finish(runs[0])
            args.mcap.parent.mkdir(parents=True, exist_ok=True)
            count = recorder.write(args.mcap)
            print(f'wrote {args.mcap} ({count} messages of the run with seed {args.seed})')
    except OSError as exc:
        return fail(PROG, f'cannot write output: {exc}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
