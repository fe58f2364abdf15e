"""Experiments: seeded batches of simulated runs, the random worlds they run on, and their statistics.

What lives where:

- `batches`: (scenario, planner, seed) tasks over a process pool or a cluster, one `Record` per run, Table 2's
  statistics and report (`fastep-bench`).
- `families`: the families benchmark, every planner on unseen random worlds against the exact optimum
  (`fastep-bench --families`).
- `random_worlds`: random solvable worlds (circle fields, circles and walls, U-traps, 1-4 robots of any model)
  and the family sources (`u_trap:1000006`) that `cached_scenario` loads like a built-in name;
  `dynamic_worlds` (movers, unknown and misplaced obstacles) and `dense_clutter` (BARN-shaped courses) add
  their families to it.
- `tuning`: `fastep-tune`, the step fitness weights and step radius chosen by differential evolution.
- `cluster`: batches and tuning on a Dask cluster (`--cluster`); the only module that imports Dask.

The names below are loaded on first use, so `python -m fastep_core.experiments.random_worlds` (or `.tuning`)
runs its module once, and a script that draws one world does not import the simulator.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from fastep_core.experiments.batches import TABLE2, Record, Task, cached_scenario, example_paths, run_batch, tasks
    from fastep_core.experiments.cluster import BatchIncomplete, ClusterError, ClusterSpec, cluster_spec, open_cluster
    from fastep_core.experiments.families import FAMILY_NAMES, rows_of, run_families
    from fastep_core.experiments.random_worlds import (
        ALL_FAMILIES,
        FAMILIES,
        FAMILY_SEED0,
        family_source,
        random_family_data,
        random_scenario,
        u_trap,
    )
    from fastep_core.experiments.tuning import tune

_HOMES = {
    'batches': ('TABLE2', 'Record', 'Task', 'cached_scenario', 'example_paths', 'run_batch', 'tasks'),
    'cluster': ('BatchIncomplete', 'ClusterError', 'ClusterSpec', 'cluster_spec', 'open_cluster'),
    'families': ('FAMILY_NAMES', 'rows_of', 'run_families'),
    'random_worlds': ('ALL_FAMILIES', 'FAMILIES', 'FAMILY_SEED0', 'family_source', 'random_family_data',
                      'random_scenario', 'u_trap'),
    'tuning': ('tune',),
}
_MODULE_OF = {name: module for module, names in _HOMES.items() for name in names}

__all__ = [
    'ALL_FAMILIES', 'BatchIncomplete', 'ClusterError', 'ClusterSpec', 'FAMILIES', 'FAMILY_NAMES', 'FAMILY_SEED0',
    'Record', 'TABLE2', 'Task', 'cached_scenario', 'cluster_spec', 'example_paths', 'family_source',
    'open_cluster', 'random_family_data', 'random_scenario', 'rows_of', 'run_batch', 'run_families', 'tasks',
    'tune', 'u_trap',
]


def __getattr__(name: str) -> Any:
    if name not in _MODULE_OF:
        raise AttributeError(f'module {__name__!r} has no attribute {name!r}')
    return getattr(importlib.import_module(f'{__name__}.{_MODULE_OF[name]}'), name)


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
