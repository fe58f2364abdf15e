"""Why FAStep-Kinematic activates its swarm so often in clutter: every activation traced and classified.

    python -m benchmarks.clutter_diagnosis --worlds 8 --workers 2 [--algorithms fastep aco] [--out out/clutter.json]

Worlds: `random_worlds.circle_field_data(seed)`, seeds 0..N-1: 20-35 circles in a 50 x 50 m workspace, one
point mass whose start and goal are at least 35 m apart, kept only if the exact planner finds a path; the run
seed is the world seed. `--world table2_s1` (or any built-in scenario) runs that scenario instead.

Per run: arrival, collisions, swarm activations (also per metre), step-optimizer and compute time, path / exact
optimum, trap escapes. For navigators that plan steps the activations are classified by what led to them
(see `classify`).
"""

from __future__ import annotations

import argparse
import json
import math
import time
from collections import Counter
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any, Sequence

import numpy as np
import yaml

from fastep_core.experiments.random_worlds import CIRCLES, circle_field_data
from fastep_core.planning import algorithms
from fastep_core.planning.navigator import FloatArray, Mode, Navigator
from fastep_core.planning.navigators.aco_kinematic import ACOKinematic
from fastep_core.planning.navigators.fastep_kinematic import FAStepKinematic
from fastep_core.planning.others import OtherRobot
from fastep_core.planning.shortest_path.optimal import shortest_path
from fastep_core.planning.swarm import step as step_module
from fastep_core.scenario import builtin_path, parse_scenario
from fastep_core.simulator import simulate


class Tracing:
    """Mixin recording every tick's decision and every swarm activation with what led to it."""

    def _trace_init(self) -> None:
        self.events: list[dict[str, Any]] = []
        self.ticks: list[tuple[float, float, float, str, bool]] = []  # t, x, y, mode, blocked-or-None
        self._ended: tuple[str, float] | None = None   # how the last waypoint ended, and when
        self._clear_since: tuple[float, FloatArray, float] | None = None   # last switch to the straight run
        self._in_choose = False
        self._tick_t = 0.0
        self._travel = 0.0
        self._last_pos: FloatArray | None = None
        self._open_step: dict[str, Any] | None = None

    def update(self, t: float, state: FloatArray, others: Sequence[OtherRobot] = ()) -> FloatArray:
        nav: Any = self
        self._tick_t = t
        pos = np.asarray(state[:2], dtype=float)
        if self._last_pos is not None:
            self._travel += float(np.hypot(*(pos - self._last_pos)))
        self._last_pos = pos.copy()
        mode_before = nav.mode
        command = Navigator.update(nav, t, state, others)
        guard_stop = bool(np.all(command == 0.0)) and nav.mode not in (Mode.ARRIVED, Mode.FAILED)
        self.ticks.append((t, float(pos[0]), float(pos[1]), nav.mode.value, guard_stop))
        if mode_before is not Mode.KINEMATIC and nav.mode is Mode.KINEMATIC:
            self._clear_since = (t, pos.copy(), self._travel)
        return command

    def keep_waypoint(self, position: FloatArray, others: Sequence[OtherRobot]) -> bool:
        nav: Any = self
        had = nav.waypoint
        keep = Navigator.keep_waypoint(nav, position, others)
        if had is not None and nav.waypoint is None:
            reached = math.hypot(*(had - position)) <= nav.params.waypoint_tolerance
            self._close_step('reached' if reached else 'robot on run', position)
        return keep

    def _close_step(self, how: str, position: FloatArray) -> None:
        self._ended = (how, self._tick_t)
        step = self._open_step
        if step is not None:
            step['ended'] = how
            step['driven'] = self._travel - step['travel0']
            step['duration'] = self._tick_t - step['t']
            step['left'] = float(np.hypot(*(np.asarray(step['waypoint']) - position)))
            self._open_step = None

    def choose_target(self, position: FloatArray, others: Sequence[OtherRobot]) -> FloatArray | None:
        nav: Any = self
        had = nav.waypoint
        self._in_choose = True
        try:
            target = super().choose_target(position, others)  # type: ignore[misc]  # a mixin: the navigator comes next
        finally:
            self._in_choose = False
        if had is not None and nav.waypoint is None and self._open_step is not None:
            self._close_step('run clear', position)
        return target

    def start_escape(self, position: FloatArray, distance: float, t: float,
                     others: Sequence[OtherRobot] = ()) -> bool:
        if self._open_step is not None:
            self._close_step('escape', position)
        return super().start_escape(position, distance, t, others)  # type: ignore[misc]  # a mixin, as above

    def plan_next_step(self, position: FloatArray, others: Sequence[OtherRobot]) -> FloatArray | None:
        nav: Any = self
        t = self._tick_t
        if self._open_step is not None:   # replanned while a waypoint was still in use
            self._close_step('replanned', position)
        before = nav.plan_time
        waypoint = Navigator.plan_next_step(nav, position, others)
        # No swarm ran (waiting to retry), or keeping right gave up and the step comes next tick: nothing yet.
        if nav.plan_time == before or nav.step_deferred:
            return waypoint
        goal = nav.goal
        obstacles = nav.world.obstacles
        surface = obstacles.distances(position)
        on_run = obstacles.path_distances(position, goal) < nav.radius + 0.5 * nav.params.clearance_margin
        blocking = (surface < nav.params.sensing_range) & on_run
        event: dict[str, Any] = {
            't': t, 'x': float(position[0]), 'y': float(position[1]), 'travel0': self._travel,
            'class': self.classify(position), 'escape': bool(nav.escaping),
            'nearest_blocking': float(surface[blocking].min()) if blocking.any() else None,
            'clearance_here': float(surface.min()) if len(surface) else None,
            'waypoint': None if waypoint is None else [float(v) for v in waypoint],
            'step': None if waypoint is None else float(np.hypot(*(waypoint - position))),
            'gain': None if waypoint is None else float(np.hypot(*(goal - position)) - np.hypot(*(goal - waypoint))),
            'ended': None,
        }
        self.events.append(event)
        if waypoint is not None:
            self._open_step = event
        return waypoint

    def classify(self, position: FloatArray) -> str:
        """What led to this activation.

        hold breaker      - the guard held the robot for another robot (not in one-robot worlds)
        escape            - during a trap escape
        stuck             - the previous waypoint lay within waypoint_tolerance of the robot when it was
                            planned, so it counted as reached on the next tick, and the run is still blocked
        chain             - the previous waypoint was reached this tick and the run is still blocked
        replan            - a waypoint was still being driven to (not reached, not dropped)
        flap              - the run to the goal was clear (waypoint dropped, straight run) less than 0.5 m
                            of travel ago, and is blocked again
        new obstacle      - blocked after a straight run of 0.5 m or more (or at the start)
        dropped by robot  - the previous waypoint was dropped because a robot moved onto its run
        aco every step    - ACO-Kinematic plans every step by design
        """
        nav: Any = self
        if not self._in_choose:
            return 'hold breaker'
        if nav.escaping:
            return 'escape'
        if isinstance(self, ACOKinematic):
            return 'aco every step'
        ended = self._ended
        if ended is not None and ended[1] == self._tick_t:
            if ended[0] == 'reached' and self.events and (self.events[-1]['step'] or 0.0) <= \
                    nav.params.waypoint_tolerance:
                return 'stuck'
            return {'reached': 'chain', 'robot on run': 'dropped by robot'}.get(ended[0], 'replan')
        if self._open_step is not None:
            return 'replan'
        if self._clear_since is not None and ended is not None and ended[0] == 'run clear' and \
                self._travel - self._clear_since[2] < 0.5:
            return 'flap'
        return 'new obstacle'


