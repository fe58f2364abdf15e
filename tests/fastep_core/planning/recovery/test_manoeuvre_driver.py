"""Driving a manoeuvre (planning/recovery/manoeuvre_driver.py): replay, drift, holds and retries."""

from __future__ import annotations

import numpy as np

from fastep_core.kinematics import TractorTrailer
from fastep_core.planning import PlannerParams
from fastep_core.planning.recovery import manoeuvre_driver
from fastep_core.planning.recovery.manoeuvre_driver import OFF_MANOEUVRE, RETRY_MANOEUVRE, ManoeuvreDriver
from fastep_core.planning.recovery.manoeuvre_search import Manoeuvre
from fastep_core.world import World

WORLD = World.from_obstacles([0, 0, 50, 50], [])
START = np.array([5.0, 5.0, 0.0, 0.0])
GOAL = np.array([45.0, 5.0])


def two_ticks(*_args, **_kwargs):
    states = np.array([START, START + [0.05, 0, 0, 0], START + [0.1, 0, 0, 0]])
    return Manoeuvre(np.array([[1.0, 0.0], [1.0, 0.0]]), states, 1, 0, 1)


def test_a_manoeuvre_is_replayed_tick_by_tick_and_ends_where_it_ends(monkeypatch):
    monkeypatch.setattr(manoeuvre_driver, 'plan_manoeuvre', two_ticks)
    m = ManoeuvreDriver(TractorTrailer(), 0.5, PlannerParams())
    assert m.plan(WORLD, START, GOAL, 0.0) and m.count == 1 and 'manoeuvring: 1 arcs' in m.status

    def allow(command):
        return command

    command, ended = m.drive(START, 0.0, 40.0, allow, lambda: False)
    assert command is not None and command[0] == 1.0 and not ended
    command, ended = m.drive(START + [0.05, 0, 0, 0], 0.05, 39.95, allow, lambda: False)
    assert command is not None and not ended
    assert m.drive(START + [0.1, 0, 0, 0], 0.1, 39.9, allow, lambda: False) == (None, True)
    assert not m.active and m.left_at == 39.9


def test_a_robot_off_its_manoeuvre_or_held_three_seconds_searches_again(monkeypatch):
    monkeypatch.setattr(manoeuvre_driver, 'plan_manoeuvre', two_ticks)
    m = ManoeuvreDriver(TractorTrailer(), 0.5, PlannerParams())
    m.plan(WORLD, START, GOAL, 0.0)
    asked = []
    off = START + [OFF_MANOEUVRE + 0.01, 0.0, 0.0, 0.0]
    assert m.drive(off, 0.0, 40.0, lambda c: c, lambda: asked.append('off') or False) == (None, False)
    m.plan(WORLD, START, GOAL, 1.0)

    def stop(command):
        return np.zeros(2)

    for t in (1.0, 2.0, 3.9):
        m.drive(START, t, 40.0, stop, lambda: asked.append('held') or True)
    assert m.tick == 0 and asked == ['off']
    m.drive(START, 4.0, 40.0, stop, lambda: asked.append('held') or True)
    assert asked == ['off', 'held']


def test_no_search_for_a_while_after_one_found_nothing(monkeypatch):
    calls = []
    monkeypatch.setattr(manoeuvre_driver, 'plan_manoeuvre', lambda *a, **k: calls.append(1))
    m = ManoeuvreDriver(TractorTrailer(), 0.5, PlannerParams())
    assert not m.plan(WORLD, START, GOAL, 10.0) and not m.plan(WORLD, START, GOAL, 10.0 + RETRY_MANOEUVRE - 0.1)
    assert len(calls) == 1
    assert not m.plan(WORLD, START, GOAL, 10.0 + RETRY_MANOEUVRE) and len(calls) == 2
