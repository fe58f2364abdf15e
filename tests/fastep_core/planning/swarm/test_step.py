import numpy as np
import pytest

from fastep_core.errors import ParameterError
from fastep_core.geometry import Circle, Segment
from fastep_core.planning import PlannerParams, StepProblem, plan_step
from fastep_core.planning.swarm.step import INFEASIBLE
from fastep_core.world import World

WORLD = World.from_obstacles([0, 0, 50, 50], [Circle((10.0, 10.0), 2.0), Segment((14.0, 5.0), (14.0, 15.0))])


def problem(origin=(7.0, 7.0), target=(20.0, 20.0), **kw):
    return StepProblem(WORLD, np.array(origin), np.array(target), clearance=0.7, step_radius=2.0, **kw)


def test_fitness_matches_eq10_where_feasible():
    p = problem()
    x = np.array([[6.0, 8.5]])
    f1 = WORLD.obstacles.distances(x).sum()
    expected = 0.18 / f1 + 0.01 * np.hypot(20 - 6.0, 20 - 8.5)
    assert p.fitness(x)[0] == pytest.approx(expected)


def test_infeasible_candidates_always_lose():
    p = problem()
    inside = np.array([[10.0, 10.0]])       # in the circle
    too_far = np.array([[7.0, 9.5]])        # beyond the step radius
    through = np.array([[8.6, 8.4]])        # clear itself? no: the run to it clips the circle's clearance
    feasible = np.array([[5.5, 8.2]])
    assert p.fitness(inside)[0] > INFEASIBLE
    assert p.fitness(too_far)[0] > INFEASIBLE
    assert p.fitness(through)[0] > INFEASIBLE
    assert p.fitness(feasible)[0] < INFEASIBLE


def test_run_crossing_a_wall_is_infeasible():
    p = problem(origin=(13.0, 10.0))
    assert p.fitness(np.array([[14.9, 10.0]]))[0] > INFEASIBLE


@pytest.mark.parametrize('seed', range(5))
def test_planned_waypoint_keeps_clearance_and_nears_the_target(seed):
    p = problem()
    step = plan_step(p, PlannerParams(), np.random.default_rng(seed))
    assert step is not None
    w = step.waypoint
    assert np.hypot(*(w - p.origin)) <= 2.0 + 1e-9
    assert WORLD.obstacles.clearance(w) >= 0.7 - 1e-9
    assert WORLD.obstacles.path_clearance(p.origin, w) >= 0.7 - 1e-9
    assert np.hypot(*(w - p.target)) < np.hypot(*(p.origin - p.target))


def test_other_robots_are_kept_at_the_sum_of_radii():
    p = problem(origin=(30.0, 30.0), target=(40.0, 40.0), others=np.array([[31.5, 31.5]]),
                robot_clearance=np.array([1.2]))
    step = plan_step(p, PlannerParams(), np.random.default_rng(1))
    assert step is not None
    assert np.hypot(*(step.waypoint - [31.5, 31.5])) >= 1.2 - 1e-9


def test_boxed_in_robot_gets_no_step():
    a, b = 9.4, 10.6  # a box whose centre is only 0.6 m from the walls: nowhere keeps 0.7 m
    walls = [Segment((a, a), (b, a)), Segment((b, a), (b, b)), Segment((b, b), (a, b)), Segment((a, b), (a, a))]
    world = World.from_obstacles([0, 0, 50, 50], walls)
    p = StepProblem(world, np.array([10.0, 10.0]), np.array([30.0, 30.0]), clearance=0.7, step_radius=2.0)
    assert plan_step(p, PlannerParams(), np.random.default_rng(0)) is None


def test_aco_plans_feasible_steps_too():
    step = plan_step(problem(), PlannerParams(), np.random.default_rng(0), method='aco')
    assert step is not None and WORLD.obstacles.clearance(step.waypoint) >= 0.7 - 1e-9


