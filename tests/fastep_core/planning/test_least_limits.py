"""Limits never lift by arithmetic (planning/limits.py): a positive limit is a positive cap however small, never 0
(unlimited), and no limit the planner takes makes a command, a guard's look-ahead or DWA's objective infinite or NaN.

The robots here drive as their commands say, near a wall and another robot, with every limit of one name brought
to a tiny value at runtime (as the planner node's parameters and speed limits do): a value below the least limit
is refused in one line (ParameterError) and the robot drives on as it was; the rest drive within their caps.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from fastep_core.errors import ParameterError
from fastep_core.geometry import Segment
from fastep_core.planning import PlannerParams
from fastep_core.planning.algorithms import make_navigator, make_robot
from fastep_core.planning.control import ControlTick, Plan
from fastep_core.planning.limits import Limits
from fastep_core.planning.others import OtherRobot
from fastep_core.scenario import RobotSpec
from fastep_core.world import World

DT = PlannerParams().dt
WORLD = World.from_obstacles((0.0, 0.0, 40.0, 20.0), [Segment((8.0, 6.0), (8.0, 14.0))])
SPECS = {'diff_drive': RobotSpec('d1', 'diff_drive', (2.0, 10.0, 0.0), (30.0, 10.0), 0.35),
         'point_mass': RobotSpec('p1', 'point_mass', (2.0, 10.0), (30.0, 10.0), 0.35)}
OTHER = OtherRobot('r2', (6.0, 12.5), (-0.2, 0.0), 0.35)   # near, moving: the guard's and DWA's robot terms
LIMIT_NAMES = ('max_speed', 'max_reverse_speed', 'max_turn_rate', 'max_acceleration', 'max_turn_acceleration',
               'emergency_deceleration')
TINY = (5e-324, 1e-300, 1e-12, 1e-6)   # the smallest double, then ever less small


def tiny_change(name: str, value: float) -> dict[str, float]:
    """`name` at `value`; emergency_deceleration and max_acceleration together (the stop brakes at least as hard)."""
    if name in ('max_acceleration', 'emergency_deceleration'):
        return {'max_acceleration': value, 'emergency_deceleration': value}
    return {name: value}


def drive(algorithm: str, model: str, change: dict[str, float]) -> tuple[list[np.ndarray], Limits, str]:
    """A robot's commands over 2 s at its default limits, then 3 s after `change` (refused: why, driving on)."""
    spec = SPECS[model]
    nav = make_navigator(algorithm, spec, spec.radius, WORLD, PlannerParams(), 0)
    nav.set_goal(spec.goal)
    tick = ControlTick(nav)
    state, sent, t = np.array(spec.start, dtype=float), np.zeros(2), 0.0
    commands, refused = [], ''
    for k in range(100):
        if k == 40:
            try:
                params = nav.params.with_overrides(change)
            except ParameterError as exc:
                refused = str(exc)
            else:
                nav.retune(params, make_robot(spec, params)[1])
                tick.retune()
        plan = Plan.of(nav, t, nav.update(t, state, [OTHER], velocity=sent))
        sent = tick.command(t, state, [OTHER], plan, DT, velocity=sent)
        commands.append(np.array(sent))
        if nav.model.holonomic:
            state = state + DT * sent
        else:
            state = state + DT * np.array([sent[0] * math.cos(state[2]), sent[0] * math.sin(state[2]), sent[1]])
        t += DT
    return commands, nav.limits, refused


@pytest.mark.parametrize('algorithm, model', [('fastep', 'point_mass'), ('fastep', 'diff_drive'),
                                              ('dwa', 'point_mass'), ('dwa', 'diff_drive'),
                                              ('fastep_route', 'diff_drive')])
@pytest.mark.parametrize('name', LIMIT_NAMES)
def test_a_tiny_limit_is_refused_below_the_least_and_driven_within_at_it(algorithm: str, model: str,
                                                                          name: str) -> None:
    for value in TINY:
        change = tiny_change(name, value)
        with warnings.catch_warnings():
            warnings.simplefilter('error')   # numpy's overflow, invalid value or division by zero: a failure
            commands, limits, refused = drive(algorithm, model, change)
        assert np.isfinite(commands).all(), (name, value)
        if value < 1e-6:
            assert refused and '\n' not in refused and 'least' in refused and \
                any(f'planner parameter {changed}=' in refused for changed in change), (name, value, refused)
            assert getattr(limits, name) == getattr(Limits.of(PlannerParams()), name)   # unchanged
            continue
        assert not refused and getattr(limits, name) == value
        late = np.array(commands[80:])   # 2 s after the change: braked to within it
        if name == 'max_speed':
            speed = np.hypot(*late.T) if model == 'point_mass' else np.abs(late[:, 0])
            assert speed.max() <= value * (1 + 1e-9), (name, value)
        elif name == 'max_turn_rate' and model == 'diff_drive':
            assert np.abs(late[:, 1]).max() <= value * (1 + 1e-9), (name, value)


def test_zero_still_means_unlimited_and_the_least_limit_is_taken() -> None:
    params = PlannerParams().with_overrides({name: 0.0 for name in LIMIT_NAMES})
    assert all(getattr(params.limits, name) == 0.0 for name in LIMIT_NAMES)
    with pytest.raises(ParameterError, match='least'):
        PlannerParams(max_speed=1e-7)
    assert PlannerParams(max_speed=1e-6).max_speed == 1e-6
