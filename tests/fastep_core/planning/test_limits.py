"""One set of limits (planning/limits.py): a runtime change of max_speed reaches the model, the guards, the
controller, the smoother and FAStep-Route's speed law in the one call Navigator.retune (and ControlTick.retune).

The robots here drive as their commands say (a base with no limits of its own: x += v dt along the heading), so
what a command "really travels" is its speed times the time; the guard must predict that, not what a model left
with an old speed limit would make of it.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from fastep_core.geometry import Segment
from fastep_core.kinematics import PointMass
from fastep_core.kinematics.diff_drive import DiffDrive, DiffDriveController
from fastep_core.planning import PlannerParams
from fastep_core.planning.algorithms import make_navigator, make_robot
from fastep_core.planning.control import ControlTick, Plan
from fastep_core.planning.limits import Limits, saturating, with_limits
from fastep_core.planning.navigator import Navigator
from fastep_core.scenario import RobotSpec
from fastep_core.world import World

DT = PlannerParams().dt
WORKSPACE = (0.0, 0.0, 200.0, 20.0)
EMPTY = World.from_obstacles(WORKSPACE, [])
SPECS = {'diff_drive': RobotSpec('d1', 'diff_drive', (2.0, 10.0, 0.0), (195.0, 10.0), 0.35),
         'point_mass': RobotSpec('p1', 'point_mass', (2.0, 10.0), (195.0, 10.0), 0.35)}


def travelled(state: np.ndarray, command: np.ndarray, dt: float, holonomic: bool) -> np.ndarray:
    """Where a base that does exactly what it is told is after dt (a straight run: no turn in these tests)."""
    if holonomic:
        return state + dt * command
    return state + dt * np.array([command[0] * np.cos(state[2]), command[0] * np.sin(state[2]), command[1]])


class Robot:
    """A navigator with its control loop (ControlTick), planning every tick as fastep-sim's robots with mass do."""

    def __init__(self, model: str, algorithm: str = 'fastep') -> None:
        self.spec = SPECS[model]
        self.nav: Navigator = make_navigator(algorithm, self.spec, self.spec.radius, EMPTY, PlannerParams(), 0)
        self.nav.set_goal(self.spec.goal)
        self.tick = ControlTick(self.nav)
        self.state, self.t = np.array(self.spec.start, dtype=float), 0.0
        self.holonomic = bool(self.nav.model.holonomic)
        self.sent = np.zeros(2)
        self.plan: Plan | None = None
        self.checks: list[tuple[np.ndarray, np.ndarray, float, np.ndarray]] = []
        self.spy()

    def spy(self) -> None:
        """Record what the control loop's guard is asked: (state, command, look-ahead, where it predicts it ends)."""
        guard = self.tick.guard
        check = guard.check

        def recorded(world, state, command, dt, others):
            self.checks.append((np.array(state), np.array(command), dt, guard.model.integrate(state, command, dt)))
            return check(world, state, command, dt, others)
        guard.check = recorded  # type: ignore[method-assign]  # what the guard is asked, recorded

    def speed(self) -> float:
        return float(np.hypot(*self.sent)) if self.holonomic else float(self.sent[0])

    def step(self, plan: Plan | None = None, replan: bool = True) -> float:
        """One control tick on `plan`, or on a new pass's plan (replan), else on the last one; the base moves."""
        if plan is None:
            if replan or self.plan is None:
                self.plan = Plan.of(self.nav, self.t, self.nav.update(self.t, self.state, (), velocity=self.sent))
            plan = self.plan
        self.sent = self.tick.command(self.t, self.state, (), plan, DT, velocity=self.sent)
        self.state = travelled(self.state, self.sent, DT, self.holonomic)
        self.t += DT
        return self.speed()

    def set(self, **changes: float) -> None:
        """What the planner node does: Navigator.retune with a new controller, then the control loop's retune."""
        params = self.nav.params.with_overrides(changes)
        self.nav.retune(params, make_robot(self.spec, params)[1])
        self.tick.retune()
        self.spy()

    def wall_ahead(self, gap: float) -> Plan:
        """The plan of now with a wall across the way `gap` m ahead of the robot's surface (unknown to the pass)."""
        assert self.plan is not None
        x = float(self.state[0]) + self.spec.radius + gap
        return dataclasses.replace(self.plan, world=World.from_obstacles(WORKSPACE, [Segment((x, 0.0), (x, 20.0))]))


