"""The navigator's decisions tick by tick: goals, detection, the guard and its hold breaker."""

import numpy as np
import pytest

from fastep_core.errors import GoalError
from fastep_core.geometry import Circle, Segment
from fastep_core.kinematics import TractorTrailer
from fastep_core.planning import FAStepKinematic, Mode, OtherRobot, PlannerParams, make_navigator
from fastep_core.planning.recovery import manoeuvre_driver
from fastep_core.planning.recovery.manoeuvre_search import Manoeuvre
from fastep_core.planning.shortest_path.exact_path import BLOCKED_RETRY, NoPathHold
from fastep_core.scenario import RobotSpec
from fastep_core.world import World

WORLD = World.from_obstacles([0, 0, 50, 50], [Circle((25.0, 25.0), 3.0)])
SPEC = RobotSpec('r1', 'point_mass', (5.0, 5.0), (45.0, 45.0), 0.5)


def navigator(world=WORLD, seed=0, algorithm='fastep'):
    return make_navigator(algorithm, SPEC, 0.5, world, PlannerParams(), seed)


@pytest.mark.parametrize('goal, words', [((25.0, 25.0), 'inside an obstacle'), ((60.0, 5.0), 'outside the map'),
                                         ((float('nan'), 3.0), 'not finite'), ((25.0, 28.3), 'occupied')])
def test_bad_goals_are_refused_with_a_reason(goal, words):
    nav = navigator()
    with pytest.raises(GoalError, match=words):
        nav.set_goal(goal)
    assert nav.mode is Mode.IDLE and np.all(nav.update(0.0, np.array([5.0, 5.0])) == 0.0)


def test_far_obstacle_on_the_line_is_not_detected_until_near():
    nav = navigator(algorithm='fastep_paper')
    nav.set_goal((45.0, 45.0))
    nav.update(0.0, np.array([5.0, 5.0]))
    assert nav.mode is Mode.KINEMATIC and nav.activations == 0
    nav.update(0.05, np.array([21.0, 21.0]))   # 2.66 m from the circle's surface, on the line
    assert nav.mode is Mode.AVOIDING and nav.activations == 1 and nav.cost > 0.0


def test_by_default_the_swarm_waits_until_the_obstacle_is_within_the_plan_horizon():
    nav = navigator()
    nav.set_goal((45.0, 45.0))
    nav.update(0.0, np.array([5.0, 5.0]))
    nav.update(0.05, np.array([21.0, 21.0]))   # detected (2.66 m, eq. 11) but beyond the 2 m plan horizon
    assert nav.mode is Mode.KINEMATIC and nav.activations == 0 and nav.reason == 'way is clear for now'
    nav.update(0.1, np.array([21.8, 21.8]))    # 1.53 m from the surface: within a step
    assert nav.mode is Mode.AVOIDING and nav.activations == 1 and nav.cost > 0.0


def test_non_finite_state_holds_still_without_failing():
    nav = navigator()
    nav.set_goal((45.0, 45.0))
    assert np.all(nav.update(0.0, np.array([np.nan, 5.0])) == 0.0)
    assert nav.mode is Mode.KINEMATIC and 'not finite' in nav.reason


def test_robot_held_by_the_guard_steps_around_after_a_second(monkeypatch):
    world = World.from_obstacles([0, 0, 50, 50], [])
    nav = navigator(world)
    nav.set_goal((45.0, 5.0))
    # Pretend detection misses the robot in the way, so only the guard stands between them.
    monkeypatch.setattr(FAStepKinematic, 'blocked', lambda self, *a, **k: False)
    other = [OtherRobot('r2', (6.1, 5.0), (0.0, 0.0), 0.5)]
    state = np.array([5.0, 5.0])
    t = 0.0
    for _ in range(10):
        assert np.all(nav.update(t, state, other) == 0.0) and 'giving way to r2' in nav.reason
        t += 0.05
    while t < 1.2:
        command = nav.update(t, state, other)
        t += 0.05
    assert nav.activations == 1 and nav.waypoint is not None
    assert np.hypot(*(nav.waypoint - [6.1, 5.0])) >= 1.2 - 1e-9
    assert np.any(command != 0.0)


def test_failure_clears_the_target():
    nav = navigator()
    nav.set_goal((45.0, 45.0))
    nav.update(0.0, np.array([5.0, 5.0]))
    assert nav.target is not None
    nav.fail('test')
    assert nav.target is None and nav.mode is Mode.FAILED


