"""The layers: fastep_core (numpy, scipy) < msg_tools (ROS messages, MCAP, figures) < fastep_ros (rclpy nodes),
and no import cycle anywhere (on 7380572 it finds navigator <-> optimal_kinematic).

fastep_core must import nothing above it, not even inside a function: read every module's syntax tree and
list each import (statements anywhere in the file, and importlib.import_module / __import__ of a constant).
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
ABOVE_CORE = ('msg_tools', 'fastep_ros', 'rclpy', 'matplotlib')


def imported_modules(path: Path) -> list[tuple[int, str]]:
    """(line, dotted module name) of every import in a Python file, wherever it stands."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.Import):
            found += [(node.lineno, alias.name) for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            found.append((node.lineno, node.module))
        elif isinstance(node, ast.Call) and node.args and isinstance(node.args[0], ast.Constant) \
                and isinstance(node.args[0].value, str):
            name = node.func.attr if isinstance(node.func, ast.Attribute) else getattr(node.func, 'id', '')
            if name in ('import_module', '__import__'):
                found.append((node.lineno, node.args[0].value))
    return found


def test_the_scanner_sees_imports_inside_functions_and_by_name(tmp_path: Path) -> None:
    module = tmp_path / 'm.py'
    module.write_text('import os\n\ndef f():\n    from msg_tools.plots import plot_paths\n'
                      '    import importlib\n    return importlib.import_module("rclpy")\n')
    assert imported_modules(module) == [(1, 'os'), (4, 'msg_tools.plots'), (5, 'importlib'), (6, 'rclpy')]


@pytest.mark.parametrize('path', sorted((ROOT / 'fastep_core').rglob('*.py')),
                         ids=lambda p: str(p.relative_to(ROOT)))
def test_fastep_core_imports_nothing_above_it(path: Path) -> None:
    wrong = [f'{path.relative_to(ROOT)}:{line}: {name}' for line, name in imported_modules(path)
             if name.split('.')[0] in ABOVE_CORE]
    assert not wrong, 'fastep_core imports a higher layer:\n' + '\n'.join(wrong)


@pytest.mark.parametrize('path', sorted((ROOT / 'msg_tools').rglob('*.py')), ids=lambda p: str(p.relative_to(ROOT)))
def test_msg_tools_imports_no_node(path: Path) -> None:
    wrong = [f'{path.relative_to(ROOT)}:{line}: {name}' for line, name in imported_modules(path)
             if name.split('.')[0] == 'fastep_ros']
    assert not wrong, 'msg_tools imports fastep_ros:\n' + '\n'.join(wrong)


def product_imports() -> dict[str, set[str]]:
    """Module -> the product modules it imports (`from package import name` counts `package.name` when that is
    a module of its own, else the package)."""
    files = {'.'.join(p.relative_to(ROOT).with_suffix('').parts).removesuffix('.__init__'): p
             for package in ('fastep_core', 'msg_tools', 'fastep_ros') for p in (ROOT / package).rglob('*.py')}
    graph: dict[str, set[str]] = {}
    for module, path in files.items():
        targets = set()
        for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
            if isinstance(node, ast.Import):
                targets |= {alias.name for alias in node.names}
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                targets |= {f'{node.module}.{alias.name}' if f'{node.module}.{alias.name}' in files else node.module
                            for alias in node.names}
        graph[module] = {t for t in targets if t in files and t != module}
    return graph


def test_no_two_modules_import_each_other() -> None:
    """No import cycle among the product's modules, through any number of modules (a package's __init__
    re-exporting its modules counts too): Tarjan's strongly connected components must all be single modules."""
    graph = product_imports()
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    cycles: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                cycles.append(sorted(component))

    for module in sorted(graph):
        if module not in index:
            visit(module)
    assert cycles == []


def test_the_cycle_finder_sees_the_navigator_split() -> None:
    graph = product_imports()
    assert 'fastep_core.planning.navigator' in graph['fastep_core.planning.navigators.optimal_kinematic']
    assert 'fastep_core.planning.navigators.optimal_kinematic' not in graph['fastep_core.planning.navigator']


def test_only_the_cluster_module_imports_dask() -> None:
    """Dask is the optional extra `cluster` (fastep_core/experiments/cluster.py): no robot node and no other module may
    import it, so a robot, and every command but --cluster, runs without it."""
    wrong = [f'{path.relative_to(ROOT)}:{line}: {name}'
             for package in ('fastep_core', 'msg_tools', 'fastep_ros')
             for path in sorted((ROOT / package).rglob('*.py'))
             for line, name in imported_modules(path)
             if name.split('.')[0] in ('dask', 'distributed')
             and path != ROOT / 'fastep_core' / 'experiments' / 'cluster.py']
    assert not wrong, 'imports Dask outside fastep_core/experiments/cluster.py:\n' + '\n'.join(wrong)
