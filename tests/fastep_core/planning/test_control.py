"""The control loop's bounded tick (planning/control.py) and fastep-sim --realtime (simulator.simulate)."""

from __future__ import annotations

import math
import types

import numpy as np
import pytest

import fastep_core.simulator as simulator
from fastep_core.geometry import Segment
from fastep_core.planning.algorithms import make_navigator
from fastep_core.planning.control import ControlTick, Plan, PlanLatency
from fastep_core.planning.navigator import Mode, Navigator
from fastep_core.planning.params import PlannerParams
from fastep_core.scenario import RobotSpec, load_scenario
from fastep_core.simulator import simulate
from fastep_core.world import World


def _navigator(model: str = 'point_mass') -> tuple[Navigator, np.ndarray]:
    world = World.from_obstacles((0.0, 0.0, 20.0, 20.0), [])
    start = (2.0, 10.0) if model == 'point_mass' else (2.0, 10.0, 0.0)
    spec = RobotSpec('r1', model, start, (18.0, 10.0), 0.5)
    return make_navigator('fastep', spec, 0.5, world, PlannerParams(), np.random.default_rng(0)), np.array(start)


@pytest.mark.parametrize('model', ['point_mass', 'diff_drive'])
def test_a_fresh_plan_on_its_own_state_gives_the_navigators_command(model: str) -> None:
    nav, state = _navigator(model)
    nav.set_goal([18.0, 10.0])
    control = ControlTick(nav)
    command = nav.update(0.0, state, ())
    plan = Plan.of(nav, 0.0, command)
    assert plan.target is not None and plan.mode is Mode.KINEMATIC
    control.smoother.reset(command)   # the robot already drives so: the smoother lets the command through
    np.testing.assert_allclose(control.command(0.0, state, (), plan, 0.05), command)


def test_no_plan_or_a_plan_not_under_way_stands_still() -> None:
    nav, state = _navigator()
    control = ControlTick(nav)
    assert not control.command(0.0, state, (), None, 0.05).any()
    nav.set_goal([18.0, 10.0])
    nav.update(0.0, state, ())
    nav.fail('test')
    assert not control.command(0.0, state, (), Plan.of(nav, 0.0, np.ones(2)), 0.05).any()


def test_a_stale_plan_is_driven_from_the_current_state_and_guarded_against_its_world() -> None:
    # A wall across the way, which the plan (made before it was known) drives straight at.
    nav, state = _navigator()
    nav.set_goal([18.0, 10.0])
    plan = Plan.of(nav, 0.0, nav.update(0.0, state, ()))
    walled = World.from_obstacles((0.0, 0.0, 20.0, 20.0), [Segment((10.0, 0.0), (10.0, 20.0))])
    plan = Plan(plan.t, plan.target, plan.command, walled, (), plan.mode, plan.reason)
    control = ControlTick(nav)
    far = control.command(3.0, np.array([5.0, 10.0]), (), plan, 0.05)
    assert far[0] > 0.0   # heads on toward the target from where the robot is now
    near = control.command(3.0, np.array([9.48, 10.0]), (), plan, 0.05)
    assert not near.any() and 'obstacle' in control.reason


def test_tracked_movers_of_an_old_plan_are_predicted_to_now() -> None:
    nav, state = _navigator()
    nav.set_goal([18.0, 10.0])
    mover = simulator.OtherRobot('track 1', (10.0, 10.0), (1.0, 0.0), 0.3, mover=True)
    plan = Plan.of(nav, 1.0, nav.update(1.0, state, ()), [mover])
    (moved,) = plan.movers_at(1.5)
    assert moved.position == (10.5, 10.0) and moved.mover
    (far,) = plan.movers_at(30.0)   # a track is a guess: predicted PREDICT_MOVERS (1 s) at most
    assert far.position == (11.0, 10.0)


def test_plan_latency_hands_a_plan_over_only_after_its_latency() -> None:
    latency = PlanLatency(factor=2.0)
    nav, state = _navigator()
    nav.set_goal([18.0, 10.0])
    plan = Plan.of(nav, 0.0, nav.update(0.0, state, ()))
    assert not latency.take(0.0) and latency.idle
    latency.submit(plan, 0.0, wall=0.1)          # 0.2 s on the robot's clock
    fresh = [latency.take(t) for t in (0.05, 0.1, 0.15, 0.2, 0.25)]
    assert fresh == [False, False, False, True, False]
    assert latency.plan is plan and latency.idle
    assert (latency.ticks, latency.stale_ticks, latency.passes) == (6, 5, 1)
    assert latency.max_latency == pytest.approx(0.2)


class _SteppingClock:
    """A stand-in for the simulator's `time` module: every reading is `step` seconds after the one before."""

    def __init__(self, step: float) -> None:
        self.now, self.step = 0.0, step

    def perf_counter(self) -> float:
        self.now += self.step
        return self.now

    def process_time(self) -> float:
        return self.now