def test_others_with_nan_positions_are_ignored():
    nav = navigator()
    nav.set_goal((45.0, 45.0))
    command = nav.update(0.0, np.array([5.0, 5.0]), [OtherRobot('r2', (float('nan'), 5.0))])
    assert np.all(np.isfinite(command)) and np.any(command != 0.0)


def test_robot_boxed_in_by_robots_retries_twice_a_second_then_fails_on_progress():
    params = PlannerParams(progress_timeout=10.0)
    nav = make_navigator('fastep', SPEC, 0.5, WORLD, params, 0)
    nav.set_goal((30.0, 10.0))
    state, t = np.array([10.0, 10.0]), 0.0
    ring = [OtherRobot(f'o{k}', (10.0 + 1.05 * np.cos(k * np.pi / 4), 10.0 + 1.05 * np.sin(k * np.pi / 4)))
            for k in range(8)]
    while t < 12.0 and nav.mode is not Mode.FAILED:
        assert np.all(nav.update(t, state, ring) == 0.0)
        t += 0.05
    assert nav.mode is Mode.FAILED and 'progress' in nav.reason
    assert 15 <= nav.activations <= 25   # about two attempts a second for 10 s, not one per tick


def test_walled_in_robot_reports_no_valid_path_on_the_first_tick():
    from fastep_core.geometry import Segment
    a, b = 9.4, 10.6
    walls = [Segment((a, a), (b, a)), Segment((b, a), (b, b)), Segment((b, b), (a, b)), Segment((a, b), (a, a))]
    world = World.from_obstacles([0, 0, 50, 50], walls)
    for algorithm in ('fastep', 'aco', 'optimal'):
        nav = make_navigator(algorithm, SPEC, 0.5, world, PlannerParams(), 0)
        nav.set_goal((30.0, 30.0))
        assert np.all(nav.update(0.0, np.array([10.0, 10.0])) == 0.0)
        assert nav.mode is Mode.FAILED and nav.reason.startswith('no valid path'), algorithm
        assert nav.activations == 0 or algorithm == 'optimal'


def test_guard_predicts_a_tractor_trailers_tick_as_the_plant_integrates_it():
    """On a tight turn the RK4 step ends off the straight Euler guess; an obstacle the true step would enter
    (and the guess would miss) stops the robot."""
    model, dt, radius = TractorTrailer(), 0.05, 0.5
    state, command = np.array([10.0, 10.0, 0.0, 0.0]), np.array([1.0, 1.0])
    true_next = model.integrate(state, command, dt)[:2]
    euler_next = state[:2] + model.velocity(state, command) * dt
    away = (true_next - euler_next) / np.hypot(*(true_next - euler_next))
    assert np.hypot(*(true_next - euler_next)) > 1e-3
    # A circle whose surface the true step ends 0.5 mm inside the radius of; the Euler guess stays outside.
    centre = true_next + away * (1.0 + radius - 5e-4)
    world = World.from_obstacles([0, 0, 50, 50], [Circle((float(centre[0]), float(centre[1])), 1.0)])
    nav = make_navigator('fastep', RobotSpec('r1', 'tractor_trailer', tuple(state), (45.0, 45.0), radius),
                         radius, world, PlannerParams(dt=dt), 0)
    assert float(world.obstacles.clearance(euler_next[None])[0]) > radius
    guarded = nav.guard(state, command, dt, [])
    assert np.all(guarded == 0.0) and 'obstacle is within the robot radius' in nav.reason
    # Steering the other way turns it clear of the circle: the guard lets that through.
    assert np.any(nav.guard(state, np.array([1.0, -1.0]), dt, []) != 0.0)


