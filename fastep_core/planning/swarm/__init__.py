"""The swarm's step: when a navigator plans one, and how the Stepping Ahead Firefly swarm chooses it.

- `detection`: activation, eq. 11 and "on the way": does something within sensing range block the straight run?
- `step_planning`: when the swarm may plan a step, and what a step plan carries from one tick to the next.
- `step`: one step, the eq. 10 fitness with a hard clearance rule, minimised by the swarm (`plan_step`).
- `step_arrays`: the fitness's array kernels.

The names below are loaded on first use: importing one module of this package does not import the others.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from fastep_core.planning.swarm.detection import RunDetector
    from fastep_core.planning.swarm.step import StepPlan, StepProblem, plan_step
    from fastep_core.planning.swarm.step_planning import StepPlanner, StepPlanning

_HOMES = {
    'detection': ('RunDetector',),
    'step': ('StepPlan', 'StepProblem', 'plan_step'),
    'step_planning': ('StepPlanner', 'StepPlanning'),
}
_MODULE_OF = {name: module for module, names in _HOMES.items() for name in names}

__all__ = [
    'RunDetector', 'StepPlan', 'StepPlanner', 'StepPlanning', 'StepProblem', 'plan_step',
]


def __getattr__(name: str) -> Any:
    if name not in _MODULE_OF:
        raise AttributeError(f'module {__name__!r} has no attribute {name!r}')
    return getattr(importlib.import_module(f'{__name__}.{_MODULE_OF[name]}'), name)


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
