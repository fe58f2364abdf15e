"""Shared helpers of the benchmark scripts: capturing the step problems a real run poses."""

from __future__ import annotations

import numpy as np

from fastep_core.planning.swarm.step import StepProblem, recorded_step_problems
from fastep_core.scenario import Scenario, load_scenario
from fastep_core.simulator import simulate


def captured_step_problems(scenario: str | Scenario = 'table2_s2', seed: int = 0,
                           algorithm: str = 'fastep') -> list[StepProblem]:
    """The StepProblems a run of a scenario poses to the step optimizer (real positions, real obstacles)."""
    with recorded_step_problems() as problems:
        simulate(load_scenario(scenario) if isinstance(scenario, str) else scenario, algorithm, seed)
    return problems


def median_ms(samples: list[float]) -> float:
    return float(np.median(samples) * 1e3)