def test_a_manoeuvre_that_did_not_help_is_followed_by_one_all_the_way_to_the_goal(monkeypatch):
    """A manoeuvre ends where the goal is in clear sight; stuck again without coming progress_distance nearer,
    the next one may not stop at "in sight" (clear_within inf) and goes on until the goal is within reach."""

    asked = []

    def fake_plan(model, world, state, goal, keep, dt, **kwargs):
        asked.append(kwargs['clear_within'])
        s = np.asarray(state, dtype=float)
        return Manoeuvre(np.zeros((1, 2)), np.array([s, s]), 1, 0, 1)

    monkeypatch.setattr(manoeuvre_driver, 'plan_manoeuvre', fake_plan)
    spec = RobotSpec('r1', 'tractor_trailer', (5.0, 5.0, 0.0, 0.0), (45.0, 5.0), 0.5)
    nav = make_navigator('fastep', spec, 0.5, World.from_obstacles([0, 0, 50, 50], []), PlannerParams(), 0)
    assert isinstance(nav.model, TractorTrailer)
    nav.set_goal((45.0, 5.0))
    state = np.array([5.0, 5.0, 0.0, 0.0])
    assert nav.start_manoeuvre(state, 0.0, [])
    assert nav.drive_manoeuvre(state, 0.0, 0.05, 40.0, []) is not None
    assert nav.drive_manoeuvre(state, 0.05, 0.05, 40.0, []) is None        # over: it ended 40 m from the goal
    assert nav.start_manoeuvre(state + [0.1, 0.0, 0.0, 0.0], 1.0, [])     # stuck again, 0.1 m nearer
    assert nav.manoeuvring is not None
    nav.manoeuvring.current = None
    progress = nav.params.progress_distance
    assert nav.start_manoeuvre(state + [progress + 0.1, 0.0, 0.0, 0.0], 2.0, [])   # came nearer meanwhile
    assert np.isfinite(asked[0]) and asked[1] == np.inf and np.isfinite(asked[2])


@pytest.fixture
def rule_gives_up(monkeypatch):
    """Every step plan that keeps right gives up (step.RULE_CALLS spent); the plans made, in order."""
    from fastep_core.planning.swarm import step as step_module
    plans: list[str] = []
    start = step_module.StepRun.__init__

    def started(self, problem, params, rng, method='fastep', feasible_within=None):
        start(self, problem, params, rng, method, feasible_within)
        plans.append('plain' if feasible_within is None else 'rule')
        if feasible_within is not None:
            def gives_up(X):
                raise step_module._GaveUp
            self.fitness = gives_up

    monkeypatch.setattr(step_module.StepRun, '__init__', started)
    return plans


def test_a_tick_that_cannot_keep_right_drives_on_and_the_plain_step_is_planned_on_the_next(rule_gives_up):
    """One swarm run per tick: the rule's give-up and the plan without it used to share a tick (the slowest
    ticks of a crowd); the robot drives on toward its last target in between instead of stopping."""
    plans = rule_gives_up
    world = World.from_obstacles([0, 0, 50, 50], [])
    nav = navigator(world)
    nav.set_goal((30.0, 10.0))
    state = np.array([10.0, 10.0])
    first = nav.update(0.0, state)
    assert first[0] > 0.0 and plans == []
    ahead = [OtherRobot('r2', (11.8, 10.0), (0.0, 0.0), 0.5)]
    on = nav.update(0.05, state, ahead)
    assert plans == ['rule'] and 'keep right' in nav.reason and nav.waypoint is None and nav.step_deferred
    assert np.allclose(on, first)      # toward the goal it was driving to, not a stop
    nav.update(0.1, state, ahead)
    assert plans == ['rule', 'plain'] and nav.waypoint is not None and nav.activations == 1
    nav.waypoint = None                # a later tick plans with the rule again
    nav.update(0.15, state, ahead)
    assert plans[2] == 'rule'


def test_a_new_goal_after_a_give_up_plans_its_first_step_with_the_rule_again(rule_gives_up):
    plans = rule_gives_up
    nav = navigator(World.from_obstacles([0, 0, 50, 50], []))
    nav.set_goal((30.0, 10.0))
    state, ahead = np.array([10.0, 10.0]), [OtherRobot('r2', (11.8, 10.0), (0.0, 0.0), 0.5)]
    nav.update(0.0, state)
    nav.update(0.05, state, ahead)
    nav.set_goal((30.0, 10.5), 0.05)
    nav.update(0.1, state, ahead)
    assert plans == ['rule', 'rule'] and nav.activations == 2   # the new goal's first step, counted


