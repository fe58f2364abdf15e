"""The navigators: each algorithm a subclass of the loop they share (planning/navigator.py).

- `fastep_kinematic`: FAStep-Kinematic, the paper's Algorithm 1 (`FAStepPaper`, as published; `FAStepKinematic`,
  with the guard, recovery and the exact path around it).
- `fastep_route`: FAStep-Route, FAStep-Kinematic guided by the exact shortest route over what the robot knows.
- `aco_kinematic`: ACO-Kinematic, the paper's baseline.
- `optimal_kinematic`: Optimal-Kinematic, the exact shortest path planned once and driven.
- `dwa`: the Dynamic Window Approach, the classical local planner for comparison.

planning/algorithms.py names them for the command line and the nodes (`make_navigator`).

The names below are loaded on first use: importing one module of this package does not import the others.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from fastep_core.planning.navigators.aco_kinematic import ACOKinematic
    from fastep_core.planning.navigators.dwa import DynamicWindow
    from fastep_core.planning.navigators.fastep_kinematic import FAStepKinematic, FAStepPaper
    from fastep_core.planning.navigators.fastep_route import FAStepRoute
    from fastep_core.planning.navigators.optimal_kinematic import OptimalKinematic

_HOMES = {
    'aco_kinematic': ('ACOKinematic',),
    'dwa': ('DynamicWindow',),
    'fastep_kinematic': ('FAStepKinematic', 'FAStepPaper'),
    'fastep_route': ('FAStepRoute',),
    'optimal_kinematic': ('OptimalKinematic',),
}
_MODULE_OF = {name: module for module, names in _HOMES.items() for name in names}

__all__ = [
    'ACOKinematic', 'DynamicWindow', 'FAStepKinematic', 'FAStepPaper', 'FAStepRoute', 'OptimalKinematic',
]


def __getattr__(name: str) -> Any:
    if name not in _MODULE_OF:
        raise AttributeError(f'module {__name__!r} has no attribute {name!r}')
    return getattr(importlib.import_module(f'{__name__}.{_MODULE_OF[name]}'), name)


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
