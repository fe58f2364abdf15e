"""The exact shortest path that keeps a robot's clearance from every obstacle: the reference optimum and the way
the navigators plan routes and escapes.

- `optimal`: `shortest_path` (the exact optimum, `OptimalPath`); `python -m fastep_core.planning.shortest_path`.
- `tangent_search`: its search, A* over the tangent visibility graph made lazily.
- `obstacle_grid`: the spatial index the search asks which obstacles lie near an edge.
- `exact_path`: the path as a navigator asks for it (the robot's clearance, other robots parked, why none exists).
- `route`: a route a robot follows and the speed it may drive along it (FAStep-Route).

The names below are loaded on first use: importing one module of this package does not import the others.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from fastep_core.planning.shortest_path.exact_path import no_path_reason, robot_path, solvable
    from fastep_core.planning.shortest_path.obstacle_grid import ObstacleGrid
    from fastep_core.planning.shortest_path.optimal import OptimalPath, shortest_path
    from fastep_core.planning.shortest_path.route import Route, RouteSpeed
    from fastep_core.planning.shortest_path.tangent_search import search

_HOMES = {
    'exact_path': ('no_path_reason', 'robot_path', 'solvable'),
    'obstacle_grid': ('ObstacleGrid',),
    'optimal': ('OptimalPath', 'shortest_path'),
    'route': ('Route', 'RouteSpeed'),
    'tangent_search': ('search',),
}
_MODULE_OF = {name: module for module, names in _HOMES.items() for name in names}

__all__ = [
    'ObstacleGrid', 'OptimalPath', 'Route', 'RouteSpeed', 'no_path_reason', 'robot_path', 'search',
    'shortest_path', 'solvable',
]


def __getattr__(name: str) -> Any:
    if name not in _MODULE_OF:
        raise AttributeError(f'module {__name__!r} has no attribute {name!r}')
    return getattr(importlib.import_module(f'{__name__}.{_MODULE_OF[name]}'), name)


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
