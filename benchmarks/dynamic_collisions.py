"""What the collisions of a v2 families run were: for every robot run that collided, rerun it and report the
first contact, judged against the truth: with what (a mover, known or only tracked; a still obstacle, known,
unknown or misplaced; another robot), how (the robot standing, or the mover coming from the side, head on, from
behind), and what the robot believed then (did it track the mover, did it believe in the obstacle).

Run: `PYTHONPATH=. .venv/bin/python -m benchmarks.dynamic_collisions FAMILIES.json [...]` on the --json output of
`fastep-bench --families ...` (the rows of runs that collided are rerun; a run is deterministic per seed).
"""

from __future__ import annotations

import argparse
import json
import math
from collections import Counter
from typing import Any

import numpy as np

from fastep_core.dynamic_world import DynamicWorld
from fastep_core.experiments.batches import cached_scenario
from fastep_core.experiments.random_worlds import family_source
from fastep_core.simulator import Tick, simulate


def first_contact(source: str, algorithm: str, seed: int, robot: str) -> dict[str, Any]:
    scenario = cached_scenario(source)
    truth = DynamicWorld(scenario.world.workspace, scenario.obstacle_specs)
    specs = {s.name: s for s in scenario.robots}
    radius = specs[robot].radius
    positions: dict[str, np.ndarray] = {s.name: np.array(s.start[:2], dtype=float) for s in scenario.robots}
    found: dict[str, Any] = {}

    def observe(tick: Tick) -> None:
        positions[tick.name] = np.array(tick.state[:2])
        if tick.name != robot or found:
            return
        p = tick.state[:2]
        speed = float(np.hypot(*tick.velocity[:2]))
        still = truth.still.obstacles
        if len(still):
            d = still.distances(p) - radius
            k = int(np.argmin(d))
            if d[k] < 0.0:
                item = still.items[k]
                spec = next(o for o in scenario.obstacle_specs if o.still and o.shape == item)
                kind = 'unknown' if not spec.known else 'misplaced' if spec.position_sigma > 0 else 'known'
                # Believed: the robot's belief has a surface within radius + 0.5 m of its centre.
                believed = tick.belief is not None and len(tick.belief.world.obstacles) > 0 and \
                    float(tick.belief.world.obstacles.clearance(p)) < radius + 0.5
                found.update(what=f'{kind} still {type(item).__name__.lower()}', how='moving' if speed > 0.05
                             else 'standing', believed=believed, t=tick.t, depth=float(-d[k]))
                return
        if len(truth.movers):
            centres = truth.movers.positions(tick.t)
            d = np.hypot(*(centres - p).T) - truth.movers.radii - radius
            k = int(np.argmin(d))
            if d[k] < 0.0:
                v_m = truth.movers.velocities(tick.t)[k]
                index = truth.movers.indices[k]
                known = scenario.obstacle_specs[index].known
                if speed <= 0.05:
                    how = 'robot standing, mover runs into it'
                else:
                    heading = tick.velocity[:2] / speed
                    c = float(np.dot(heading, v_m) / max(np.hypot(*v_m), 1e-9))
                    how = 'mover crossing from the side' if abs(c) < 0.5 else 'head on' if c < 0 else \
                        'mover going the robot\'s way (within 60 degrees)'
                tracked = known or (tick.belief is not None and any(
                    math.dist(m.position, centres[k]) < 1.0 for m in tick.belief.movers))
                found.update(what=f'{"known" if known else "unknown"} mover', how=how, believed=tracked, t=tick.t,
                             depth=float(-d[k]))
                return
        for name, q in positions.items():
            if name != robot and np.hypot(*(q - p)) < radius + specs[name].radius:
                found.update(what='another robot', how='moving' if speed > 0.05 else 'standing', believed=True,
                             t=tick.t, depth=float(radius + specs[name].radius - np.hypot(*(q - p))))
                return

    simulate(scenario, algorithm, seed, observer=observe)
    return found or {'what': 'not found on the ticks (a contact between samples)', 'how': '', 'believed': None}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('json', nargs='+')
    parser.add_argument('--algorithms', nargs='+', help='only these planners\' collisions')
    args = parser.parse_args()
    kinds: Counter[tuple[str, str, str]] = Counter()
    for path in args.json:
        rows = json.load(open(path))['rows']
        for row in rows:
            if not row['collided'] or (args.algorithms and row['algorithm'] not in args.algorithms):
                continue
            contact = first_contact(family_source(row['family'], row['world']), row['algorithm'], row['seed'],
                                    row['robot'])
            print(f"{row['family']}:{row['world']} {row['algorithm']} seed {row['seed']} {row['robot']}: "
                  f"{contact['what']}, {contact['how']}, believed/tracked {contact['believed']}, "
                  f"t {contact.get('t', math.nan):.2f} s, depth {contact.get('depth', math.nan):.2f} m", flush=True)
            kinds[(row['algorithm'], contact['what'], contact['how'])] += 1
    print()
    for (algorithm, what, how), n in sorted(kinds.items()):
        print(f'{algorithm:14s} {n:3d}  {what}, {how}')


if __name__ == '__main__':
    main()
