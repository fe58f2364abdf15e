"""fastep-container: several fastep nodes in one process, on one executor.

    fastep-container [--ros-args --log-level warn] --node plant --ros-args -r __ns:=/r1 -p start:=[5.0, 25.0] \\
                     --node planner --ros-args -r __ns:=/r1 -p robot_radius:=0.5 ...

Each `--node KIND ...` builds one node from the arguments up to the next `--node`, exactly those `python -m
fastep_ros.KIND` takes, given as the node's own cli_args, so a node is the same in a container as alone. KIND is
one of plant, planner, map_server, clock, recorder; arguments before the first `--node` are the process's.
fastep-launch --layout robot runs each robot's plant and planner in one container, --layout graph every node in
one. Like a single node's process: Ctrl-C / SIGTERM stop every node, exit 0; a node that cannot start is one
line on stderr, exit 2; a recorder that could not write its file makes the exit code 1. The executor is
FASTEP_EXECUTOR's (fastep_ros.executors).
"""

from __future__ import annotations

import sys
from typing import Any, Callable, Sequence

from fastep_core.errors import FastepError
from fastep_ros.errors import StartupError

__all__ = ['KINDS', 'NODE_FLAG', 'container_args', 'main', 'split_args']

PROG = 'fastep-container'
NODE_FLAG = '--node'
KINDS = ('plant', 'planner', 'map_server', 'clock', 'recorder')


def _node_class(kind: str) -> Callable[..., Any]:
    """The Node subclass of a KIND (imported only when used: the recorder pulls in mcap, the planner scipy)."""
    if kind == 'plant':
        from fastep_ros.plant import PlantNode
        return PlantNode
    if kind == 'planner':
        from fastep_ros.planner import PlannerNode
        return PlannerNode
    if kind == 'map_server':
        from fastep_ros.map_server import MapNode
        return MapNode
    if kind == 'clock':
        from fastep_ros.clock import ClockNode
        return ClockNode
    from fastep_ros.recorder import RecorderNode
    return RecorderNode


def split_args(argv: Sequence[str]) -> tuple[list[str], list[tuple[str, list[str]]]]:
    """(the process's arguments, [(KIND, the node's arguments)]); a StartupError for a malformed command line."""
    argv = list(argv)
    head: list[str] = []
    while argv and argv[0] != NODE_FLAG:
        head.append(argv.pop(0))
    nodes: list[tuple[str, list[str]]] = []
    while argv:
        argv.pop(0)   # --node
        if not argv or argv[0] == NODE_FLAG:
            raise StartupError(f'{NODE_FLAG} needs a node kind ({", ".join(KINDS)})')
        kind = argv.pop(0)
        if kind not in KINDS:
            raise StartupError(f'{NODE_FLAG} {kind!r}: the node kind must be one of {", ".join(KINDS)}')
        own: list[str] = []
        while argv and argv[0] != NODE_FLAG:
            own.append(argv.pop(0))
        nodes.append((kind, own))
    if not nodes:
        raise StartupError(f'no node to run: give at least one {NODE_FLAG} KIND [--ros-args ...]')
    if head and head[0] != '--ros-args':
        raise StartupError(f'unexpected argument {head[0]!r} before the first {NODE_FLAG} (only --ros-args ...)')
    return head, nodes


def container_args(nodes: Sequence[tuple[str, Sequence[str]]], process_args: Sequence[str] = ()) -> list[str]:
    """The command-line arguments (after the program) that run `nodes` [(KIND, node arguments)] in one container."""
    out = list(process_args)
    for kind, own in nodes:
        out += [NODE_FLAG, kind, *own]
    return out


def _build(nodes: Sequence[tuple[str, list[str]]]) -> list[Any]:
    """Every node, in order; if one cannot start, the ones built before it are destroyed and its StartupError
    names it (the node's namespace and kind)."""
    built: list[Any] = []
    try:
        for kind, own in nodes:
            try:
                built.append(_node_class(kind)(cli_args=own))
            except FastepError as exc:
                where = _namespace(own)
                raise StartupError(f'{kind}{f" in {where}" if where else ""}: {exc}') from None
    except BaseException:
        for node in reversed(built):
            node.destroy_node()
        raise
    return built


def _namespace(own: Sequence[str]) -> str:
    for i, arg in enumerate(own[:-1]):
        if arg == '-r' and own[i + 1].startswith('__ns:='):
            return own[i + 1].removeprefix('__ns:=')
    return ''


def main(argv: Sequence[str] | None = None) -> int:
    from fastep_core.cli import fail
    from fastep_ros.common import node_main

    try:
        head, nodes = split_args(sys.argv[1:] if argv is None else argv)
    except StartupError as exc:
        return fail(PROG, exc)
    for kind, _ in nodes:
        _node_class(kind)   # imported now: before a launcher's gate opens (fastep_ros.common.GATE_ENV), not after
    code = node_main(PROG, lambda: _build(nodes), ['container', *head])
    if any(kind == 'recorder' for kind, _ in nodes):
        from fastep_ros.recorder import exit_code
        return exit_code(code, PROG)   # as fastep-record: a write failure is one line and exit 1
    return code


if __name__ == '__main__':
    raise SystemExit(main())
