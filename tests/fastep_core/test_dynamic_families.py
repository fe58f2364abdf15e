"""The v2 world families (experiments/dynamic_worlds.py) through random_worlds, as the benchmark loads them."""

from __future__ import annotations

import numpy as np
import pytest

from fastep_core.dynamic_world import DynamicWorld
from fastep_core.experiments.batches import cached_scenario
from fastep_core.experiments.dynamic_worlds import DYNAMIC_FAMILIES
from fastep_core.experiments.random_worlds import ALL_FAMILIES, FAMILIES, family_source, random_family_data, solvable
from fastep_core.geometry import point_segment_distance
from fastep_core.scenario import parse_scenario


@pytest.mark.parametrize('family', DYNAMIC_FAMILIES)
@pytest.mark.parametrize('seed', [0, 1, 2])
def test_a_family_world_is_what_its_family_says_and_solvable_from_the_truth(family: str, seed: int) -> None:
    data = random_family_data(family, seed)
    assert data == random_family_data(family, seed)                      # same seed, same world
    scenario = parse_scenario(data)
    assert solvable(scenario) and not scenario.is_static
    assert all(r.sensor is not None and r.model == 'point_mass' for r in scenario.robots)
    specs = scenario.obstacle_specs
    movers = [o for o in specs if o.motion is not None]
    unknown = [o for o in specs if not o.known and o.motion is None]
    misplaced = [o for o in specs if o.position_sigma > 0.0]
    robots = len(scenario.robots)
    expected = {'crossing_movers': (movers and not misplaced and robots == 1),
                'unknown_obstacles': (unknown and not movers and not misplaced and robots == 1),
                'misplaced_obstacles': (misplaced and not movers and not unknown and robots == 1),
                'dynamic_mix': (movers and 2 <= robots <= 4)}[family]
    assert expected
    # No mover's track comes near a start or goal (a robot standing there is never run down).
    ends = np.array([p for r in scenario.robots for p in (r.start[:2], r.goal)], dtype=float)
    truth = DynamicWorld(scenario.world.workspace, specs)
    for k in range(len(truth.movers)):
        path = truth.movers.vertices[k]
        for a, b in zip(path[:-1], path[1:]):
            assert point_segment_distance(ends, a, b).min() > truth.movers.radii[k] + 0.5


def test_the_families_are_loaded_by_name_and_the_default_stays_static() -> None:
    assert set(DYNAMIC_FAMILIES) <= set(ALL_FAMILIES) and not set(DYNAMIC_FAMILIES) & set(FAMILIES)
    scenario = cached_scenario(family_source('dynamic_mix', 5))
    assert scenario.name == 'dynamic_mix_5'
