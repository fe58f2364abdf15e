"""Process layouts of fastep-launch: which of the graph's nodes share a process (and its executor).

    node   one process per node (map, each plant, each planner, clock, recorder), as on separate computers
    robot  one process per robot (its plant and planner, fastep_ros.container); map, clock and recorder each alone
    graph  the simulated graph (map, plants, planners, clock) in one process on one executor; the observers (the
           recorder, with an exit code of its own, and the Foxglove bridge) in their own
    cores  the simulated graph in one process per usable CPU core, robots dealt in turn, map and clock in the first

Nodes, names, namespaces, parameters and topics are the same in every layout: a container builds each node from the
arguments its own process would get. Only the cost differs: each rclpy process pays its executor's work per wake-up
and a DDS participant (discovery grows with the square of participants), while one process uses one core at most.
In lock step a tick is a chain of messages through every node, cheapest inside one process, so default_layout is
`graph` in lock step up to GRAPH_ROBOTS robots and `cores` otherwise (on wall time several robots planning in one
process delay the others). Measured in docs/benchmarks.md, "Executors and process layouts".
"""

from __future__ import annotations

import os
import sys
from dataclasses import dataclass
from typing import Any, Sequence

__all__ = ['GRAPH_ROBOTS', 'LAYOUTS', 'Member', 'command', 'default_layout', 'group', 'usable_cores']

LAYOUTS = ('node', 'robot', 'graph', 'cores')
# Nodes that watch the graph on wall time and keep a process of their own in every layout: the recorder (its exit
# code says whether its file is complete), the Foxglove bridge (a WebSocket server, whose clients' pace is theirs).
OBSERVERS = ('recorder', 'foxglove_bridge')
GRAPH_ROBOTS = 4   # robots up to which `graph` is the default in lock step (above: `cores`)


def usable_cores() -> int:
    """The CPU cores this process may run on (its affinity where the platform tells it)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:   # not on Linux
        return os.cpu_count() or 1


def default_layout(sim_time: bool, robots: int = 1) -> str:
    """The layout fastep-launch uses unless told: on simulated time (lock step) with `robots` robots, or wall time."""
    return 'graph' if sim_time and robots <= GRAPH_ROBOTS else 'cores'



@dataclass(frozen=True)
class Member:
    """One node of the graph: its label (as fastep-launch names it in messages), module, namespace and parameters."""

    label: str
    module: str
    namespace: str
    params: dict[str, Any]


def group(layout: str, members: Sequence[Member]) -> list[tuple[str, list[Member]]]:
    """The processes of a layout: [(label, the nodes it runs)], in the order the nodes were given (a robot's
    process where its first node was)."""
    if layout not in LAYOUTS:
        raise ValueError(f'unknown layout {layout!r}')
    if layout == 'node':
        return [(m.label, [m]) for m in members]
    if layout == 'graph':
        simulated = [m for m in members if m.module not in OBSERVERS]
        return ([('fastep-graph', simulated)] if simulated else []) + \
            [(m.label, [m]) for m in members if m.module in OBSERVERS]
    if layout == 'cores':
        robots_seen: list[str] = []
        for m in members:
            if m.module in ('plant', 'planner') and m.namespace not in robots_seen:
                robots_seen.append(m.namespace)
        parts = max(1, min(usable_cores(), len(robots_seen)))
        shares: list[list[Member]] = [[] for _ in range(parts)]
        for m in members:
            if m.module not in OBSERVERS:
                robot = robots_seen.index(m.namespace) if m.module in ('plant', 'planner') else 0
                shares[robot % parts].append(m)
        return [(f'fastep-graph {i + 1}/{parts}', share) for i, share in enumerate(shares) if share] + \
            [(m.label, [m]) for m in members if m.module in OBSERVERS]
    out: list[tuple[str, list[Member]]] = []
    robots: dict[str, list[Member]] = {}
    for m in members:
        if m.module in ('plant', 'planner') and m.namespace not in ('', '/'):
            if m.namespace not in robots:
                robots[m.namespace] = []
                out.append((f'fastep-robot {m.namespace}', robots[m.namespace]))
            robots[m.namespace].append(m)
        else:
            out.append((m.label, [m]))
    return out


def node_args(member: Member, ros_value: Any) -> list[str]:
    """A node's own command-line arguments: `--ros-args -r __ns:=NS -p name:=value ...`."""
    out = ['--ros-args', '-r', f'__ns:={member.namespace}']
    for name, value in member.params.items():
        out += ['-p', f'{name}:={ros_value(value)}']
    return out


def command(members: Sequence[Member], log_level: str, ros_value: Any) -> list[str]:
    """The command line of a process that runs `members`: the node's own module for one node, a container for
    several. `ros_value` writes a parameter value as the command line takes it."""
    if len(members) == 1:
        return [sys.executable, '-m', f'fastep_ros.{members[0].module}', *node_args(members[0], ros_value),
                '--log-level', log_level]
    from fastep_ros.container import container_args
    return [sys.executable, '-m', 'fastep_ros.container',
            *container_args([(m.module, node_args(m, ros_value)) for m in members],
                            ['--ros-args', '--log-level', log_level])]
