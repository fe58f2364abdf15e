"""Process layouts of fastep-launch: which of the graph's nodes share a process (and its executor).

    node   one process per node (map, each plant, each planner, clock, recorder), as on separate computers
    robot  one process per robot (its plant and planner, fastep_ros.container), and the map, clock and recorder
           each in its own
    graph  every node of the simulated graph (map, plants, planners, clock) in one process, on one executor; the
           recorder, an observer writing a file with an exit code of its own (1: the file is incomplete), keeps its
           own process, so its writes never hold up the lock step

The nodes, their names, namespaces, parameters and topics are the same in every layout: a container builds each
node from the very arguments its own process would get (fastep_ros.container). What changes is what it costs:
each rclpy process pays its executor's work per wake-up and its own DDS participant (discovery traffic grows
with the square of the participants), so fewer processes cost less CPU, while one process uses one core at most.
docs/benchmarks.md ("Executors and process layouts") measures the three: on the default SingleThreadedExecutor
`robot` scaled best (one process for the whole graph rebuilds a wait set of every node's entities at each
wake-up: its latency grows with the robots); `graph` on the EventsExecutor costs least.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from typing import Any, Sequence

__all__ = ['DEFAULT_LAYOUT', 'LAYOUTS', 'Member', 'command', 'group']

LAYOUTS = ('node', 'robot', 'graph')
DEFAULT_LAYOUT = 'robot'


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
        simulated = [m for m in members if m.module != 'recorder']
        return ([('fastep-graph', simulated)] if simulated else []) + \
            [(m.label, [m]) for m in members if m.module == 'recorder']
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
