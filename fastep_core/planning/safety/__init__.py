"""Between a planned command and the robot: the checks and limits that keep it off obstacles and other robots.

- `guard`: the last check of a command against the map, the scan and other robots (`Guard`).
- `guard_inputs`: what perception tells the guards of one scan.
- `yielding`: the speed checked against where movers will be.
- `passage`: one-lane passages on a route, and who waits before one.
- `base_response`: the braking and acceleration the base has shown, measured from odometry.
- `lateness`: how late the control loop acts, and the speed that stays safe at that lateness.
- `smoother`: the velocity smoother, the last stage before cmd_vel.

The names below are loaded on first use: importing one module of this package does not import the others.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from fastep_core.planning.safety.base_response import BaseResponse, ShownResponse
    from fastep_core.planning.safety.guard import Guard, Stop
    from fastep_core.planning.safety.guard_inputs import GuardInputs
    from fastep_core.planning.safety.lateness import Lateness, stopping_speed
    from fastep_core.planning.safety.passage import Passage, passages
    from fastep_core.planning.safety.smoother import VelocitySmoother
    from fastep_core.planning.safety.yielding import Yield, Yielding

_HOMES = {
    'base_response': ('BaseResponse', 'ShownResponse'),
    'guard': ('Guard', 'Stop'),
    'guard_inputs': ('GuardInputs',),
    'lateness': ('Lateness', 'stopping_speed'),
    'passage': ('Passage', 'passages'),
    'smoother': ('VelocitySmoother',),
    'yielding': ('Yield', 'Yielding'),
}
_MODULE_OF = {name: module for module, names in _HOMES.items() for name in names}

__all__ = [
    'BaseResponse', 'Guard', 'GuardInputs', 'Lateness', 'Passage', 'ShownResponse', 'Stop', 'VelocitySmoother',
    'Yield', 'Yielding', 'passages', 'stopping_speed',
]


def __getattr__(name: str) -> Any:
    if name not in _MODULE_OF:
        raise AttributeError(f'module {__name__!r} has no attribute {name!r}')
    return getattr(importlib.import_module(f'{__name__}.{_MODULE_OF[name]}'), name)


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
