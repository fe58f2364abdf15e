"""A late control loop slows the robot (planning/safety/lateness.py, control.py): measured lateness, the speed that
stops in time, and a starved loop that meets nothing where one blind to its lateness does."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fastep_core.geometry import Segment
from fastep_core.planning.algorithms import make_navigator
from fastep_core.planning.control import ControlTick, Plan
from fastep_core.planning.params import PlannerParams
from fastep_core.planning.safety.lateness import LATENESS_WINDOW, Lateness, stopping_speed
from fastep_core.scenario import RobotSpec
from fastep_core.world import World

P = PlannerParams()
DT = P.dt
RADIUS = 0.3


@pytest.mark.parametrize('room, late, braking', [(0.4, 0.0, 2.5), (0.4, 0.3, 2.5), (2.0, 1.2, 0.8), (0.0, 0.5, 2.0)])
def test_stopping_speed_driven_late_then_braked_stops_within_the_room(room, late, braking):
    speed = stopping_speed(room, late, braking)
    assert speed * late + speed * speed / (2.0 * braking) == pytest.approx(room, abs=1e-12)
    if late == 0.0:
        assert speed == pytest.approx(math.sqrt(2.0 * braking * room))


def test_stopping_speed_with_an_immediate_stop_is_the_room_over_the_lateness():
    assert stopping_speed(0.5, 0.25, 0.0) == pytest.approx(2.0)
    assert stopping_speed(0.5, 0.0, 0.0) == math.inf


def test_on_time_ticks_are_not_late():
    lateness = Lateness()
    for k in range(100):
        lateness.tick(k * DT, DT, odometry_age=0.02)   # odometry younger than a period is on time
        lateness.moving(k * DT, True)
    assert lateness.late == 0.0 and lateness.describe() == ''


def test_a_late_tick_counts_for_the_window_and_then_is_forgotten():
    lateness = Lateness()
    t = 0.0
    lateness.tick(t, DT)
    lateness.moving(t, True)
    t += 0.55   # 0.5 s later than due
    lateness.tick(t, DT, odometry_age=0.2)
    assert lateness.gap == pytest.approx(0.5) and lateness.odometry == pytest.approx(0.15)
    assert lateness.late == pytest.approx(0.65)
    assert 'ticks 0.50 s' in lateness.describe() and 'odometry 0.15 s' in lateness.describe()
    while t < 0.55 + LATENESS_WINDOW - 2 * DT:
        lateness.moving(t, True)
        t += DT
        lateness.tick(t, DT)
    assert lateness.gap == pytest.approx(0.5)   # still within the window
    for _ in range(5):
        lateness.moving(t, True)
        t += DT
        lateness.tick(t, DT)
    assert lateness.late == 0.0


def test_a_long_pause_standing_still_or_a_clock_that_went_back_is_not_late():
    lateness = Lateness()
    lateness.tick(0.0, DT)
    lateness.moving(0.0, False)   # told to stand
    lateness.tick(0.5, DT)        # standing, the loop starved all the same
    assert lateness.gap == pytest.approx(0.45)
    lateness.reset()
    lateness.tick(0.0, DT)
    lateness.moving(0.0, False)
    lateness.tick(30.0, DT)       # the loop off (inactive) for half a minute, standing
    assert lateness.late == 0.0
    lateness.moving(30.0, True)
    lateness.tick(31.0, DT)
    assert lateness.gap == pytest.approx(1.0 - DT)
    lateness.tick(2.0, DT)   # a restarted simulation
    assert lateness.late == 0.0


def test_a_scan_older_than_allowed_makes_the_loop_late():
    lateness = Lateness()
    lateness.tick(0.0, DT, scan_late=0.4)
    assert lateness.scan == pytest.approx(0.4) and 'scan 0.40 s' in lateness.describe()


def _navigator(model: str, obstacles: list[Segment], goal: tuple[float, float]):
    world = World.from_obstacles((-2.0, -4.0, 14.0, 4.0), obstacles)
    start = (0.0, 0.0) if model == 'point_mass' else (0.0, 0.0, 0.0)
    nav = make_navigator('fastep_route', RobotSpec('r1', model, start, goal, RADIUS), RADIUS, world, P,
                         np.random.default_rng(0))
    nav.set_goal(goal)
    return nav, np.array(start, dtype=float), world


def starved(model: str, goal: tuple[float, float], wall_x: float, blind: bool, seed: int = 0,
            stale_plan: bool = False) -> dict[str, object]:
    """Drive toward `goal` with a wall across the way at x = wall_x through a control loop that is starved: after
    one 0.5 s gap at the start, a tick in four comes 0.3-0.5 s apart, the base meanwhile doing what it was last told
    (integrated in 5 ms steps).
    stale_plan: the plan drives at a target beyond the wall (made before it was known), only the guard stands
    between. blind: the control tick does not measure its lateness. Returns the least clearance to the wall."""
    wall = Segment((wall_x, -3.0), (wall_x, 3.0))
    nav, state, world = _navigator(model, [wall], goal)
    control = ControlTick(nav)
    if blind:
        control.lateness.tick = lambda *args, **kwargs: None   # type: ignore[method-assign]  # the loop as before
    rng = np.random.default_rng(seed)
    t, velocity, clearance, slowed, ticks = 0.0, np.zeros(2), math.inf, False, 0
    while t < 20.0:
        plan = Plan.of(nav, t, nav.update(t, state, [], velocity.copy()))
        if stale_plan:
            plan = Plan(t, np.array([12.0, 0.0]), plan.command, world, (), plan.mode, plan.reason)
        if plan.mode.value == 'arrived':
            break
        command = control.command(t, state, [], plan, DT, velocity.copy())
        slowed = slowed or bool(control.slowed)
        ticks += 1
        gap = 0.5 if ticks == 1 else DT if rng.random() > 0.25 else float(rng.uniform(0.3, 0.5))
        for _ in range(round(gap / 0.005)):
            state = nav.model.integrate(state, command, 0.005)
            clearance = min(clearance, wall_x - float(state[0]) - RADIUS)
        velocity = np.array(command, dtype=float)
        t += gap
    return {'clearance': clearance, 'slowed': slowed, 'arrived': plan.mode.value == 'arrived', 'state': state}


@pytest.mark.parametrize('model', ['point_mass', 'diff_drive'])
def test_a_starved_loop_stops_at_a_goal_before_a_wall_where_one_blind_to_its_lateness_hits_it(model):
    goal, wall_x = (6.0, 0.0), 6.45
    late = starved(model, goal, wall_x, blind=False)
    assert late['arrived'] and late['slowed']
    assert late['clearance'] > 0.0
    blind = [starved(model, goal, wall_x, blind=True, seed=s)['clearance'] for s in range(3)]
    assert min(blind) < 0.0   # the same starved loop, its lateness not counted: into the wall


@pytest.mark.parametrize('model', ['point_mass', 'diff_drive'])
def test_a_starved_loop_on_a_plan_at_a_wall_is_stopped_by_the_guard_short_of_it(model):
    for seed in range(3):
        run = starved(model, (12.0, 0.0), 5.0, blind=False, seed=seed, stale_plan=True)
        assert run['clearance'] > 0.0 and run['slowed']
    blind = [starved(model, (12.0, 0.0), 5.0, blind=True, seed=s, stale_plan=True)['clearance'] for s in range(3)]
    assert min(blind) < 0.0


def test_on_time_the_control_tick_is_never_slowed_and_its_guard_looks_a_tick_ahead():
    nav, state, _ = _navigator('point_mass', [], (10.0, 0.0))
    control = ControlTick(nav)
    t = 0.0
    for _ in range(60):
        plan = Plan.of(nav, t, nav.update(t, state, []))
        command = control.command(t, state, [], plan, DT, np.array(control.smoother.velocity), t)
        assert control.slowed == '' and control.lateness.late == 0.0
        state = nav.model.integrate(state, command, DT)
        t += DT
    assert float(state[0]) > 1.0