def distance(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.hypot(*(np.asarray(a)[:2] - np.asarray(b)[:2])))


def checked_as_travelled(robot: Robot) -> list[float]:
    """The look-ahead of each of the last tick's guard checks, each asserted to predict as far as a base doing
    the command goes meanwhile."""
    aheads = []
    for state, command, ahead, after in robot.checks:
        truth = travelled(state, command, ahead, robot.holonomic)
        assert distance(after, state) == pytest.approx(distance(truth, state)), (command, ahead)
        aheads.append(ahead)
    robot.checks.clear()
    return aheads


@pytest.mark.parametrize('model', ['diff_drive', 'point_mass'])
def test_a_max_speed_raised_at_runtime_is_what_the_guard_predicts_the_robot_travels(model):
    robot = Robot(model)
    for _ in range(60):
        robot.step()
    assert robot.speed() == pytest.approx(1.0)
    robot.set(max_speed=1.5)
    speeds = []
    for _ in range(20):
        speeds.append(robot.step())
        checked_as_travelled(robot)   # each tick's commands, on the way up too
    assert speeds[-1] == pytest.approx(1.5)   # the controller and the smoother took it
    robot.step()
    (ahead,) = set(checked_as_travelled(robot))
    assert ahead == pytest.approx(DT + 0.5 * 1.5 / robot.nav.params.emergency_deceleration)   # its braking distance
    # The model, the pass's guard and the control loop's guard (and the node's latency compensation: the model)
    # predict a tick of it as far as it goes.
    assert robot.tick.guard.model is robot.nav.model is robot.nav.guard_check.model
    fast = robot.sent
    assert robot.nav.model.integrate(robot.state, fast, DT) == pytest.approx(travelled(robot.state, fast, DT,
                                                                                       robot.holonomic))
    assert distance(robot.nav.model.integrate(robot.state, fast, DT), robot.state) == pytest.approx(1.5 * DT)
    assert robot.nav.limits.max_speed == robot.tick.limits.max_speed == robot.tick.smoother.max_speed == 1.5


def test_the_guard_stops_a_robot_at_a_raised_max_speed_before_a_wall_its_braking_look_ahead_reaches():
    robot = Robot('diff_drive')
    for _ in range(60):
        robot.step()
    robot.set(max_speed=1.5)
    for _ in range(20):
        robot.step()
    # At 1.5 m/s the guard looks 0.05 + 1.5 / (2 x 5) = 0.2 s ahead: 0.3 m. A wall 0.25 m ahead is within it (at the
    # old limit of 1.0 m/s the prediction was 0.2 m, and the robot drove on).
    wall = robot.wall_ahead(0.25)
    before = robot.speed()
    after = float(robot.tick.command(robot.t, robot.state, (), wall, DT, velocity=robot.sent)[0])
    assert 'obstacle' in robot.tick.reason
    assert after == pytest.approx(before - robot.nav.params.emergency_deceleration * DT)   # the guard's stop


