"""The repository's layering of tests, benchmarks and their shared helpers, checked on the source.

Tests and benchmarks share helpers through the fastep_testing package only: tests never import (or run) a
benchmark, nothing edits sys.path, the product never imports test helpers, and the test folders mirror the
package folders.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PRODUCT = ('fastep_core', 'fastep_ros', 'msg_tools')


def modules(folder: str) -> list[Path]:
    return sorted(p for p in (ROOT / folder).rglob('*.py') if '__pycache__' not in p.parts)


def imported(path: Path) -> set[str]:
    """Top-level names of every module `path` imports (anywhere in the file, lazily or not)."""
    names = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            names.update(alias.name.split('.')[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module.split('.')[0])
    return names


def uses_sys_path(path: Path) -> bool:
    return any(isinstance(node, ast.Attribute) and node.attr == 'path' and isinstance(node.value, ast.Name)
               and node.value.id == 'sys' for node in ast.walk(ast.parse(path.read_text(), str(path))))


def runs_a_benchmark(path: Path) -> bool:
    """Does the file name a benchmark module in a string, as in [python, '-m', 'benchmarks.fake_robots']?"""
    return any(isinstance(node, ast.Constant) and isinstance(node.value, str)
               and re.fullmatch(r'benchmarks(\.\w+)+', node.value) is not None
               for node in ast.walk(ast.parse(path.read_text(), str(path))))


def relative(paths: list[Path]) -> list[str]:
    return [str(p.relative_to(ROOT)) for p in paths]


@pytest.mark.parametrize('folder', ['tests', 'benchmarks', 'fastep_testing'])
def test_nothing_edits_sys_path(folder: str) -> None:
    assert relative([p for p in modules(folder) if uses_sys_path(p)]) == []


def test_tests_neither_import_nor_run_benchmarks() -> None:
    offenders = [p for p in modules('tests') + modules('fastep_testing')
                 if 'benchmarks' in imported(p) or runs_a_benchmark(p)]
    assert relative(offenders) == []


def test_benchmarks_and_helpers_do_not_import_tests() -> None:
    assert relative([p for p in modules('benchmarks') + modules('fastep_testing') if 'tests' in imported(p)]) == []


def test_the_product_imports_no_test_helper() -> None:
    offenders = [p for package in PRODUCT for p in modules(package)
                 if imported(p) & {'fastep_testing', 'benchmarks', 'tests'}]
    assert relative(offenders) == []


def test_test_folders_hold_only_tests() -> None:
    """A helper module next to the tests could only be imported by a bare name: helpers go to fastep_testing."""
    strays = [p for p in modules('tests') if not p.name.startswith('test_') and p.name != 'conftest.py']
    assert relative(strays) == []


def test_test_folders_mirror_the_packages() -> None:
    folders = {p.parent.relative_to(ROOT / 'tests') for p in modules('tests')} - {Path('.')}
    unmatched = [str(f) for f in sorted(folders) if not (ROOT / f / '__init__.py').is_file()]
    assert unmatched == [], 'each tests/<path> must mirror a package <path>'