def oncoming_robot_problem() -> StepProblem:
    """A robot heading +x in a corridor with another robot 3 m ahead, to be kept right of (its position)."""
    world = World.from_obstacles([0, 0, 30, 10], [])
    return StepProblem(world, np.array([13.0, 5.0]), np.array([27.0, 5.0]), clearance=0.7, step_radius=2.0,
                       others=np.array([[16.0, 5.0]]), robot_clearance=np.array([1.2]),
                       pass_on_right=np.array([[16.0, 5.0]]))


def test_pass_on_right_keeps_the_waypoint_right_of_the_oncoming_robot():
    p = oncoming_robot_problem()
    for seed in range(5):
        step = plan_step(p, PlannerParams(), np.random.default_rng(seed))
        assert step is not None and step.waypoint[1] <= 5.0 + 1e-9   # heading +x, right is -y


def test_an_unknown_step_optimizer_is_a_parameter_error():
    with pytest.raises(ParameterError, match="unknown step optimizer 'pso'"):
        plan_step(problem(), PlannerParams(), np.random.default_rng(0), method='pso')


def test_robots_out_of_reach_are_skipped_without_changing_a_bit():
    """In a crowd, the runs' clearance from the other robots is measured only for the robots a run can reach
    (issue 15, many robots); every violation must stay the same, bit for bit, as measuring them all."""
    from fastep_testing.step_reference import reference_terms
    rng = np.random.default_rng(5)
    world = World.from_obstacles([0, 0, 60, 60], [])
    for _ in range(50):
        origin = rng.uniform(5.0, 55.0, 2)
        others = np.vstack([origin + rng.normal(0.0, 2.0, (5, 2)), rng.uniform(0.0, 60.0, (60, 2))])
        problem = StepProblem(world, origin, np.array([59.0, 59.0]), 0.7, 2.0, others=others,
                              robot_clearance=rng.uniform(0.8, 1.5, len(others)))
        X = origin + rng.uniform(-2.0, 2.0, (500, 2))
        assert np.array_equal(problem.terms(X)[1], reference_terms(problem, X)[1])


def test_recorded_step_problems_are_those_posed_inside_the_block():
    from fastep_core.planning.swarm.step import recorded_step_problems
    ahead = np.array([[3.0, 0.0]])
    p = problem()
    with recorded_step_problems() as outer:
        plan_step(p, PlannerParams(), np.random.default_rng(0))
        with recorded_step_problems() as inner:
            p.pass_on_right = ahead
            plan_step(p, PlannerParams(), np.random.default_rng(0))
            p.pass_on_right = np.zeros((0, 2))
    plan_step(p, PlannerParams(), np.random.default_rng(0))
    assert len(outer) == 2 and len(inner) == 1
    assert outer[0].pass_on_right.shape == (0, 2)
    assert np.array_equal(inner[0].pass_on_right, ahead)
    assert np.array_equal(outer[1].pass_on_right, ahead)       # as posed, not as left afterwards


def test_default_step_plan_is_the_loop_reference_move_for_move():
    """The paper's FAStep (attraction_sample 0) on a real step problem: the vectorised swarm and the plain-loop
    reference make the same moves, so they return the same waypoint, bit for bit."""
    from fastep_testing.fastep_loop import fastep_loop
    params = PlannerParams()
    p = problem(others=np.array([[8.5, 6.0]]), robot_clearance=np.array([1.2]))
    kw = dict(n_fireflies=params.n_fireflies, max_iter=params.max_iter, patience=params.patience,
              gamma=params.gamma, beta0=params.beta0, alpha=params.alpha, alpha_damping=params.alpha_damping,
              tol=params.tol)
    for seed in range(2):
        step = plan_step(p, params, np.random.default_rng(seed))
        reference = fastep_loop(p.fitness, p.bounds(), rng=np.random.default_rng(seed), **kw)
        assert step is not None and np.array_equal(step.waypoint, reference.x) and step.cost == reference.fun


