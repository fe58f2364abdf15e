"""Sixteen robots in lock step on a busy computer step exactly like fastep-sim: fastep-launch as a user starts it
(the default layout and executor for 16 robots) beside processes that keep both cores busy, compared with
fastep-sim of the same scenario, algorithm and seed in every robot's arrival tick, path, clearance and every
trajectory row both runs hold. A wait given up on (a node starved past the lock step's wait) would say
"lock step: ... acting without" and leave fastep-sim's run: neither may happen."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any

from fastep_core.scenario import load_scenario
from fastep_core.simulator import simulate
from fastep_testing.graph import free_domain, isolated_env, stop_process, write
from fastep_testing.runs import circle_yaml

ROBOTS = 16
ALGORITHM = 'fastep_route'   # 28 s simulated on this circle (fastep, the paper's: 122 s)
BUSY = 2                     # processes spinning beside the graph, one a core


def test_sixteen_robots_in_lock_step_beside_busy_processes_run_exactly_like_fastep_sim(tmp_path: Path) -> None:
    scenario = write(tmp_path / 'circle.yaml', circle_yaml(ROBOTS, 5.0, 2.0))
    run: dict[str, Any] = simulate(load_scenario(str(scenario)), ALGORITHM, 0).to_json()
    reference: list[dict[str, Any]] = run['robots']
    out = tmp_path / 'run.json'
    env = isolated_env(free_domain(), tmp_path / 'roslog')
    busy = [subprocess.Popen([sys.executable, '-c', 'while True: pass'], stdin=subprocess.DEVNULL)
            for _ in range(BUSY)]
    launch = None
    try:
        launch = subprocess.Popen([sys.executable, '-m', 'fastep_ros.launch', str(scenario), '--algorithm', ALGORITHM,
                                   '--rtf', '50', '--seed', '0', '--no-progress', '--json', str(out)], env=env,
                                  stdout=subprocess.PIPE, stderr=subprocess.PIPE, stdin=subprocess.DEVNULL, text=True)
        stdout, stderr = launch.communicate(timeout=900)
    finally:
        for proc in busy:
            proc.kill()
            proc.wait()
        if launch is not None:
            stop_process(launch)
    assert launch.returncode == 0, (stdout, stderr)
    given_up = ('acting without', 'not waiting for it')   # a planner's, the clock's
    assert 'Traceback' not in stderr and not any(words in stdout + stderr for words in given_up), stderr
    robots = json.loads(out.read_text())['runs'][0]['robots']
    assert len(robots) == len(reference) == ROBOTS
    for robot, sim in zip(robots, reference):
        name = robot['name']
        assert robot['reached'] and not robot['collided'], (name, robot['status'])
        assert robot['sim_time'] == sim['sim_time'], name   # the same arrival tick
        assert abs(robot['path_length'] - sim['path_length']) <= 2e-6, name
        assert abs(robot['min_clearance'] - sim['min_clearance']) <= 2e-6, name
        expected = {round(row[0], 3): row[1:] for row in sim['trajectory']}
        common = [(row[1:], expected[round(row[0], 3)]) for row in robot['trajectory'] if round(row[0], 3) in expected]
        assert len(common) > 50, name
        assert max(abs(a - b) for live, fast in common for a, b in zip(live, fast)) <= 2e-6, name
