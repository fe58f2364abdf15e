"""Every console script: a flag it does not know is one line on stderr and exit code 2, nothing on stdout.

The commands are read from setup.py, so a new console script must be listed here as a command line (tested)
or as a ROS node (its input are ROS parameters: tests/fastep_ros/test_launch.py checks those).
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
COMMANDS = {'fastep-sim', 'fastep-bench', 'fastep-tune', 'fastep-report', 'fastep-recover', 'fastep-replay',
            'fastep-launch'}
NODES = {'fastep-plant', 'fastep-map', 'fastep-planner', 'fastep-clock', 'fastep-record', 'fastep-foxglove',
         'fastep-container'}


def console_scripts() -> dict[str, str]:
    """name -> module of every console script in setup.py."""
    tree = ast.parse((ROOT / 'setup.py').read_text())
    for node in ast.walk(tree):
        if isinstance(node, ast.keyword) and node.arg == 'entry_points':
            entries = ast.literal_eval(node.value)['console_scripts']
            return {name.strip(): target.split(':')[0].strip()
                    for name, target in (entry.split('=') for entry in entries)}
    raise AssertionError('setup.py has no entry_points')


def test_every_console_script_is_a_command_or_a_node() -> None:
    assert set(console_scripts()) == COMMANDS | NODES


@pytest.mark.parametrize('name', sorted(COMMANDS))
def test_unknown_flag_is_one_line_and_exit_2(name: str) -> None:
    module = console_scripts()[name]
    done = subprocess.run([sys.executable, '-m', module, 'x', '--no-such-flag'], capture_output=True, text=True,
                          timeout=120, cwd=ROOT)
    assert done.returncode == 2, done.stderr
    assert done.stdout == ''
    assert done.stderr.startswith(f'{name}: error: ') and 'Traceback' not in done.stderr
    assert len(done.stderr.splitlines()) == 1, done.stderr


# Every tool that loads a scenario, with how it is given one (issue "Hardening", item 3: a 500-byte alias bomb
# hung them all, or ended in MemoryError).
SCENARIO_TOOLS = {
    'fastep-sim': ['{}'],
    'fastep-bench': ['--scenarios', '{}', '--runs', '1', '--out', '{dir}'],
    'fastep-launch': ['{}'],
    'fastep-map': ['--ros-args', '-p', 'scenario:={}'],
    'fastep-record': ['--ros-args', '-p', 'scenario:={}', '-p', 'output:={dir}/r.mcap'],
    'fastep-foxglove': ['--ros-args', '-p', 'scenario:={}', '-p', 'port:=0'],
}
LAUGHS = 'x_a: &a [lol, lol, lol, lol, lol, lol, lol, lol, lol]\n' + ''.join(
    f"x_{b}: &{b} [{', '.join([f'*{a}'] * 9)}]\n" for a, b in zip('abcdefgh', 'bcdefghi'))
HOSTILE = {
    'alias_bomb': ('workspace: *i\n', 'more than 1000000 nodes once its aliases are expanded'),
    'deep': ('x_deep: ' + '[' * 1000 + ']' * 1000 + '\nworkspace: [0, 0, 9, 9]\n', 'nested deeper than 64'),
}


@pytest.mark.parametrize('case', sorted(HOSTILE))
@pytest.mark.parametrize('name', sorted(SCENARIO_TOOLS))
def test_a_hostile_scenario_is_one_line_and_exit_2(tmp_path: Path, name: str, case: str) -> None:
    from fastep_testing.graph import free_domain, isolated_env
    text, words = HOSTILE[case]
    path = tmp_path / f'{case}.yaml'
    path.write_text(LAUGHS + text + 'robots:\n  - {name: r1, model: point_mass, start: [1, 1], goal: [5, 5], '
                    'radius: 0.5}\n')
    args = [arg.format(str(path), dir=tmp_path) for arg in SCENARIO_TOOLS[name]]
    env = isolated_env(free_domain(), tmp_path / 'roslog')
    done = subprocess.run([sys.executable, '-m', console_scripts()[name], *args], capture_output=True, text=True,
                          timeout=120, cwd=ROOT, env=env)
    assert done.returncode == 2, done.stderr
    assert words in done.stderr and 'Traceback' not in done.stderr, done.stderr
    assert len(done.stderr.strip().splitlines()) == 1, done.stderr
