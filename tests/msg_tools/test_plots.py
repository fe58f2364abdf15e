"""The path figure: drawn from a simulated run, and from a live run whose monitor saw no odometry."""

from __future__ import annotations

from pathlib import Path

from fastep_core.scenario import load_scenario
from fastep_core.simulator import RobotRun, Run, simulate
from msg_tools.plots import plot_costs, plot_paths

PNG = b'\x89PNG\r\n\x1a\n'


def test_paths_and_costs_of_a_simulated_run(tmp_path: Path) -> None:
    scenario = load_scenario('table2_s1')
    run = simulate(scenario, seed=0)
    paths = plot_paths(scenario, run, tmp_path / 'paths.png')
    costs = plot_costs(run, tmp_path / 'costs.png')
    assert paths.read_bytes().startswith(PNG) and costs.read_bytes().startswith(PNG)


def test_a_robot_without_trajectory_is_drawn_without_a_path(tmp_path: Path) -> None:
    # fastep-launch reports from odometry: a robot whose odometry never arrived has no rows (CI once crashed here).
    scenario = load_scenario('case_study_1')
    run = Run(0, 'fastep', [RobotRun(name=spec.name, model=spec.model) for spec in scenario.robots])
    out = plot_paths(scenario, run, tmp_path / 'empty.png')
    assert out.read_bytes().startswith(PNG)