@pytest.mark.parametrize('model', ['diff_drive', 'point_mass'])
def test_a_max_speed_lowered_at_runtime_is_reached_braking_and_the_guard_looks_as_far_as_the_robot_goes(model):
    robot = Robot(model)
    for _ in range(60):
        robot.step()
    robot.set(max_speed=1.5)
    for _ in range(20):
        robot.step()
    robot.set(max_speed=0.5)
    acceleration, braking = robot.nav.params.max_acceleration, robot.nav.params.emergency_deceleration
    speeds, aheads = [], []
    for _ in range(12):
        speeds.append(robot.step())
        # Every command of the ramp down is predicted as far as the robot goes doing it, over the look-ahead.
        aheads.append(max(checked_as_travelled(robot)))
    drops = -np.diff([1.5, *speeds])
    assert drops[:8] == pytest.approx([acceleration * DT] * 8)   # braking at max_acceleration to the new limit ...
    assert speeds[-4:] == pytest.approx([0.5] * 4)                # ... which it keeps
    # The look-ahead follows the speed: a tick and the braking time from the speed the robot had at the tick.
    assert aheads == pytest.approx([DT + 0.5 * v / braking for v in [1.5, *speeds[:-1]]])
    assert robot.tick.smoother.max_speed == robot.tick.limits.max_speed == 0.5


def test_the_guard_stops_a_robot_braking_to_a_lowered_max_speed_before_a_wall_it_would_reach():
    robot = Robot('diff_drive')
    for _ in range(60):
        robot.step()
    robot.set(max_speed=1.5)
    for _ in range(20):
        robot.step()
    robot.set(max_speed=0.5)
    # Its first command brakes to 1.375 m/s; over the 0.2 s look-ahead that is 0.275 m: a wall 0.25 m ahead is
    # reached. A model saturating at the new 0.5 m/s would predict 0.1 m (at the first limit, 1.0 m/s, 0.2 m).
    wall = robot.wall_ahead(0.25)
    after = float(robot.tick.command(robot.t, robot.state, (), wall, DT, velocity=robot.sent)[0])
    assert 'obstacle' in robot.tick.reason
    assert after == pytest.approx(1.5 - robot.nav.params.emergency_deceleration * DT)


@pytest.mark.parametrize('model', ['diff_drive', 'point_mass'])
def test_a_plan_made_before_a_runtime_change_is_driven_on_within_the_new_limits(model):
    # FAStep-Route's speed law is frozen with the plan: the control loop drives on a plan for as long as the next
    # pass takes, within the limits it has now.
    robot = Robot(model, 'fastep_route')
    for _ in range(60):
        robot.step()
    assert robot.speed() == pytest.approx(1.0)
    robot.set(max_speed=1.5)
    speeds = [robot.step(replan=False) for _ in range(20)]   # one long pass: the plan of before the change
    assert speeds[-1] == pytest.approx(1.5)
    robot.set(max_speed=0.5)
    speeds = [robot.step(replan=False) for _ in range(20)]
    assert max(np.abs(np.diff([1.5, *speeds]))) <= robot.nav.params.max_acceleration * DT * (1 + 1e-9)
    assert speeds[-1] == pytest.approx(0.5)


def test_limits_are_the_planner_parameters_and_reach_controllers_and_models_as_a_whole():
    params = PlannerParams().with_overrides({'max_speed': 1.5, 'max_turn_rate': 1.0, 'max_acceleration': 2.0,
                                             'dt': 0.1})
    limits = params.limits
    assert limits == Limits.of(params) == Limits(1.5, 0.25, 1.0, 2.0, 3.2, 5.0, 0.1)
    model, controller = DiffDrive(1.0, 2.0), DiffDriveController()
    moved = with_limits(controller, limits)
    assert (moved.max_speed, moved.max_turn_rate, moved.max_acceleration) == (1.5, 1.0, 2.0)
    assert moved.speed_gain == controller.speed_gain and controller.max_speed == 1.0   # a copy, gains kept
    # A model saturates at the higher of its limits and the new ones: a lowered limit is reached braking.
    assert (saturating(model, limits).max_speed, saturating(model, limits).max_turn_rate) == (1.5, 2.0)
    assert saturating(model, Limits(max_speed=0.0)).max_speed == 0.0   # unlimited is the highest
    point_mass = PointMass()
    assert saturating(point_mass, limits) is point_mass   # nothing to saturate
