"""FAStep-Route against its targets: arrival, collisions, path / optimum, compute per run against ACO's.

    python -m benchmarks.fastep_route --worlds 8 --workers 2 --out /tmp/route/families.json
    python -m benchmarks.fastep_route --families table2_s1 table2_s2 table2_s3 --worlds 10 --out /tmp/route/t2.json
    python -m benchmarks.fastep_route --markdown /tmp/route/families.json /tmp/route/t2.json
    python -m benchmarks.fastep_route --figure multi 2 docs/figures/fastep_route_worst.png

Families: sparse and dense circle fields, walls, u_traps, multi (2-4 point masses), tractor (tractor-trailers),
or any built-in scenario by name; world seed = run seed = 0..N-1, so every planner meets the same worlds.
Path / optimum: the exact shortest path keeping radius + clearance_margin (docs/optimality.md), per robot.
CPU: process time of the whole `simulate` call (load-proof); compute: the simulator's wall seconds inside the
navigators, summed over the robots. A small measuring tool for docs/fastep_route.md, not the families benchmark
(`fastep-bench --families`).
"""

from __future__ import annotations

import argparse
import json
import time
from collections import Counter
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any, Sequence

import numpy as np
import yaml
from scipy.stats import mannwhitneyu, wilcoxon

from benchmarks.clutter_diagnosis import circle_field_data
from fastep_core.experiments.random_worlds import random_scenario_data, u_trap_scenario_data
from fastep_core.planning.shortest_path.optimal import shortest_path
from fastep_core.scenario import builtin_path, parse_scenario
from fastep_core.simulator import simulate

FAMILIES = ('sparse', 'dense', 'walls', 'u_traps', 'multi', 'tractor')


def world_data(family: str, seed: int) -> dict[str, Any]:
    """The scenario mapping of world `seed` of a family (or a built-in scenario by name)."""
    if family == 'sparse':
        return circle_field_data(seed, (20, 35))
    if family == 'dense':
        return circle_field_data(seed, (40, 60))
    if family == 'walls':
        return random_scenario_data(seed, n_robots=1, tractor_share=0.0)
    if family == 'u_traps':
        return u_trap_scenario_data(seed)
    if family == 'multi':
        return random_scenario_data(seed, n_robots=2 + seed % 3, tractor_share=0.0)
    if family == 'tractor':
        return u_trap_scenario_data(seed, 'tractor_trailer') if seed % 2 == 0 else \
            random_scenario_data(seed, n_robots=1, tractor_share=1.0)
    data: dict[str, Any] = yaml.safe_load(builtin_path(family).read_text())
    return data


def run_one(job: tuple[str, int, str, dict[str, float]]) -> dict[str, Any]:
    family, seed, algorithm, planner = job
    data = world_data(family, seed)
    if planner:
        data['planner'] = {**data.get('planner', {}), **planner}
    scenario = parse_scenario(data)
    start = time.process_time()
    run = simulate(scenario, algorithm, seed)
    cpu = time.process_time() - start
    robots = []
    for robot, spec in zip(run.robots, scenario.robots):
        keep = spec.radius + scenario.planner.clearance_margin
        optimum = shortest_path(scenario.world, spec.start[:2], spec.goal, keep)
        robots.append({'name': robot.name, 'model': robot.model, 'reached': robot.reached, 'collided': robot.collided,
                       'path_length': robot.path_length, 'optimum': None if optimum is None else optimum.length,
                       'compute_time': robot.compute_time, 'sim_time': robot.sim_time,
                       'activations': robot.activations, 'escapes': robot.escapes, 'manoeuvres': robot.manoeuvres,
                       'status': robot.status})
    if algorithm == 'fastep_route':   # the route's own numbers, from a second, untimed run (same seed, same run)
        navigators: dict[str, Any] = {}
        simulate(scenario, algorithm, seed, lambda tick: navigators.setdefault(tick.name, tick.navigator))
        for robot in robots:
            nav = navigators[robot['name']]
            robot.update(route_time=nav.route_time, replans=nav.replans,
                         reasons=dict(Counter(reason for _, reason in nav.replan_log)))
    label = ' '.join([algorithm, *(f'{k}={v:g}' for k, v in planner.items())])
    return {'family': family, 'seed': seed, 'algorithm': label, 'cpu': cpu,
            'compute': sum(r['compute_time'] for r in robots), 'robots': robots}