class TracingFAStep(Tracing, FAStepKinematic):
    def __init__(self, *args: Any, **kwargs: Any) -> None:
        FAStepKinematic.__init__(self, *args, **kwargs)
        self._trace_init()


class TracingACO(Tracing, ACOKinematic):
    def __init__(self, *args: Any, **kwargs: Any) -> None:
        ACOKinematic.__init__(self, *args, **kwargs)
        self._trace_init()


TRACED: dict[str, type[Navigator]] = {'fastep': TracingFAStep, 'aco': TracingACO}
EVALUATIONS: list[int] = []   # fitness evaluations of every swarm run of the current run (a load-free cost)


def _counting(optimizer: Any) -> Any:
    def run(*args: Any, **kwargs: Any) -> Any:
        result = optimizer(*args, **kwargs)
        EVALUATIONS.append(result.nfev)
        return result
    return run


step_module.fastep = _counting(step_module.fastep)  # type: ignore[attr-defined]  # counted in this process only
step_module.aco_r = _counting(step_module.aco_r)  # type: ignore[attr-defined]  # counted in this process only


def world_data(world: str, seed: int, circles: tuple[int, int]) -> dict[str, Any]:
    """'circles': circle field `seed`; otherwise a built-in scenario by name (the same world for every seed)."""
    if world == 'circles':
        return circle_field_data(seed, circles)
    data: dict[str, Any] = yaml.safe_load(builtin_path(world).read_text())
    return data


