"""Shared helpers of the benchmark scripts: capturing the step problems a real run poses."""

from __future__ import annotations

import numpy as np

import fastep_core.planning.navigator as navigator
from fastep_core.planning.step import StepProblem
from fastep_core.scenario import load_scenario
from fastep_core.simulator import simulate


def captured_step_problems(scenario_name: str = 'table2_s2', seed: int = 0) -> list[StepProblem]:
    """The StepProblems FAStep-Kinematic solves in one run of a scenario (real positions, real obstacles)."""
    problems: list[StepProblem] = []
    original = navigator.plan_step

    def spy(problem, params, rng, method='fastep'):
        problems.append(problem)
        return original(problem, params, rng, method)

    navigator.plan_step = spy
    try:
        simulate(load_scenario(scenario_name), 'fastep', seed)
    finally:
        navigator.plan_step = original
    return problems


def median_ms(samples: list[float]) -> float:
    return float(np.median(samples) * 1e3)
