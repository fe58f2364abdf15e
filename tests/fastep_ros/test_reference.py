"""The reference pages in docs/reference/ are what fastep_ros.reference generates from the code now: a parameter,
topic or command-line option changed without `make docs` fails here."""

from __future__ import annotations

from pathlib import Path

from fastep_ros.reference import PARAMS_FILE, pages

ROOT = Path(__file__).resolve().parents[2]


def test_the_generated_reference_pages_and_params_file_are_current() -> None:
    where = {name: ROOT / ('config' if name == PARAMS_FILE else 'docs/reference') / name for name in pages()}
    stale = [where[name] for name, text in pages().items() if where[name].read_text() != text + '\n']
    assert not stale, f'{", ".join(map(str, stale))} differ from the code: run `make docs` and commit them'


def test_the_reference_has_every_node_and_command() -> None:
    generated = pages()
    for executable in ('fastep-planner', 'fastep-plant', 'fastep-map', 'fastep-clock', 'fastep-record'):
        assert f'## {executable}' in generated['parameters.md'] and f'## {executable}' in generated['topics.md']
    assert '| `exclusive_cmd_vel` | bool | `True` |  |  |' in generated['parameters.md']
    assert '| `<ns>/cmd_vel` | publishes | geometry_msgs/msg/Twist | reliable, volatile, depth 10 |' in \
        generated['topics.md']
    for command in ('fastep-sim', 'fastep-bench', 'fastep-tune', 'fastep-launch', 'fastep-report', 'fastep-replay',
                    'fastep-recover'):
        assert f'## {command}\n\n```text\nusage: {command}' in generated['commands.md'], command