def test_realtime_with_slow_planning_drives_on_stale_plans_and_counts_them(monkeypatch: pytest.MonkeyPatch) -> None:
    # Every planning pass takes 0.01 s of "wall time"; x 25 that is 0.25 s, five ticks of 0.05 s.
    clock = _SteppingClock(0.01)
    monkeypatch.setattr(simulator, 'time', types.SimpleNamespace(perf_counter=clock.perf_counter,
                                                                 process_time=clock.process_time))
    scenario = load_scenario('case_study_1')
    run = simulate(scenario, 'fastep', 0, realtime=25.0)
    for robot in run.robots:
        assert robot.reached and not robot.collided
        assert robot.realtime is not None
        latency = robot.realtime
        assert latency.max_latency == pytest.approx(0.25)
        # A pass every fifth tick at most: the others drove on the plan they had.
        assert latency.stale_ticks >= 0.75 * latency.ticks
        assert latency.passes <= latency.ticks / 5 + 1
        data = robot.to_json()['realtime']
        assert isinstance(data, dict) and data['stale_ticks'] == latency.stale_ticks
    assert clock.now > 0.0


def test_lock_step_runs_carry_no_realtime_fields_and_stay_deterministic() -> None:
    scenario = load_scenario('case_study_1')
    first, second = simulate(scenario, 'fastep', 3), simulate(scenario, 'fastep', 3)
    assert [r.trajectory for r in first.robots] == [r.trajectory for r in second.robots]
    robots = first.to_json()['robots']
    assert isinstance(robots, list) and all('realtime' not in r for r in robots)


def test_realtime_factor_zero_arrives_like_lock_step() -> None:
    scenario = load_scenario('diff_drive_walls')
    locked = simulate(scenario, 'fastep_route', 0).robots[0]
    timed = simulate(scenario, 'fastep_route', 0, realtime=0.0).robots[0]
    assert timed.reached and not timed.collided
    assert timed.realtime is not None and timed.realtime.stale_ticks == 1   # the first tick has no plan yet
    assert timed.sim_time is not None and locked.sim_time is not None
    assert math.isclose(timed.sim_time, locked.sim_time, abs_tol=1.0)


def test_commands_ramp_within_the_acceleration_limits_and_the_guards_stop_brakes_harder() -> None:
    nav, state = _navigator('diff_drive')
    nav.set_goal([18.0, 10.0])
    plan = Plan.of(nav, 0.0, nav.update(0.0, state, ()))
    control = ControlTick(nav)
    p = nav.params
    speeds = [float(control.command(0.05 * k, state, (), plan, 0.05)[0]) for k in range(1, 30)]
    steps = np.diff([0.0, *speeds])
    assert max(steps) <= p.max_acceleration * 0.05 + 1e-9 and speeds[-1] == pytest.approx(p.max_speed)
    # A wall the plan did not know, right ahead: the guard's stop, braking at emergency_deceleration.
    walled = World.from_obstacles((0.0, 0.0, 20.0, 20.0), [Segment((2.6, 0.0), (2.6, 20.0))])
    plan = Plan(plan.t, plan.target, plan.command, walled, (), plan.mode, plan.reason)
    # Held where it is (the test does not move it), it brakes until its braking distance fits before the wall.
    braking, reasons = [], []
    for k in range(1, 3):
        braking.append(float(control.command(1.5 + 0.05 * k, state, (), plan, 0.05)[0]))
        reasons.append(control.reason)
    assert all('obstacle' in reason for reason in reasons), reasons
    drops = -np.diff([speeds[-1], *braking])
    assert drops.min() > p.max_acceleration * 0.05 + 1e-9                      # harder than any other command ...
    assert drops.max() == pytest.approx(p.emergency_deceleration * 0.05)       # ... at emergency_deceleration


def test_a_steered_robot_does_not_back_into_space_no_scan_has_seen() -> None:
    from fastep_core.planning.recovery.back_up import SeenFree
    from fastep_core.planning.safety.guard_inputs import GuardInputs
    from fastep_core.sensing.laser import Scan
    nav, state = _navigator('diff_drive')
    nav.set_goal([18.0, 10.0])
    nav.update(0.0, state, ())
    back = np.array([-0.25, 0.0])
    plan = Plan(0.0, None, back, nav.world, (), Mode.AVOIDING, 'backing up: stuck')
    control = ControlTick(nav)
    assert control.command(0.0, state, (), plan, 0.05)[0] < 0.0   # no laser: the map alone says the way is free
    # A 270-degree laser facing ahead: the quarter behind the robot is blind.
    scan = Scan(-0.75 * math.pi, 0.75 * math.pi, 1.5 * math.pi / 269, 0.05, 5.0, np.full(270, np.inf))
    nav.take_perception(GuardInputs(seen=SeenFree.of_scans([(scan, np.array([2.0, 10.0, 0.0]))])))
    assert not control.command(0.05, state, (), plan, 0.05).any()
    assert control.reason.startswith('stopped: no evidence')