@pytest.mark.parametrize('seed', range(5))
def test_attraction_sample_plans_a_feasible_step_close_to_the_papers(seed):
    p = problem()
    paper = plan_step(p, PlannerParams(), np.random.default_rng(seed))
    sampled = plan_step(p, PlannerParams(attraction_sample=5), np.random.default_rng(seed))
    again = plan_step(p, PlannerParams(attraction_sample=5), np.random.default_rng(seed))
    assert paper is not None and sampled is not None and again is not None
    assert np.array_equal(sampled.waypoint, again.waypoint)
    w = sampled.waypoint
    assert np.hypot(*(w - p.origin)) <= 2.0 + 1e-9 and WORLD.obstacles.clearance(w) >= 0.7 - 1e-9
    assert WORLD.obstacles.path_clearance(p.origin, w) >= 0.7 - 1e-9
    assert sampled.cost <= paper.cost + 2e-3                  # 2e-3 of fitness: 20 cm nearer the goal at c = 0.01
    assert sampled.result.nfev < paper.result.nfev / 2


def test_merged_moves_plan_the_loop_references_step_with_one_call_per_iteration():
    """merged_moves (a departure from the paper, off by default) on a real step problem: the planner's swarm is the
    plain-loop reference's with merged_moves, bit for bit, and calls the fitness once per iteration."""
    from fastep_testing.fastep_loop import fastep_loop
    params = PlannerParams(merged_moves=1)
    p = problem(others=np.array([[8.5, 6.0]]), robot_clearance=np.array([1.2]))
    kw = dict(n_fireflies=params.n_fireflies, max_iter=params.max_iter, patience=params.patience,
              gamma=params.gamma, beta0=params.beta0, alpha=params.alpha, alpha_damping=params.alpha_damping,
              tol=params.tol)
    fitness = p.fitness
    for seed in range(2):
        calls: list[int] = []

        def counted(X, calls=calls):
            calls.append(len(X))
            return fitness(X)
        p.fitness = counted     # type: ignore[method-assign]  # count the swarm's calls
        try:
            step = plan_step(p, params, np.random.default_rng(seed))
        finally:
            del p.fitness
        reference = fastep_loop(p.fitness, p.bounds(), rng=np.random.default_rng(seed), merged_moves=True, **kw)
        assert step is not None and np.array_equal(step.waypoint, reference.x) and step.cost == reference.fun
        assert len(calls) == 1 + step.result.nit and calls[1:] == [1226 + 50] * step.result.nit
        w = step.waypoint
        assert np.hypot(*(w - p.origin)) <= 2.0 + 1e-9 and WORLD.obstacles.path_clearance(p.origin, w) >= 0.7 - 1e-9


def robots_kept_right_per_call(p: StepProblem) -> list[int]:
    """Count p's fitness calls: the list gets, per call, how many robots the plan was keeping right of."""
    calls: list[int] = []
    fitness = p.fitness

    def counted(X: np.ndarray) -> np.ndarray:
        calls.append(len(p.pass_on_right))
        return fitness(X)

    p.fitness = counted   # type: ignore[method-assign]  # counts the calls each plan makes
    return calls


@pytest.mark.parametrize('plain_after', [True, False])
def test_keeping_right_is_given_up_within_rule_calls_where_it_leaves_no_feasible_step(plain_after):
    """Robots ahead on both sides leave no step right of both: the rule's swarm stops after RULE_CALLS calls
    (it used to shrink the violation until max_iter); the step is then planned without the rule, or, with
    plain_after False, left to the caller (the navigator plans it on the next tick)."""
    from fastep_core.planning.swarm.step import RULE_CALLS, plan_step_passing_right
    p = problem(origin=(30.0, 30.0), target=(45.0, 30.0))
    calls = robots_kept_right_per_call(p)
    ahead = np.array([[3.0, 0.0], [-3.0, 0.0]])   # right of +x is -y, right of -x is +y
    step = plan_step_passing_right(p, PlannerParams(), np.random.default_rng(0), 'fastep', ahead,
                                   plain_after=plain_after)
    assert calls[:RULE_CALLS] == [2] * RULE_CALLS and 2 not in calls[RULE_CALLS:]
    if plain_after:
        assert step is not None and len(calls) > RULE_CALLS
    else:
        assert step is None and len(calls) == RULE_CALLS
    assert p.pass_on_right.shape == (0, 2)