def run_one(job: tuple[str, int, str, dict[str, Any], tuple[int, int]]) -> dict[str, Any]:
    world, seed, algorithm, overrides, circles = job
    data = world_data(world, seed, circles)
    if overrides:
        data['planner'] = {**data.get('planner', {}), **overrides}
    scenario = parse_scenario(data)
    spec = scenario.robots[0]
    captured: list[Navigator] = []
    original = algorithms.NAVIGATORS[algorithm]
    traced = TRACED.get(algorithm)

    def factory(*args: Any, **kwargs: Any) -> Navigator:
        nav = (traced or original)(*args, **kwargs)
        captured.append(nav)
        return nav

    algorithms.NAVIGATORS[algorithm] = factory  # type: ignore[assignment]  # a factory in the class's place
    EVALUATIONS.clear()
    try:
        start = time.process_time()
        run = simulate(scenario, algorithm, seed)
        cpu = time.process_time() - start
    finally:
        algorithms.NAVIGATORS[algorithm] = original
    robot = run.robots[0]
    optimum = shortest_path(scenario.world, spec.start[:2], spec.goal, spec.radius + scenario.planner.clearance_margin)
    nav: Any = captured[0]
    events = getattr(nav, 'events', [])
    steps = [e for e in events if e['step'] is not None]
    return {
        'seed': seed, 'algorithm': algorithm, 'overrides': overrides, 'circles': len(data['obstacles']),
        'family': f'{circles[0]}-{circles[1]} circles' if world == 'circles' else world,
        'straight': float(np.hypot(*(np.asarray(spec.goal) - np.asarray(spec.start[:2])))),
        'optimum': None if optimum is None else optimum.length,
        'reached': robot.reached, 'collided': robot.collided, 'min_clearance': robot.min_clearance,
        'path_length': robot.path_length, 'sim_time': robot.sim_time, 'compute_time': robot.compute_time,
        'plan_time': robot.plan_time, 'cpu_time': cpu, 'evaluations': sum(EVALUATIONS),
        'swarm_runs': len(EVALUATIONS), 'activations': robot.activations,
        'escapes': robot.escapes, 'status': robot.status,
        'classes': dict(Counter(e['class'] for e in events)),
        'ended': dict(Counter(str(e['ended']) for e in steps)),
        'step_median': float(np.median([e['step'] for e in steps])) if steps else None,
        'driven_median': float(np.median([e['driven'] for e in steps if 'driven' in e])) if steps else None,
        'gain_median': float(np.median([e['gain'] for e in steps])) if steps else None,
        'events': events,
        'guard_stop_ticks': sum(1 for tick in getattr(nav, 'ticks', []) if tick[4]),
        'escape_times': [e['t'] for e in events if e['class'] == 'escape'][:1],
    }