@pytest.mark.parametrize('algorithm', ['fastep', 'optimal'])
def test_a_hold_breaker_step_that_cannot_keep_right_is_planned_plainly_on_the_next_tick(rule_gives_up, monkeypatch,
                                                                                        algorithm):
    """The hold breaker comes once: when its step cannot keep right, the next tick plans the plain step as the
    hold breaker's, committed (left to choose_target, a planner that follows a path never planned it and the
    robot stayed held)."""
    plans = rule_gives_up
    nav = make_navigator(algorithm, SPEC, 0.5, World.from_obstacles([0, 0, 50, 50], []), PlannerParams(), 0)
    nav.set_goal((30.0, 10.0))
    # Pretend detection misses the robot in the way, so only the guard and its hold breaker act.
    monkeypatch.setattr(type(nav), 'blocked', lambda self, *a, **k: False)
    other = [OtherRobot('r2', (11.7, 10.0), (0.0, 0.0), 0.5)]
    state, t = np.array([10.6, 10.0]), 0.0
    while t < 1.2 and not plans:
        nav.update(t, state, other)
        t += 0.05
    assert plans == ['rule'] and nav.step_deferred
    activations = nav.activations
    command = nav.update(t, state, other)
    assert plans == ['rule', 'plain'] and nav.waypoint is not None and nav.activations == activations
    assert np.any(command != 0.0)
    for _ in range(5):   # committed: driven to, not planned again
        t += 0.05
        state = state + 0.05 * command
        command = nav.update(t, state, other)
    assert plans == ['rule', 'plain'] and np.any(command != 0.0)


def test_a_step_plan_over_budget_is_finished_on_the_next_ticks_while_the_robot_drives_on():
    """params.step_iterations bounds a control tick's swarm work: the plan is finished over the next ticks, as one
    activation, from where it began, and comes out as the waypoint the whole plan gives; meanwhile the robot
    drives on toward the target it had rather than stopping."""
    world = World.from_obstacles([0, 0, 50, 50], [Circle((13.5, 10.0), 1.0)])
    whole = make_navigator('fastep', SPEC, 0.5, world, PlannerParams(), 0)
    spread = make_navigator('fastep', SPEC, 0.5, world, PlannerParams(step_iterations=1), 0)
    far, near = np.array([8.0, 10.0]), np.array([11.0, 10.0])   # the circle's surface 4.5 and 1.5 m ahead
    for nav in (whole, spread):
        nav.set_goal((30.0, 10.0))
        nav.update(0.0, far)
    whole.update(0.05, near)
    assert whole.waypoint is not None and whole.activations == 1
    command = spread.update(0.05, near)
    assert spread.waypoint is None and spread.step_deferred and 'planning a step' in spread.reason
    assert command[0] > 0.0 and spread.mode is Mode.AVOIDING   # driving on toward the goal, guarded
    ticks, t = 1, 0.05
    while spread.waypoint is None:
        t += 0.05
        spread.update(t, near)
        ticks += 1
    assert ticks > 1
    assert np.array_equal(spread.waypoint, whole.waypoint) and spread.cost == whole.cost
    assert spread.activations == 1 and not spread.step_deferred


def test_a_new_goal_drops_an_unfinished_step_plan():
    world = World.from_obstacles([0, 0, 50, 50], [Circle((13.5, 10.0), 1.0)])
    nav = make_navigator('fastep', SPEC, 0.5, world, PlannerParams(step_iterations=1), 0)
    nav.set_goal((30.0, 10.0))
    nav.update(0.0, np.array([11.0, 10.0]))
    assert nav.step_deferred and nav.activations == 1
    nav.set_goal((30.0, 10.5), 0.05)
    nav.update(0.05, np.array([11.0, 10.0]))
    assert nav.activations == 2   # a plan of its own for the new goal, not the old one finished


def test_with_a_budget_a_tick_that_planned_a_route_leaves_the_step_to_the_next():
    """FAStep-Route: a route replan and a step plan in one tick were the slowest ticks left in a crowd; with
    step_iterations set, such a tick runs no swarm iteration (the step continues next tick). Without a budget the
    step is planned whole, as always."""
    spread = make_navigator('fastep_route', SPEC, 0.5, WORLD, PlannerParams(step_iterations=3), 0)
    whole = make_navigator('fastep_route', SPEC, 0.5, WORLD, PlannerParams(), 0)
    for nav in (spread, whole):
        nav.set_goal((45.0, 45.0))
        nav.update(0.0, np.array([5.0, 5.0]))   # the goal's first tick plans the first route
    assert spread.step_budget() == 0 and whole.step_budget() is None
    spread.update(0.05, np.array([5.1, 5.1]))   # no route this tick
    assert spread.step_budget() == 3