def test_with_merged_moves_keeping_right_is_given_up_after_the_same_four_iterations():
    from fastep_core.planning.swarm.step import plan_step_passing_right, rule_calls
    params = PlannerParams(merged_moves=1)
    assert rule_calls(params) == 5 and rule_calls(PlannerParams()) == 9 and rule_calls(params, 'aco') == 9
    p = problem(origin=(30.0, 30.0), target=(45.0, 30.0))
    calls = robots_kept_right_per_call(p)
    step = plan_step_passing_right(p, params, np.random.default_rng(0), 'fastep', np.array([[3.0, 0.0], [-3.0, 0.0]]),
                                   plain_after=False)
    assert step is None and calls == [2] * 5    # the initial swarm and four iterations, one call each


def test_a_budget_that_is_not_reached_changes_no_plan():
    p = oncoming_robot_problem()
    for seed in range(5):
        free = plan_step(p, PlannerParams(), np.random.default_rng(seed))
        bounded = plan_step(p, PlannerParams(), np.random.default_rng(seed), feasible_within=5)
        assert free is not None and bounded is not None
        assert np.array_equal(free.waypoint, bounded.waypoint) and free.cost == bounded.cost


@pytest.mark.parametrize('iterations', [1, 2, 5])
def test_a_step_plan_spread_over_ticks_is_the_whole_plan(iterations):
    """StepRun.advance(k) runs at most k swarm iterations per call (a planner's budget per control tick, PlannerParams
    .step_iterations); however it is spread, the plan is plan_step's, bit for bit."""
    from fastep_core.planning.swarm.step import StepRun
    p = problem(others=np.array([[8.5, 6.0]]), robot_clearance=np.array([1.2]))
    for seed in range(3):
        whole = plan_step(p, PlannerParams(), np.random.default_rng(seed))
        run = StepRun(p, PlannerParams(), np.random.default_rng(seed))
        calls = 1
        while not run.advance(iterations):
            calls += 1
            assert run.plan is None and not run.done
        assert whole is not None and run.plan is not None and run.done
        assert np.array_equal(run.plan.waypoint, whole.waypoint) and run.plan.cost == whole.cost
        assert calls == -(-whole.result.nit // iterations)   # the initial swarm comes with the first
        assert run.advance(iterations) and run.plan.cost == whole.cost   # a finished run stays finished


def test_a_spread_plan_that_finds_nothing_feasible_in_time_gives_up():
    """feasible_within counts objective calls across advances: the run ends there, done, with no plan."""
    from fastep_core.planning.swarm.step import StepRun
    p = problem(origin=(30.0, 30.0), target=(45.0, 30.0))
    p.pass_on_right = np.array([[3.0, 0.0], [-3.0, 0.0]])   # right of both: nowhere
    run = StepRun(p, PlannerParams(), np.random.default_rng(0), feasible_within=5)
    advances = 1
    while not run.advance(1):
        advances += 1
    assert run.gave_up and run.plan is None and advances > 1


def test_a_spread_plan_whose_objective_raises_raises_again_rather_than_looking_unfinished():
    from fastep_core.planning.swarm.step import StepRun
    run = StepRun(problem(), PlannerParams(), np.random.default_rng(0))
    fitness, calls = run.fitness, []

    def breaks_on_the_third(X: np.ndarray) -> np.ndarray:
        calls.append(len(X))
        if len(calls) == 3:
            raise ValueError('boom')
        return fitness(X)

    run.fitness = breaks_on_the_third
    with pytest.raises(ValueError, match='boom'):
        while not run.advance(1):
            pass
    for iterations in (1, None):
        with pytest.raises(ValueError, match='boom'):
            run.advance(iterations)
    assert not run.done and run.plan is None and len(calls) == 3
