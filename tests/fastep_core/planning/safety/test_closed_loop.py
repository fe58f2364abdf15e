"""Closed loop (planning/safety/base_response.py, smoother.py's feedback, the stopped goal check): commands shaped from
what the base measurably does, stops planned with the braking it has shown, arrival only once stopped. The base here is
a stand-in that reaches its command at most `limit` m/s^2 (and `turn_limit` rad/s^2) per tick: the physics plant
(fastep_core/dynamics) is tested against the same targets elsewhere."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pytest

from fastep_core.geometry import Segment
from fastep_core.kinematics.diff_drive import DiffDrive
from fastep_core.planning import PlannerParams
from fastep_core.planning.algorithms import make_navigator
from fastep_core.planning.behaviours import RETURNING, STOPPING
from fastep_core.planning.control import ControlTick, Plan
from fastep_core.planning.navigator import Mode
from fastep_core.planning.safety.base_response import BaseResponse, off_commands
from fastep_core.planning.safety.smoother import VelocitySmoother
from fastep_core.scenario import RobotSpec
from fastep_core.world import World

P = PlannerParams()
DT = P.dt
RADIUS = 0.22


@dataclass
class SlowBase:
    """A diff-drive base whose velocity moves toward its command by at most limit * dt (turn_limit for omega)."""

    limit: float
    turn_limit: float
    velocity: np.ndarray

    def step(self, command: np.ndarray) -> None:
        for i, lim in ((0, self.limit), (1, self.turn_limit)):
            change = float(command[i]) - float(self.velocity[i])
            self.velocity[i] += max(-lim * DT, min(lim * DT, change))


def drive(limit: float, turn_limit: float, goal: tuple[float, float], heading: float | None = None,
          wall: float | None = 0.45, closed: bool = True, seconds: float = 30.0,
          start: tuple[float, float, float] = (0.0, 0.0, 0.0), speed: float = 0.0) -> dict[str, object]:
    """fastep_route's defaults, through the control tick (a plan every tick), on a SlowBase from (0, 0, 0) to goal
    with a wall `wall` metres beyond it (centre to wall). closed: the measured velocity is given; else not."""
    obstacles = () if wall is None else (Segment((goal[0] + wall, -3.0), (goal[0] + wall, 3.0)),)
    world = World((-2.0, -4.0, 12.0, 4.0), obstacles)
    nav = make_navigator('fastep_route', RobotSpec('r1', 'diff_drive', start, goal, RADIUS), RADIUS,
                         world, P, np.random.default_rng(0))
    nav.set_goal(goal, heading=heading)
    control = ControlTick(nav)
    base = SlowBase(limit, turn_limit, np.array([speed, 0.0]))
    state, t, clearance, farthest, modes = np.array(start), 0.0, math.inf, -math.inf, []
    headings = []
    while t < seconds:
        measured = base.velocity.copy() if closed else None
        plan = Plan.of(nav, t, nav.update(t, state, [], measured))
        modes.append((plan.mode, plan.reason, base.velocity.copy()))
        if plan.mode is Mode.ARRIVED:
            break
        base.step(control.command(t, state, [], plan, DT, measured))
        state = nav.model.integrate(state, base.velocity, DT)
        t += DT
        farthest = max(farthest, float(state[0]))
        headings.append(float(state[2]))
        if wall is not None:
            clearance = min(clearance, goal[0] + wall - float(state[0]) - RADIUS)
    return {'arrived': modes[-1][0] is Mode.ARRIVED, 'state': state, 'velocity': base.velocity.copy(),
            'clearance': clearance, 'overshoot': farthest - goal[0], 'modes': modes, 'response': nav.response,
            'headings': headings}


@pytest.mark.parametrize('limit, turn_limit', [(0.8, 1.5), (0.5, 1.5)])
def test_a_base_that_brakes_slower_than_told_stops_at_a_goal_before_a_wall(limit, turn_limit):
    """The report: a 40 kg base (0.8 m/s^2) arrived at 0.9 m/s and hit the wall 0.45 m behind the goal."""
    run = drive(limit, turn_limit, (5.0, 0.0))
    assert run['arrived']
    assert run['clearance'] > 0.1
    assert run['overshoot'] <= 0.1
    response = run['response']
    assert isinstance(response, BaseResponse)
    # Seen only speeding up at `limit`: stops are planned at 0.6 of it until it has braked hard (it never needs to).
    assert response.linear.accelerating == pytest.approx(limit, rel=0.05) and response.linear.braking is None
    assert response.braking == pytest.approx(0.6 * limit, rel=0.05)
    assert f'braking {0.6 * limit:.2g} m/s^2 measured, max_acceleration 2.5' in response.problem()


def test_open_loop_the_same_base_is_said_arrived_while_it_still_drives():
    """What closing the loop changes: without the measured velocity the goal is reached at speed (the old way)."""
    run = drive(0.8, 1.5, (5.0, 0.0), closed=False)
    assert run['arrived'] and float(run['velocity'][0]) > 0.5
    assert run['response'].problem() == ''   # nothing measured: nothing known


def test_arrival_waits_until_the_measured_speed_is_below_trans_stopped_velocity():
    run = drive(0.8, 1.5, (5.0, 0.0))
    stopping = [v for mode, reason, v in run['modes'] if reason == STOPPING]
    assert stopping and all(mode is Mode.KINEMATIC for mode, reason, _ in run['modes'] if reason == STOPPING)
    assert max(abs(float(v[0])) for v in stopping) > P.trans_stopped_velocity
    _, _, last = run['modes'][-1]
    assert abs(float(last[0])) <= P.trans_stopped_velocity and abs(float(last[1])) <= P.rot_stopped_velocity


@pytest.mark.parametrize('limit, turn_limit', [(2.5, 3.2), (0.8, 1.0), (0.5, 0.6)])
def test_a_goal_heading_is_reached_stopped_and_within_tolerance_on_a_slow_turning_base(limit, turn_limit):
    """The report: arrived while still turning at 1.9 rad/s, ending 0.65 rad off."""
    run = drive(limit, turn_limit, (5.0, 0.0), heading=math.pi / 2)
    assert run['arrived'] and run['clearance'] > 0.1
    state, velocity = run['state'], run['velocity']
    assert abs(math.remainder(float(state[2]) - math.pi / 2, math.tau)) <= P.yaw_goal_tolerance
    assert abs(float(velocity[1])) <= P.rot_stopped_velocity


def test_a_base_that_does_what_it_is_told_measures_nothing_and_keeps_the_configured_limits():
    run = drive(1e9, 1e9, (5.0, 0.0), wall=None)
    response = run['response']
    assert run['arrived']
    assert response.linear.shown is None and response.turn.shown is None
    assert response.braking == P.max_acceleration and response.problem() == ''


def test_response_measures_braking_over_a_run_and_never_above_the_limit():
    response = BaseResponse(False, 2.5, 3.2)
    velocity, t = 1.0, 0.0
    for _ in range(12):   # asked to brake at the limit; the base does 1.0 m/s^2
        command = max(velocity - 2.5 * DT, 0.0)
        response.observe(t, np.array([velocity, 0.0]), np.array([command, 0.0]))
        velocity, t = max(velocity - 1.0 * DT, 0.0), t + DT
    assert response.linear.braking == pytest.approx(1.0)
    assert response.braking == pytest.approx(1.0) and response.stop_within(5.0) == pytest.approx(1.0)
    strong = BaseResponse(False, 2.5, 3.2)
    velocity, t = 2.0, 0.0
    for _ in range(12):    # an emergency stop asks 5 m/s^2; the base does 4: within the limit, 2.5
        command = max(velocity - 5.0 * DT, 0.0)
        strong.observe(t, np.array([velocity, 0.0]), np.array([command, 0.0]))
        velocity, t = max(velocity - 4.0 * DT, 0.0), t + DT
    assert strong.braking == 2.5 and strong.stop_within(5.0) == pytest.approx(4.0)


def test_response_ignores_a_base_one_command_behind_and_commands_it_was_not_asked_to_follow_fast():
    response = BaseResponse(False, 2.5, 3.2)
    commands = [min(0.125 * k, 1.0) for k in range(1, 20)]
    for k, command in enumerate(commands):   # odometry two commands late, exactly (a plant node on a graph)
        measured = commands[k - 2] if k >= 2 else 0.0
        response.observe(k * DT, np.array([measured, 0.0]), np.array([command, 0.0]))
    assert response.linear.shown is None
    gentle = BaseResponse(False, 2.5, 3.2)
    for k in range(20):   # a ramp of 0.5 m/s^2 the base follows 0.06 m/s behind: never asked the configured rate
        gentle.observe(k * DT, np.array([max(0.025 * k - 0.06, 0.0), 0.0]), np.array([0.025 * (k + 1), 0.0]))
    assert gentle.linear.shown is None


def test_off_commands_allows_an_exact_earlier_command_but_not_a_base_lagging_a_ramp():
    recent = [np.array([0.3, 0.0]), np.array([0.425, 0.0])]
    assert not off_commands(np.array([0.3, 0.0]), recent, False)        # one command behind, exactly
    assert not off_commands(np.array([0.4, 0.02]), recent, False)       # within the bound of the last
    assert off_commands(np.array([0.34, 0.0]), recent, False)           # between them: a base that lags
    assert off_commands(np.array([0.425, 0.3]), recent, False)          # turning when told not to
    assert not off_commands(np.array([5.0, 5.0]), [], False)


def test_the_smoother_ramps_from_odometry_when_the_base_is_off_its_commands():
    smoother = VelocitySmoother.for_model(DiffDrive(P.max_speed, P.max_turn_rate), P.limits)
    smoother.reset(np.array([0.3, 0.0]))
    assert smoother.smooth(np.array([0.0, 0.0]), DT)[0] == pytest.approx(0.3 - 2.5 * DT)
    assert smoother.feedback(np.array([0.9, 0.0]))   # a heavy base coasting faster than it is told
    assert smoother.smooth(np.array([0.0, 0.0]), DT)[0] == pytest.approx(0.9 - 2.5 * DT)
    assert not smoother.feedback(np.array([0.9 - 2.5 * DT, 0.0]))
    assert not smoother.feedback(None) and not smoother.feedback(np.array([math.nan, 0.0]))


def test_a_goal_carried_past_is_backed_up_to_not_turned_round_for():
    """The report: the heavy base overshot open-floor goals and looped back 4-8 times."""
    run = drive(0.8, 1.5, (5.0, 0.0), wall=None, start=(4.7, 0.0, 0.0), speed=1.0)
    assert run['overshoot'] > 0.3   # 1 m/s, 0.3 m before the goal, braking at 0.8: it cannot stop in time
    assert run['arrived']
    assert any(reason == RETURNING for _, reason, _ in run['modes'])
    assert max(abs(h) for h in run['headings']) < 0.2   # backed straight up: no turn round
    assert float(np.linalg.norm(run['state'][:2] - np.array([5.0, 0.0]))) <= P.goal_tolerance


def test_a_point_mass_has_no_turn_to_report():
    response = BaseResponse(True, 2.5, 3.2)
    assert response.turn_braking == 0.0 and response.problem() == ''


def test_poses_that_move_as_the_twist_says_change_nothing_and_a_slide_shows():
    model, response = DiffDrive(P.max_speed, P.max_turn_rate), BaseResponse(False, 2.5, 3.2)
    state, command = np.array([0.0, 0.0, 0.3]), np.array([0.8, 1.5])
    for k in range(10):   # a kinematic arc: the chord is a little shorter than the arc, never more
        state = model.integrate(state, command, DT)
        assert response.slide((k + 1) * DT, command, state) is command
    slid = response.slide(11 * DT, np.array([0.2, 1.5]), model.integrate(state, command, DT))
    assert slid[0] == pytest.approx(0.8, rel=0.01) and slid[1] == 1.5   # wheels at 0.2, the base moving at 0.8
    assert response.corrected(np.array([0.2, 0.0]))[0] == pytest.approx(0.8, rel=0.01)


def test_the_control_tick_judges_slides_by_the_odometry_pose_not_the_state_predicted_with_the_command():
    """On wall time the state is the odometry's pose predicted forward with the last command over its age: a base
    behind its command looked as if it followed it (a 0.8 m/s^2 base measured at 2.7, and driven into a wall)."""
    world = World((-2.0, -4.0, 30.0, 4.0), ())
    nav = make_navigator('fastep_route', RobotSpec('r1', 'diff_drive', (0.0, 0.0, 0.0), (25.0, 0.0), RADIUS), RADIUS,
                         world, P, np.random.default_rng(0))
    nav.set_goal((25.0, 0.0))
    control = ControlTick(nav)
    pose, twist = np.zeros(3), np.array([0.5, 0.0])
    for k in range(20):
        t = k * DT
        ahead = 0.02 * (k % 2)   # the odometry's age at the tick: 0 or 20 ms
        state = pose + np.array([1.0 * ahead, 0.0, 0.0])   # predicted with a command of 1 m/s
        plan = Plan.of(nav, t, nav.update(t, state, [], twist))
        control.command(t, state, [], plan, DT, twist, t, pose)
        assert nav.response.corrected(twist) is twist   # no slide: the base does what its odometry says
        pose = pose + np.array([0.5 * DT, 0.0, 0.0])


def test_late_ticks_still_measure_a_base_that_cannot_follow_its_ramp():
    """On a busy machine ticks come late: the smoother still ramps at most one period's change per command, and the
    base was measured only when the check allowed for it (a heavy base taken at 2.5 m/s^2 drove into the wall)."""
    response = BaseResponse(False, 2.5, 3.2, period=DT)
    velocity, t = 0.0, 0.0
    for _ in range(12):
        command = velocity + 2.5 * DT   # the closed-loop ramp from what the base does
        response.observe(t, np.array([velocity, 0.0]), np.array([command, 0.0]))
        velocity, t = velocity + 0.8 * 0.09, t + 0.09   # 90 ms ticks; the base accelerates at 0.8
    assert response.linear.accelerating == pytest.approx(0.8)
