"""What a navigator does when driving straight on does not bring it closer: trap detection, the escape along the
exact path, backing up, and a tractor-trailer's manoeuvres.

- `progress`: the progress checker (a run fails without progress) and the trap detector.
- `escape`: the way out of a trap, the exact shortest path followed by a pure-pursuit carrot.
- `back_up`: when the guard keeps the robot stopped: the hold breaker's clock and backing up into space seen free.
- `manoeuvre_search`: a tractor-trailer's manoeuvres, a hybrid-A* search over short arcs;
  `manoeuvre_driver` drives one tick by tick.

A tick asks them through planning/behaviours/ (recoveries.py), in its order.

The names below are loaded on first use: importing one module of this package does not import the others.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from fastep_core.planning.recovery.back_up import BackUp, SeenFree, StopTimer, reverse_free
    from fastep_core.planning.recovery.escape import TrapEscape
    from fastep_core.planning.recovery.manoeuvre_driver import ManoeuvreDriver
    from fastep_core.planning.recovery.manoeuvre_search import Manoeuvre, plan_manoeuvre
    from fastep_core.planning.recovery.progress import ProgressChecker, TrapDetector

_HOMES = {
    'back_up': ('BackUp', 'SeenFree', 'StopTimer', 'reverse_free'),
    'escape': ('TrapEscape',),
    'manoeuvre_driver': ('ManoeuvreDriver',),
    'manoeuvre_search': ('Manoeuvre', 'plan_manoeuvre'),
    'progress': ('ProgressChecker', 'TrapDetector'),
}
_MODULE_OF = {name: module for module, names in _HOMES.items() for name in names}

__all__ = [
    'BackUp', 'Manoeuvre', 'ManoeuvreDriver', 'ProgressChecker', 'SeenFree', 'StopTimer', 'TrapDetector',
    'TrapEscape', 'plan_manoeuvre', 'reverse_free',
]


def __getattr__(name: str) -> Any:
    if name not in _MODULE_OF:
        raise AttributeError(f'module {__name__!r} has no attribute {name!r}')
    return getattr(importlib.import_module(f'{__name__}.{_MODULE_OF[name]}'), name)


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