def test_an_unfinished_step_plan_is_planned_afresh_when_the_world_changed_or_time_went_by():
    """A plan left unfinished continues only on the very next tick, within PENDING_FOR, in the same world: a new
    obstacle where its waypoint would land is planned round (afresh and whole, so a world changing every tick
    cannot keep a plan from ending), and robots seen 10 s ago are not."""
    old = World.from_obstacles([0, 0, 50, 50], [Circle((13.5, 10.0), 1.0)])
    whole = make_navigator('fastep', SPEC, 0.5, old, PlannerParams(), 0)
    whole.set_goal((30.0, 10.0))
    whole.update(0.0, np.array([11.0, 10.0]))
    assert whole.waypoint is not None
    new = World.from_obstacles([0, 0, 50, 50], [Circle((13.5, 10.0), 1.0), Circle(tuple(whole.waypoint), 0.5)])
    for gap, world in ((0.05, new), (10.0, old)):
        nav = make_navigator('fastep', SPEC, 0.5, old, PlannerParams(step_iterations=1), 0)
        nav.set_goal((30.0, 10.0))
        nav.update(0.0, np.array([11.0, 10.0]))
        assert nav.step_deferred and nav.activations == 1
        nav.world = world
        nav.update(gap, np.array([11.0, 10.0]))
        assert nav.activations == 2                               # planned afresh, not continued
        if world is new:                                          # ... whole, round the new obstacle
            assert nav.waypoint is not None and not nav.step_deferred
            assert new.obstacles.clearance(nav.waypoint) >= nav.clearance - 1e-9


def test_with_a_budget_the_robot_stands_while_the_hold_breakers_step_is_planned(monkeypatch):
    """Driving on while the hold breaker's step is planned would drive at what holds the robot; the guard would
    stop it again and call the hold breaker a second time. So the robot stands until the step is planned, then
    drives it, committed, as without a budget: one activation."""
    monkeypatch.setattr(FAStepKinematic, 'blocked', lambda self, *a, **k: False)   # only the guard acts
    for budget in (0, 1):
        nav = make_navigator('fastep', SPEC, 0.5, World.from_obstacles([0, 0, 50, 50], []),
                             PlannerParams(step_iterations=budget), 0)
        nav.set_goal((30.0, 10.0))
        other = [OtherRobot('r2', (11.7, 10.0), (0.0, 0.0), 0.5)]
        state, t, pending = np.array([10.6, 10.0]), 0.0, []
        for _ in range(60):
            command = nav.update(t, state, other)
            if nav.step_deferred:
                pending.append(tuple(command))
            state, t = state + 0.05 * command, t + 0.05
        assert nav.activations == 1 and nav.waypoint is not None and nav.committed
        assert all(c == (0.0, 0.0) for c in pending) and (len(pending) > 0) == (budget > 0)


def test_a_step_plan_given_no_iteration_every_tick_still_ends(monkeypatch):
    """A tick may give a step plan no swarm iteration (FAStep-Route, after a route), but never two ticks in a row:
    routes every tick would otherwise keep the step from ever ending."""
    monkeypatch.setattr(FAStepKinematic, 'step_budget', lambda self: 0)
    nav = make_navigator('fastep', SPEC, 0.5, World.from_obstacles([0, 0, 50, 50], [Circle((13.5, 10.0), 1.0)]),
                         PlannerParams(step_iterations=3), 0)
    nav.set_goal((30.0, 10.0))
    ticks, t = 0, 0.0
    while nav.waypoint is None and ticks < 40:
        nav.update(t, np.array([11.0, 10.0]))
        ticks, t = ticks + 1, t + 0.05
    assert nav.waypoint is not None and nav.activations == 1 and 2 < ticks < 40


def test_with_a_budget_routes_every_tick_still_let_the_step_end():
    """FAStep-Route replans its route every tick when the world changes near the route every tick (perception: a
    circle by the route fitted larger, then smaller): such a tick still gets its step planned (a plan is planned
    whole after a world change)."""
    def world(k):
        return World.from_obstacles([0, 0, 50, 50], [Circle((20.0, 11.0), 0.7 if k % 2 else 0.5)])
    nav = make_navigator('fastep_route', SPEC, 0.5, world(0), PlannerParams(step_iterations=3), 0)
    nav.set_goal((30.0, 10.0))
    state, t = np.array([10.0, 10.0]), 0.0
    nav.update(t, state)
    for k in range(20):
        t += 0.05
        nav.world = world(k + 1)
        command = nav.update(t, state, [OtherRobot('r2', (state[0] + 2.0, 10.0), (-0.3, 0.0), 0.5)])
        state = state + 0.05 * command
    assert nav.replans >= 20 and len(nav.plan) >= 1 and nav.reason != 'planning a step (finished on the next tick)'


