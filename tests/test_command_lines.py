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
NODES = {'fastep-plant', 'fastep-map', 'fastep-planner', 'fastep-clock', 'fastep-record'}


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
