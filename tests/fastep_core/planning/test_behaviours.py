"""The tick's behaviours as objects: their order, their own state, and what they may touch of the navigator."""

import ast
from pathlib import Path

import numpy as np

import fastep_core.planning.behaviours as behaviours_package
from fastep_core.geometry import Circle
from fastep_core.kinematics import PointMass
from fastep_core.planning import Mode, PlannerParams, make_navigator
from fastep_core.planning.behaviours import (
    Algorithm,
    Arrival,
    BackingUp,
    BackToGoal,
    Escaping,
    HoldBreaker,
    Manoeuvring,
    PathCheck,
    ProgressCheck,
    Tick,
    TrapCheck,
)
from fastep_core.planning.recovery.progress import ProgressChecker, TrapDetector
from fastep_core.planning.safety.base_response import BaseResponse
from fastep_core.scenario import RobotSpec
from fastep_core.world import World

WORLD = World.from_obstacles([0, 0, 20, 20], [Circle((10.0, 10.0), 1.0)])


def navigator(model='point_mass'):
    spec = RobotSpec('r1', model, (2.0, 2.0), (18.0, 18.0), 0.5)
    return make_navigator('fastep', spec, 0.5, WORLD, PlannerParams(), 0)


def test_the_order_a_tick_asks_them():
    order = [type(b) for b in navigator().behaviours.in_order]
    assert order == [Arrival, BackToGoal, PathCheck, ProgressCheck, TrapCheck, BackingUp, HoldBreaker, Escaping]
    trailer = [type(b) for b in navigator('tractor_trailer').behaviours.in_order]
    assert trailer[5] is Manoeuvring and trailer[6] is BackingUp   # a manoeuvre under way before backing up
    assert isinstance(navigator().behaviours.algorithm, Algorithm)


class Standing:
    """The least a behaviour needs of a navigator to run: no Navigator at all."""

    def __init__(self) -> None:
        self.params = PlannerParams()
        self.model = PointMass()
        self.mode, self.reason, self.waypoint, self.cost = Mode.KINEMATIC, '', None, 1.0
        self.progress = ProgressChecker(0.5, 10.0)
        self.trap = TrapDetector(0.5, 10.0)
        self.cleared = 0

    def clear_target(self) -> None:
        self.cleared += 1


def tick(distance, velocity):
    state = np.array([5.0, 5.0])
    return Tick(1, 0.0, 0.05, state, state, (), distance, np.asarray(velocity, float), np.array([5.0, 5.0]), None,
                WORLD, BaseResponse(True, 2.5, 3.2), None)


def test_arrival_reads_the_tick_alone_and_keeps_its_own_state():
    arrival, nav = Arrival(), Standing()
    assert arrival(nav, tick(1.0, [0.0, 0.0])) is None and not arrival.reached   # not within goal_tolerance
    assert np.all(arrival(nav, tick(0.1, [0.3, 0.0])) == 0.0)     # there, still moving: brakes, not arrived
    assert nav.mode is Mode.KINEMATIC and arrival.reached and nav.cleared == 1 and nav.waypoint is None
    arrival(nav, tick(0.1, [0.0, 0.0]))                           # stopped, as measured
    assert nav.mode is Mode.ARRIVED and nav.reason == 'goal reached'
    arrival.new_goal()
    assert not arrival.reached


def test_a_new_goal_resets_each_behaviours_state():
    nav = navigator()
    nav.set_goal((18.0, 18.0))
    state = np.array([2.0, 2.0])
    for i in range(3):
        state = state + nav.update(0.05 * i, state) * 0.05
    held = nav.behaviours
    assert held.path_check.checked
    held.arrival.reached, held.hold_breaker.broken = True, 7
    nav.set_goal((18.0, 2.0), t=1.0)
    assert not held.path_check.checked and not held.arrival.reached and held.hold_breaker.broken == -1


def test_no_behaviour_touches_a_private_attribute_of_its_navigator():
    folder = Path(behaviours_package.__file__).parent
    private = []
    for path in folder.glob('*.py'):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id == 'nav' \
                    and node.attr.startswith('_'):
                private.append(f'{path.name}: nav.{node.attr}')
    assert private == []