@pytest.mark.parametrize('algorithm', ['fastep', 'fastep_route'])
def test_no_path_in_what_the_laser_shows_holds_the_robot_and_it_goes_on_once_the_belief_opens(algorithm):
    """A belief closing the only way (a mover standing in a doorway, a wrong wall) holds a robot that plans in its
    scans, the status naming what is in the way; a new belief with the way open lets it go on. Without a laser, and
    after blocked_timeout, no path fails the goal."""
    room = [Segment((10.0, 0.0), (10.0, 9.0)), Segment((10.0, 11.0), (10.0, 20.0))]   # a 2 m door at y 9-11
    closed = World.from_obstacles([0, 0, 20, 20], [*room, Circle((10.0, 10.0), 1.2)])
    opened = World.from_obstacles([0, 0, 20, 20], room)
    state = np.array([5.0, 10.0])
    nav = make_navigator(algorithm, SPEC, 0.5, closed, PlannerParams(), 0)
    nav.from_scans = True
    nav.set_goal((15.0, 10.0))
    for k in range(40):                                     # 2 s
        command = nav.update(0.05 * k, state)
        assert not nav.failed and np.all(command == 0.0)
    assert nav.reason.startswith('blocked: no way to the goal') and '(10.00, 10.00)' in nav.reason
    nav.world = opened
    nav.update(2.0, state)
    assert not nav.failed and np.hypot(*nav.update(2.05, state)) > 0.0
    blind = make_navigator(algorithm, SPEC, 0.5, closed, PlannerParams(), 0)
    blind.set_goal((15.0, 10.0))
    blind.update(0.0, state)
    assert blind.failed and blind.reason.startswith('no valid path')
    patient = make_navigator(algorithm, SPEC, 0.5, closed, PlannerParams(blocked_timeout=1.0), 0)
    patient.from_scans = True
    patient.set_goal((15.0, 10.0))
    for k in range(30):
        patient.update(0.05 * k, state)
    assert patient.failed and patient.reason.startswith('no valid path')


def test_the_no_path_hold_keeps_its_own_time_apart_from_fastep_routes_route_wait():
    """FAStep-Route's wait for a robot standing on its route and the no-path hold are two timers: a path found does
    not restart the route's wait, and the wait's start is not taken as when the hold began."""
    world = World.from_obstacles([0, 0, 20, 20], [Circle((10.0, 10.0), 1.0)])
    nav = make_navigator('fastep_route', SPEC, 0.5, world, PlannerParams(), 0)
    nav.from_scans = True
    nav.set_goal((15.0, 10.0))
    nav.update(3.0, np.array([5.0, 10.0]))
    nav._blocked_since = 1.0   # a robot has stood on the route since t = 1
    assert nav.exact_path(np.array([5.0, 10.0])) is not None
    assert nav._blocked_since == 1.0 and nav.no_path.since is None
    nav.fail_no_path(np.array([5.0, 10.0]))   # held from now (t = 3), not from the route's t = 1
    assert not nav.failed and nav.no_path.since == 3.0 and nav._blocked_since == 1.0


def test_a_no_path_hold_searches_again_on_a_new_belief_or_after_the_retry_time():
    hold = NoPathHold()
    believed, newer = World.from_obstacles([0, 0, 20, 20], []), World.from_obstacles([0, 0, 20, 20], [])
    hold.searched(believed, 0.0, found=False)
    assert hold.waited(0.0, 10.0, from_scans=True) == 0.0
    assert hold.skip_search(believed, 0.5) and not hold.skip_search(newer, 0.5)
    assert not hold.skip_search(believed, BLOCKED_RETRY)
    assert hold.waited(4.0, 10.0, from_scans=True) == 4.0 and hold.waited(10.0, 10.0, from_scans=True) is None
    assert hold.waited(0.0, 10.0, from_scans=False) is None and hold.since is None
    hold.searched(newer, 1.0, found=False)
    hold.waited(1.0, 10.0, from_scans=True)
    hold.searched(newer, 2.0, found=True)
    assert hold.since is None and not hold.skip_search(newer, 2.1)