def summary(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    out = []
    keys = sorted({(r['family'], r['algorithm'], json.dumps(r['overrides'], sort_keys=True)) for r in rows})
    for family, algorithm, overrides in keys:
        sel = [r for r in rows if r['family'] == family and r['algorithm'] == algorithm and
               json.dumps(r['overrides'], sort_keys=True) == overrides]
        ratio = [r['path_length'] / r['optimum'] for r in sel if r['reached'] and r['optimum']]
        classes: Counter[str] = Counter()
        for r in sel:
            classes.update(r['classes'])
        out.append({
            'family': family, 'algorithm': algorithm, 'overrides': overrides, 'runs': len(sel),
            'arrived': sum(r['reached'] for r in sel), 'collided': sum(r['collided'] for r in sel),
            'activations_median': float(np.median([r['activations'] for r in sel])),
            'activations_per_m': float(np.median([r['activations'] / max(r['path_length'], 1e-9) for r in sel])),
            'plan_time_median': float(np.median([r['plan_time'] for r in sel])),
            'compute_median': float(np.median([r['compute_time'] for r in sel])),
            'cpu_median': float(np.median([r['cpu_time'] for r in sel])),
            'evaluations_median': float(np.median([r['evaluations'] for r in sel])),
            'evaluations_per_activation': float(sum(r['evaluations'] for r in sel) /
                                                max(1, sum(r['activations'] for r in sel))),
            'path_opt_mean': float(np.mean(ratio)) if ratio else None,
            'path_opt_worst': float(np.max(ratio)) if ratio else None,
            'sim_time_median': float(np.median([r['sim_time'] or math.nan for r in sel])),
            'escapes': sum(r['escapes'] for r in sel), 'runs_with_escape': sum(r['escapes'] > 0 for r in sel),
            'classes': dict(classes),
        })
    return out


def markdown(paths: Sequence[Path]) -> str:
    """Markdown tables of one or more --out files: one row per family and configuration."""
    rows = [r for path in paths for r in json.loads(Path(path).read_text())['runs']]
    lines = ['| world | planner | arrived | collided | activations (median / max / total) | act. per m (median) | '
             'plan time (median / mean s) | compute (median / mean s) | CPU (median / mean s) | '
             'CPU / ACO\'s (median of worlds) | evaluations per activation | path / opt. (mean / worst) | '
             'runs with escape | sim time (median s) |',
             '|' + '---|' * 14]
    aco_cpu = {(r['family'], r['seed']): r['cpu_time'] for r in rows if r['algorithm'] == 'aco'}
    for row in summary(rows):
        sel = [r for r in rows if r['family'] == row['family'] and r['algorithm'] == row['algorithm'] and
               json.dumps(r['overrides'], sort_keys=True) == row['overrides']]
        name = row['algorithm'] if row['overrides'] == '{}' else \
            f"{row['algorithm']} " + ', '.join(f'{k}={v:g}' for k, v in json.loads(row['overrides']).items())
        ratios = [r['cpu_time'] / aco_cpu[r['family'], r['seed']] for r in sel if (r['family'], r['seed']) in aco_cpu]
        ratio = f'{np.median(ratios):.2f}' if ratios else '-'
        lines.append(
            f"| {row['family']} | {name} | {row['arrived']}/{row['runs']} | {row['collided']} | "
            f"{row['activations_median']:g} / {max(r['activations'] for r in sel)} / "
            f"{sum(r['activations'] for r in sel)} | {row['activations_per_m']:.3f} | "
            f"{row['plan_time_median']:.3f} / {np.mean([r['plan_time'] for r in sel]):.3f} | "
            f"{row['compute_median']:.3f} / {np.mean([r['compute_time'] for r in sel]):.3f} | "
            f"{row['cpu_median']:.3f} / {np.mean([r['cpu_time'] for r in sel]):.3f} | {ratio} | "
            f"{row['evaluations_per_activation']:.0f} | {row['path_opt_mean']:.3f} / {row['path_opt_worst']:.3f} | "
            f"{row['runs_with_escape']} | {row['sim_time_median']:.1f} |")
    return '\n'.join(lines)


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument('--worlds', type=int, default=8)
    p.add_argument('--first', type=int, default=0)
    p.add_argument('--world', default='circles',
                   help="'circles' (circle fields, seeds FIRST..FIRST+WORLDS-1) or a built-in scenario name "
                        "(e.g. table2_s2: run seeds FIRST..FIRST+WORLDS-1)")
    p.add_argument('--circles', type=int, nargs=2, default=list(CIRCLES), metavar=('LOW', 'HIGH'),
                   help='circles per world, drawn uniformly from LOW..HIGH (default 20 35)')
    p.add_argument('--algorithms', nargs='+', default=['fastep', 'aco'])
    p.add_argument('--config', action='append', default=[], metavar='NAME=VALUE[,NAME=VALUE...]',
                   help='an extra fastep configuration by planner overrides, e.g. --config '
                        'plan_horizon=2,stuck_steps=1 (repeatable)')
    p.add_argument('--workers', type=int, default=2)
    p.add_argument('--out', type=Path, default=Path('out/clutter_diagnosis.json'))
    p.add_argument('--markdown', type=Path, nargs='+', metavar='OUT.json',
                   help='print the tables of earlier --out files as markdown and exit')
    args = p.parse_args()
    if args.markdown:
        print(markdown(args.markdown))
        return 0
    configs: list[tuple[str, dict[str, Any]]] = [(a, {}) for a in args.algorithms]
    for config in args.config:
        overrides = {k: float(v) for k, v in (item.split('=', 1) for item in config.split(','))}
        configs.append(('fastep', overrides))
    circles = (args.circles[0], args.circles[1])
    seeds = range(args.first, args.first + args.worlds)
    jobs = [(args.world, seed, a, o, circles) for a, o in configs for seed in seeds]
    with ProcessPoolExecutor(args.workers) as pool:
        rows = list(pool.map(run_one, jobs))
    table = summary(rows)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps({'table': table, 'runs': rows}, indent=1))
    for r in rows:
        ratio = r['path_length'] / r['optimum'] if r['optimum'] else math.nan
        print(f"{r['family'][:12]:12s} {r['algorithm']:6s} {json.dumps(r['overrides']):30s} seed {r['seed']:2d} "
              f"obstacles {r['circles']:2d} arr {r['reached']!s:5s} col {r['collided']!s:5s} "
              f"act {r['activations']:4d} plan {r['plan_time']:.3f}s cmp {r['compute_time']:.3f}s "
              f"cpu {r['cpu_time']:.3f}s nfev {r['evaluations']} path/opt {ratio:.3f} esc {r['escapes']} "
              f"classes {r['classes']} ended {r['ended']} step {r['step_median']} driven {r['driven_median']}")
    for row in table:
        print(json.dumps(row))
    return 0


if __name__ == '__main__':
    raise SystemExit(main())