def summary(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per family and planner: the target's numbers; CPU / ACO's is the median over worlds of the ratio."""
    out = []
    aco = {(r['family'], r['seed']): (r['cpu'], r['compute']) for r in rows if r['algorithm'] == 'aco'}
    for family in dict.fromkeys(r['family'] for r in rows):
        for algorithm in dict.fromkeys(r['algorithm'] for r in rows if r['family'] == family):
            sel = [r for r in rows if r['family'] == family and r['algorithm'] == algorithm]
            robots = [b for r in sel for b in r['robots']]
            ratios = [b['path_length'] / b['optimum'] for b in robots if b['reached'] and b['optimum']]
            worst = max(((b['path_length'] / b['optimum'], r['seed'], b['name']) for r in sel for b in r['robots']
                         if b['reached'] and b['optimum']), default=(float('nan'), -1, ''))
            vs_aco = [r['cpu'] / aco[(family, r['seed'])][0] for r in sel if (family, r['seed']) in aco]
            compute_vs_aco = [r['compute'] / aco[(family, r['seed'])][1] for r in sel if (family, r['seed']) in aco]
            out.append({
                'family': family, 'algorithm': algorithm, 'runs': len(sel), 'robots': len(robots),
                'arrived': sum(b['reached'] for b in robots), 'collided': sum(b['collided'] for b in robots),
                'ratio_mean': float(np.mean(ratios)) if ratios else float('nan'), 'ratio_worst': worst[0],
                'worst_at': f'seed {worst[1]} {worst[2]}',
                'cpu_median': float(np.median([r['cpu'] for r in sel])),
                'compute_median': float(np.median([r['compute'] for r in sel])),
                'cpu_vs_aco_median': float(np.median(vs_aco)) if vs_aco else float('nan'),
                'cpu_vs_aco_max': float(np.max(vs_aco)) if vs_aco else float('nan'),
                'compute_vs_aco_median': float(np.median(compute_vs_aco)) if compute_vs_aco else float('nan'),
                'activations': sum(b['activations'] for b in robots), 'escapes': sum(b['escapes'] for b in robots),
                'manoeuvres': sum(b['manoeuvres'] for b in robots),
                'sim_time_median': float(np.median([b['sim_time'] for b in robots if b['sim_time'] is not None]
                                                   or [float('nan')])),
            })
    return out


def _lengths(rows: list[dict[str, Any]], family: str, algorithm: str) -> dict[tuple[int, str], float]:
    """Path length of every robot of a family's runs by one planner, by (seed, robot)."""
    return {(r['seed'], b['name']): b['path_length'] for r in rows
            if r['family'] == family and r['algorithm'] == algorithm for b in r['robots']}


def path_tests(rows: list[dict[str, Any]], planner: str = 'fastep_route') -> list[str]:
    """Path length, planner against each other one: on a built-in scenario (one world, many seeds) two-sided
    Mann-Whitney U of the runs; in a family (one world per seed) two-sided Wilcoxon signed-rank of the pairs
    (same world, same seed), over every robot."""
    lines = []
    for family in dict.fromkeys(r['family'] for r in rows):
        mine = _lengths(rows, family, planner)
        for other in dict.fromkeys(r['algorithm'] for r in rows if r['family'] == family):
            theirs = _lengths(rows, family, other)
            keys = sorted(set(mine) & set(theirs))
            if other == planner or len(keys) < 2:
                continue
            a, b = np.array([mine[k] for k in keys]), np.array([theirs[k] for k in keys])
            if family in FAMILIES:
                test, p = 'Wilcoxon', float(wilcoxon(a, b).pvalue) if np.any(a != b) else 1.0
            else:
                test, p = 'Mann-Whitney', float(mannwhitneyu(a, b, alternative='two-sided').pvalue)
            lines.append(f'| {family} | {planner} {a.mean():.2f} m | {other} {b.mean():.2f} m | '
                         f'{(b.mean() - a.mean()) / b.mean() * 100:.2f} % | {p:.2g} ({test}, n = {len(keys)}) |')
    return lines


def markdown(paths: Sequence[Path]) -> str:
    rows = [row for p in paths for row in json.loads(p.read_text())['rows']]
    head = ('| family | planner | runs | robots arrived | collided | path / opt. mean | worst (where) | CPU per run '
            '(median s) | CPU / ACO\'s (median / max) | compute per run (median s) | compute / ACO\'s (median) | '
            'activations | escapes | manoeuvres | sim time (median s) |')
    lines = [head, '|' + '---|' * 15]
    for s in summary(rows):
        lines.append(f'| {s["family"]} | {s["algorithm"]} | {s["runs"]} | {s["arrived"]}/{s["robots"]} | '
                     f'{s["collided"]} | {s["ratio_mean"]:.3f} | {s["ratio_worst"]:.3f} ({s["worst_at"]}) | '
                     f'{s["cpu_median"]:.3f} | {s["cpu_vs_aco_median"]:.2f} / {s["cpu_vs_aco_max"]:.2f} | '
                     f'{s["compute_median"]:.3f} | {s["compute_vs_aco_median"]:.2f} | {s["activations"]} | '
                     f'{s["escapes"]} | {s["manoeuvres"]} | '
                     f'{s["sim_time_median"]:.1f} |')
    routed = [(r['family'], b) for r in rows if r['algorithm'] == 'fastep_route' for b in r['robots']
              if 'route_time' in b]
    if routed:
        lines += ['', '| family | robots | route wall s per robot (median / max) | replans (total / max per robot) '
                  '| why |', '|---|---|---|---|---|']
        for family in dict.fromkeys(f for f, _ in routed):
            mine = [b for f, b in routed if f == family]
            why: Counter[str] = Counter()
            for b in mine:
                why.update(b['reasons'])
            times = [b['route_time'] for b in mine]
            lines.append(f'| {family} | {len(mine)} | {np.median(times):.3f} / {max(times):.3f} | '
                         f'{sum(b["replans"] for b in mine)} / {max(b["replans"] for b in mine)} | '
                         f'{", ".join(f"{k}: {v}" for k, v in why.most_common()) or "-"} |')
    tests = path_tests(rows)
    if tests:
        lines += ['', '| family | mean path | against | shorter by | p (path) |', '|---|---|---|---|---|',
                  *tests]
    return '\n'.join(lines)


def figure(family: str, seed: int, out: Path) -> Path:
    """FAStep-Route's paths in world `seed` of a family, each robot's exact optimum dashed beside its path."""
    from msg_tools import plots  # matplotlib only for the figure

    scenario = parse_scenario(world_data(family, seed))
    run = simulate(scenario, 'fastep_route', seed)
    fig = plots.run_paths_figure(scenario, run)
    ax = fig.axes[0]
    for spec in scenario.robots:
        keep = spec.radius + scenario.planner.clearance_margin
        optimum = shortest_path(scenario.world, spec.start[:2], spec.goal, keep)
        if optimum is not None:
            xy = optimum.sample(0.05)
            ax.plot(xy[:, 0], xy[:, 1], 'k--', lw=0.9, label=f'{spec.name} optimum ({optimum.length:.1f} m)')
    ax.legend(loc='upper right', fontsize=8)
    ax.set_title(f'{family} world {seed}: FAStep-Route, seed {seed}')
    return plots.save(fig, out)


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument('--families', nargs='+', default=list(FAMILIES))
    p.add_argument('--worlds', type=int, default=8, help='worlds (seeds 0..N-1) per family')
    p.add_argument('--first', type=int, default=0, help='first seed')
    p.add_argument('--algorithms', nargs='+', default=['fastep_route', 'fastep', 'aco'])
    p.add_argument('--planner', nargs='+', default=[], metavar='NAME=VALUE',
                   help='planner parameters for every run (the rows are labelled with them)')
    p.add_argument('--workers', type=int, default=2)
    p.add_argument('--out', type=Path)
    p.add_argument('--markdown', nargs='+', type=Path, help='print the tables of earlier --out files and stop')
    p.add_argument('--figure', nargs=3, metavar=('FAMILY', 'SEED', 'OUT.png'),
                   help='draw FAStep-Route\'s paths in one world against the optimum and stop')
    args = p.parse_args()
    if args.figure:
        print(figure(args.figure[0], int(args.figure[1]), Path(args.figure[2])))
        return 0
    if args.markdown:
        print(markdown(args.markdown))
        return 0
    planner = {name: float(value) for name, value in (item.split('=', 1) for item in args.planner)}
    jobs = [(f, s, a, planner) for f in args.families for s in range(args.first, args.first + args.worlds)
            for a in args.algorithms]
    start, cpu = time.perf_counter(), time.process_time()
    with ProcessPoolExecutor(args.workers) as pool:
        rows = list(pool.map(run_one, jobs))
    meta = {'wall': time.perf_counter() - start, 'load': list(__import__('os').getloadavg()), 'jobs': len(jobs)}
    if args.out:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps({'meta': meta, 'rows': rows}) + '\n')
        print(markdown([args.out]))
    print(f'{len(jobs)} runs in {meta["wall"]:.0f} s wall, {time.process_time() - cpu:.1f} s CPU in the parent; '
          f'load average at the end {meta["load"]}')
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
