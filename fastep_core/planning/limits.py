"""A robot's limits as one value: the speeds, the accelerations and the control period every part of a navigator reads.

The kinematic model saturates at the speed limits, the controller caps its commands at them, the velocity smoother
caps and ramps every command within them, the guard and the node's latency compensation predict with the model,
FAStep-Route's speed law regulates within them, yielding and backing up move at them, the base's response is judged
against the accelerations and DWA searches its window within them. One value, made from the planner parameters
(`Limits.of`, `PlannerParams.limits`) and handed whole to every reader in one call (`Navigator.retune`), so that a
change made at runtime reaches all of them at once: a model left with an old speed limit makes the guard predict a
faster command short, and the robot goes farther than the guard looked.

A model is handed new limits by `saturating` (where they are lower it keeps saturating where it did: a limit lowered
below the robot's speed is reached braking at max_acceleration, and the base does the commands of that ramp);
controllers by `with_limits`.

A positive limit is never below LEAST_LIMIT (PlannerParams refuses one, `speed_limited` holds a speed limit's cap
at it), so that no limit is 0 (unlimited) by arithmetic and none makes a look-ahead, a ramp or an objective
infinite.
"""

from __future__ import annotations

from dataclasses import dataclass, fields, is_dataclass, replace
from typing import Any, Protocol, TypeVar

__all__ = ['LEAST_LIMIT', 'LIMIT_NAMES', 'LimitSource', 'Limits', 'limit_problem', 'saturating', 'speed_limited',
           'with_limits']

T = TypeVar('T')

LEAST_LIMIT = 1e-6
"""The least positive value of a limit (Limits' max_speed, max_reverse_speed, max_turn_rate, max_acceleration,
max_turn_acceleration, emergency_deceleration), in its own unit: 1 um/s, 1e-6 rad/s, 1e-6 m/s^2 (0 still means
unlimited). A robot held to it stands still for any purpose (3.6 mm an hour), and every quotient the readers take
stays finite: the guard's braking look-ahead v / 2a (5e5 s a m/s), DWA's speed / max_speed and progress over
max_speed x horizon, the route's sqrt(2 a d). Below it: a parameter is refused (PlannerParams), a speed limit's cap
is held at it (`speed_limited`). At 5e-324 the look-ahead was infinite (NaN positions), DWA's objective overflowed
and the diff_drive guard raised a math domain error; a SpeedLimit of 5e-324 % made max_speed 0, unlimited."""


class LimitSource(Protocol):
    """What Limits.of reads: PlannerParams (planning/params.py, which imports this module, so not named here)."""

    @property
    def max_speed(self) -> float: ...

    @property
    def max_reverse_speed(self) -> float: ...

    @property
    def max_turn_rate(self) -> float: ...

    @property
    def max_acceleration(self) -> float: ...

    @property
    def max_turn_acceleration(self) -> float: ...

    @property
    def emergency_deceleration(self) -> float: ...

    @property
    def dt(self) -> float: ...


@dataclass(frozen=True)
class Limits:
    """The speed and acceleration limits of one robot and its control period (PlannerParams' fields of the same
    names; 0 for a limit means unlimited). The default: no limits, at PlannerParams' default period."""

    max_speed: float = 0.0                # m/s: |v| (a point mass: its speed)
    max_reverse_speed: float = 0.0        # m/s: a steered robot's -v
    max_turn_rate: float = 0.0            # rad/s: |omega| of a diff_drive
    max_acceleration: float = 0.0         # m/s^2: |dv/dt| of every command but the guard's stop
    max_turn_acceleration: float = 0.0    # rad/s^2: |domega/dt|
    emergency_deceleration: float = 0.0   # m/s^2: the guard's stop (0: immediate)
    dt: float = 0.05                      # s: the control period

    @classmethod
    def of(cls, params: LimitSource) -> Limits:
        """The limits of these planner parameters (PlannerParams)."""
        return cls(params.max_speed, params.max_reverse_speed, params.max_turn_rate, params.max_acceleration,
                   params.max_turn_acceleration, params.emergency_deceleration, params.dt)


_SPEEDS = ('max_speed', 'max_turn_rate')   # what a model saturates at (kinematics/diff_drive.py)
LIMIT_NAMES: tuple[str, ...] = tuple(f.name for f in fields(Limits) if f.name != 'dt')
"""The limits (every field of Limits but dt): what a controller may cap or ramp at, each 0 or >= LEAST_LIMIT."""


def limit_problem(name: str, value: float) -> str:
    """Why `value` cannot be the limit `name` ('' when it can): a positive limit below LEAST_LIMIT."""
    if 0.0 < value < LEAST_LIMIT:
        return (f'planner parameter {name}={value:g} is below the least limit {LEAST_LIMIT:g}: 0 means unlimited, '
                f'and a robot at the least already stands still')
    return ''


def speed_limited(max_speed: float, limit: float, percentage: bool) -> float:
    """max_speed (0: unlimited) capped by a speed limit (nav2_msgs/SpeedLimit: `limit` percent of max_speed, or m/s;
    0: none). A positive limit is a positive cap, at least LEAST_LIMIT: 5e-324 % of 1 m/s is 0 in floating point,
    and 0 means unlimited. A percentage of an unlimited max_speed caps nothing (the caller says so)."""
    if limit <= 0.0:
        return max_speed
    if percentage:
        if max_speed <= 0.0:
            return max_speed
        return min(max_speed, max(max_speed * (limit / 100.0), LEAST_LIMIT))
    return max(limit, LEAST_LIMIT) if max_speed <= 0.0 else min(max_speed, max(limit, LEAST_LIMIT))


def _own(item: object, names: tuple[str, ...]) -> list[str]:
    """The names among `names` that are fields of the dataclass `item` (none for anything else)."""
    if not is_dataclass(item) or isinstance(item, type):
        return []
    own = {f.name for f in fields(item)}
    return [name for name in names if name in own]


def with_limits(item: T, limits: Limits) -> T:
    """A copy of the controller (any dataclass) with each limit it has (max_speed, max_acceleration, ...) taken from
    `limits`, the rest of it (gains, the last command) as it was; `item` itself when it has none."""
    names = _own(item, LIMIT_NAMES)
    if not names:
        return item
    changes: dict[str, Any] = {name: getattr(limits, name) for name in names}
    return replace(item, **changes)  # type: ignore[type-var]  # T is bound to the dataclasses it is called with


def _higher(kept: float, new: float) -> float:
    return 0.0 if kept <= 0.0 or new <= 0.0 else max(kept, new)


def saturating(model: T, limits: Limits) -> T:
    """The kinematic model after a runtime change to `limits`: it saturates at the new speed limits where they are
    higher than its own, at its own where they are lower (0, unlimited, is the highest); `model` itself when it does
    not saturate (a point mass, a tractor-trailer).

    Why not lower: a limit lowered below the robot's speed is reached braking at max_acceleration (the smoother, the
    diff_drive controller), and the base does the commands of that ramp. A model saturated at the new limit would
    predict them short, as a stale limit predicted a raised one: the guard would under-predict how far the robot
    goes. Commands within the new limits are predicted the same by either model."""
    names = _own(model, _SPEEDS)
    if not names:
        return model
    changes: dict[str, Any] = {name: _higher(getattr(model, name), getattr(limits, name)) for name in names}
    if all(changes[name] == getattr(model, name) for name in names):
        return model
    return replace(model, **changes)  # type: ignore[type-var]  # a model that saturates is a dataclass
