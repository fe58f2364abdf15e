"""Detection: RunDetector keeps an answer about the obstacles while it stays proven, and it is always the answer
measuring every obstacle gives."""

import numpy as np
import pytest

from fastep_core.geometry import Circle, Segment
from fastep_core.planning.params import PlannerParams
from fastep_core.planning.swarm.detection import RunDetector
from fastep_core.world import World


@pytest.mark.parametrize('seed', range(4))
def test_an_answer_kept_while_proven_is_the_answer_measured_afresh(seed):
    """A robot and its run's end wandering through circles and walls, in small steps and sometimes a jump: every
    answer of the detector that keeps its proofs equals a fresh detector's, and both kept and measured answers
    (blocked and clear) occur."""
    rng = np.random.default_rng(seed)
    circles = [Circle((float(x), float(y)), float(r)) for x, y, r in
               zip(rng.uniform(5, 45, 30), rng.uniform(5, 45, 30), rng.uniform(0.3, 2.0, 30))]
    walls = [Segment((20.0, 2.0), (20.0, 14.0)), Segment((28.0, 36.0), (44.0, 36.0))]
    world = World.from_obstacles([0, 0, 50, 50], circles + walls)
    kept = RunDetector(0.5)
    position, offset = np.array([25.0, 25.0]), np.array([6.0, 2.0])
    reused = answers = blocked = 0
    for k in range(600):
        jump = k % 41 == 0
        position = np.clip(position + rng.normal(0.0, 2.0 if jump else 0.05, 2), 0.5, 49.5)
        offset = offset + rng.normal(0.0, 3.0 if jump else 0.08, 2)   # the run's end: a target a few metres on
        end = np.clip(position + offset, 0.5, 49.5)
        for near_run in (False, True):
            before = kept._clear_runs[int(near_run)]
            answer = kept.obstacles_on_run(world, position, end, 2.5, 0.75, near_run)
            assert answer == RunDetector(0.5).obstacles_on_run(world, position, end, 2.5, 0.75, near_run)
            reused += before is not None and kept._clear_runs[int(near_run)] is before
            answers += 1
            blocked += answer
    assert 0 < reused < answers and 0 < blocked < answers


def test_a_robot_driving_along_its_run_past_obstacles_beside_it_keeps_its_clear_answer():
    """The run to a fixed goal passes 5 cm outside `within` of three circles and a wall, and a circle on the run lies
    far ahead. Driving along the run (a few millimetres off it) the robot measures once, and again only when the
    circle on the run comes within sensing range; every answer is a fresh detector's. (With a room of the least
    distance of any obstacle beside the run, it measured again every tick or two.)"""
    within, sensing = 0.75, 2.5
    beside = [Circle((6.0, 10.0 + 0.8 + within + 0.05), 0.8), Circle((9.0, 10.0 - 0.5 - within - 0.05), 0.5),
              Circle((12.0, 10.0 + 1.0 + within + 0.05), 1.0)]
    wall = Segment((14.0, 10.0 - within - 0.05), (17.0, 10.0 - within - 0.05))
    world = World.from_obstacles([0, 0, 50, 50], [*beside, Circle((27.0, 10.0), 0.6), wall])
    kept = RunDetector(0.5)
    goal = np.array([40.0, 10.0])
    rng = np.random.default_rng(0)
    measured, answers = [], []
    for k in range(600):
        position = np.array([3.0 + 0.04 * k, 10.0 + rng.uniform(-0.004, 0.004)])
        before = kept._clear_runs[0]
        answer = kept.obstacles_on_run(world, position, goal, sensing, within)
        assert answer == RunDetector(0.5).obstacles_on_run(world, position, goal, sensing, within)
        answers.append(answer)
        if kept._clear_runs[0] is not before:
            measured.append(k)
    first_blocked = answers.index(True)
    assert not any(answers[:first_blocked]) and 27.0 - 0.6 - sensing <= 3.0 + 0.04 * first_blocked < 27.0
    assert measured[0] == 0 and len([k for k in measured if k < first_blocked]) <= 2


def test_a_run_to_a_nan_end_is_measured_not_taken_from_a_proof():
    """A blocked answer kept for a run to (12, 10) is not reused for a run to (nan, 10): measuring says clear."""
    world = World.from_obstacles([0, 0, 50, 50], [Circle((10.0, 10.0), 1.0)])
    kept = RunDetector(0.5)
    position = np.array([8.0, 10.0])
    assert kept.obstacles_on_run(world, position, np.array([12.0, 10.0]), 2.5, 0.75)
    nan_end = np.array([np.nan, 10.0])
    assert kept.obstacles_on_run(world, position, nan_end, 2.5, 0.75) == \
        RunDetector(0.5).obstacles_on_run(world, position, nan_end, 2.5, 0.75)


def test_a_new_world_or_forget_drops_the_kept_answers():
    params = PlannerParams()
    empty = World.from_obstacles([0, 0, 50, 50], [])
    detector = RunDetector(0.5)
    position, goal = np.array([10.0, 10.0]), np.array([20.0, 10.0])
    assert not detector.blocked(empty, params, position, goal, [])
    walled = World.from_obstacles([0, 0, 50, 50], [Circle((11.5, 10.0), 0.5)])
    assert detector.blocked(walled, params, position, goal, [])         # the world changed: measured again
    detector.forget()
    assert detector._detection is None and detector._clear_runs == [None, None]
