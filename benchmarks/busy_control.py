"""Benchmark: a robot on wall time beside busy processes: the late control loop slows it, it meets nothing.

    python -m benchmarks.busy_control [--busy 0 8 16] [--stall 0 0.3] [--worlds wall_ahead unmapped_box] [--json OUT]

Each run is fastep_testing.robot_harness.run_world (the planner node and a simulated base as separate processes
on wall time, a 720-beam laser) with `--busy` processes spinning on the CPU beside them (the 2-core machine's
load rises by that many). One row per run: arrival, collision and least clearance against the true world, the
longest gap between commands at the base, the most lateness the planner's status gave (`late`: its worst recent
tick gap, odometry and scan age beyond what is due; fastep_core/planning/safety/lateness.py), how many statuses said the
speed was reduced for it, and the time to the goal. Targets: no collision in any row; lateness seen and the
speed reduced where commands came late. Busy processes share the CPU fairly, so the planner may stay on time
beside them; `--stall S` starves it for certain: the planner's process is stopped (SIGSTOP) for S seconds of
every `--stall-every` (a process the scheduler did not run), while the base drives on its last command.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import signal
import subprocess
import sys
import threading
from dataclasses import asdict
from pathlib import Path
from typing import Sequence

from fastep_testing.robot_harness import HarnessResult, run_world

COLUMNS = ('world', 'busy', 'stall s', 'load', 'arrived', 'collided', 'min clr m', 'longest gap s', 'most late s',
           'slowed statuses', 'to goal s')


def spinners(count: int) -> list[subprocess.Popen[bytes]]:
    """`count` processes that keep a core busy each until stopped."""
    return [subprocess.Popen([sys.executable, '-c', 'while True: pass'], stdin=subprocess.DEVNULL)
            for _ in range(count)]


def stop(processes: Sequence[subprocess.Popen[bytes]]) -> None:
    for process in processes:
        process.kill()
    for process in processes:
        process.wait()


class Staller(threading.Thread):
    """Stops this process's planner child (fastep-planner) for `stall` s of every `every` s until `done` is set."""

    def __init__(self, stall: float, every: float) -> None:
        super().__init__(daemon=True)
        self.stall, self.every, self.done, self.stalls = stall, every, threading.Event(), 0

    def planners(self) -> list[int]:
        pids = []
        for entry in Path('/proc').iterdir():
            if not entry.name.isdigit():
                continue
            try:
                ppid = int((entry / 'stat').read_text().rsplit(')', 1)[1].split()[1])
                cmdline = (entry / 'cmdline').read_bytes()
            except (OSError, IndexError, ValueError):
                continue
            if ppid == os.getpid() and (b'fastep-planner' in cmdline or b'fastep_ros.planner' in cmdline):
                pids.append(int(entry.name))
        return pids

    def run(self) -> None:
        while not self.done.wait(max(self.every - self.stall, 0.0)):
            pids = self.planners()
            for pid in pids:
                os.kill(pid, signal.SIGSTOP)
            self.done.wait(self.stall)
            for pid in pids:
                os.kill(pid, signal.SIGCONT)
            self.stalls += bool(pids)


def row(r: HarnessResult, busy: int, stall: float) -> list[str]:
    return [r.world, str(busy), f'{stall:g}', f'{r.load[0]:.1f}', 'yes' if r.arrived else f'**no** ({r.status})',
            '**yes**' if r.collided else 'no', f'{r.min_clearance:.2f}', f'{r.longest_gap:.3f}',
            f'{r.most_late:.2f}', str(r.slowed), 'n/a' if math.isnan(r.time_to_goal) else f'{r.time_to_goal:.1f}']


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog='busy_control', description=__doc__.splitlines()[0])
    parser.add_argument('--busy', type=int, nargs='+', default=[0, 8, 16], help='busy processes beside each run')
    parser.add_argument('--stall', type=float, nargs='+', default=[0.0],
                        help='s the planner is stopped, each --stall-every s (0: never)')
    parser.add_argument('--stall-every', type=float, default=1.0)
    parser.add_argument('--worlds', nargs='+', default=['wall_ahead', 'unmapped_box'])
    parser.add_argument('--timeout', type=float, default=180.0, help='s a run may take once its goal is sent')
    parser.add_argument('--json', help='write every run as JSON here')
    args = parser.parse_args(argv)
    rows, runs = [], []
    for busy in args.busy:
        for stall in args.stall:
            for world in args.worlds:
                processes = spinners(busy)
                staller = Staller(stall, args.stall_every)
                if stall > 0.0:
                    staller.start()
                try:
                    result = run_world(world, timeout=args.timeout, start_timeout=120.0)
                finally:
                    staller.done.set()
                    if staller.is_alive():
                        staller.join()
                    stop(processes)
                rows.append(row(result, busy, stall))
                runs.append({'busy': busy, 'stall': stall, 'stalls': staller.stalls, **asdict(result)})
                print(' | '.join(rows[-1]), flush=True)
    print(f'\n| {" | ".join(COLUMNS)} |\n|{"---|" * len(COLUMNS)}')
    for line in rows:
        print(f'| {" | ".join(line)} |')
    print(f'\n{os.cpu_count()} cores')
    if args.json:
        with open(args.json, 'w') as out:
            json.dump(runs, out, indent=1)
    return 1 if any(r['collided'] for r in runs) else 0


if __name__ == '__main__':
    sys.exit(main())
