"""The layers: fastep_core (numpy, scipy) < msg_tools (ROS messages, MCAP, figures) < fastep_ros (rclpy nodes).

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
