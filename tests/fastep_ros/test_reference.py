"""The reference pages in docs/reference/ are what fastep_ros.reference generates from the code now: a parameter,
topic or command-line option changed without `make docs` fails here."""

from __future__ import annotations

from pathlib import Path

import pytest

from fastep_ros.reference import COMPONENTS, PARAMS_FILE, components, pages, runtime

ROOT = Path(__file__).resolve().parents[2]


def test_the_generated_reference_pages_and_params_file_are_current() -> None:
    where = {name: ROOT / ('config' if name == PARAMS_FILE else 'docs/reference') / name for name in pages()}
    import difflib
    generated = pages()
    stale = [name for name, text in generated.items() if where[name].read_text() != text + '\n']
    diff = ''.join(line for name in stale for line in list(difflib.unified_diff(
        where[name].read_text().splitlines(True), (generated[name] + '\n').splitlines(True), str(where[name]),
        'generated'))[:30])
    assert not stale, f'{", ".join(stale)} differ from the code: run `make docs` and commit them\n{diff}'


def test_the_reference_is_generated_apart_from_any_graph_on_the_domain() -> None:
    """A graph on the same domain (a test beside make docs) put its topics into topics.md: the recorder there
    subscribed to them. Discovery is off while the pages are made."""
    import os
    import subprocess
    import sys
    import time
    intruder = subprocess.Popen([sys.executable, '-c', (
        'import rclpy, time\n'
        'from nav_msgs.msg import Odometry\n'
        'rclpy.init(); node = rclpy.create_node("intruder", namespace="/r9")\n'
        'pub = node.create_publisher(Odometry, "odom", 10)\n'
        'print("up", flush=True)\n'
        'while True:\n'
        '    pub.publish(Odometry()); time.sleep(0.05)\n')],
        env=dict(os.environ, ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST'), stdout=subprocess.PIPE, text=True)
    try:
        assert intruder.stdout is not None and intruder.stdout.readline().strip() == 'up'
        time.sleep(1.0)   # discovered by then by anyone who looks (it needs no more than DDS's first announcements)
        assert '/r9/' not in pages()['topics.md']
    finally:
        intruder.kill()
        intruder.wait()


def test_the_reference_has_every_node_and_command() -> None:
    generated = pages()
    for executable in ('fastep-planner', 'fastep-plant', 'fastep-map', 'fastep-clock', 'fastep-record'):
        assert f'## {executable}' in generated['parameters.md'] and f'## {executable}' in generated['topics.md']
    assert '| `exclusive_cmd_vel` | bool | `True` |  |  | yes |' in generated['parameters.md']
    assert '| `max_speed` | double | `1.0` | m/s | [0, inf] | yes |' in generated['parameters.md']
    assert '| `frame_id` | string | `\'map\'` |  |  | no |' in generated['parameters.md']
    for executable, parts in COMPONENTS.items():
        for _, title, _ in parts:
            assert f'### {executable.removeprefix("fastep-")}: {title}\n' in generated['parameters.md']
    assert '    # ---- Safety: ' in generated[PARAMS_FILE]
    assert '| `<ns>/cmd_vel` | publishes | geometry_msgs/msg/Twist | reliable, volatile, depth 10 |' in \
        generated['topics.md']
    for command in ('fastep-sim', 'fastep-bench', 'fastep-tune', 'fastep-launch', 'fastep-report', 'fastep-replay',
                    'fastep-recover'):
        assert f'## {command}\n\n```text\nusage: {command}' in generated['commands.md'], command


def test_the_status_table_holds_every_message_the_planner_says() -> None:
    """STATUS_MESSAGES (the status page) against the code: each message PlannerReports.status and
    navigation_status return as a literal, and every navigator mode."""
    import ast
    import inspect
    import textwrap

    from fastep_core.planning.navigator import Mode
    from fastep_ros.planner_status import STATUS_MESSAGES, PlannerReports
    said = set()
    for method in (PlannerReports.status, PlannerReports.navigation_status):
        tree = ast.parse(textwrap.dedent(inspect.getsource(method)))
        for node in ast.walk(tree):
            if isinstance(node, ast.Return) and isinstance(node.value, ast.Tuple) and len(node.value.elts) == 3:
                message = node.value.elts[1]
                said |= {c.value for c in ast.walk(message) if isinstance(c, ast.Constant) and isinstance(c.value, str)}
    said |= {mode.value for mode in Mode}
    assert said == {message for message, _, _ in STATUS_MESSAGES}
    assert 'status.md' in pages() and '| `conflict` | ERROR |' in pages()['status.md']


def test_every_planner_and_plant_parameter_declares_one_of_its_nodes_components() -> None:
    """The planner's table (PlannerParams and the node's own) places every parameter: a new one declared without a
    component stops the generator (test below), and so make docs."""
    from fastep_ros.planner_params import PARAMETERS
    keys = {key for key, _, _ in COMPONENTS['fastep-planner']}
    assert {param.name: param.component for param in PARAMETERS if param.component not in keys} == {}


def test_a_parameter_without_a_component_stops_the_generator() -> None:
    from fastep_ros.common import Param
    given = {'rate': Param('rate', 1.0, 'how often', unit='Hz', component='node'), 'gain': Param('gain', 1.0, 'k')}
    with pytest.raises(ValueError, match='gain declared without a component'):
        components('fastep-planner', ['gain', 'rate'], given)
    with pytest.raises(ValueError, match='undeclared'):   # declared past fastep_ros.common.declare: nothing known
        components('fastep-planner', ['rate', 'undeclared'], given)
    assert components('fastep-planner', ['rate'], given)['node'] == ['rate']


def test_runtime_is_what_the_node_applies_and_rclpy_lets_through() -> None:
    from rcl_interfaces.msg import ParameterDescriptor
    writable, fixed = ParameterDescriptor(read_only=False), ParameterDescriptor(read_only=True)
    assert runtime('n', ['a', 'b'], [writable, fixed], frozenset({'a'})) == {'a': True, 'b': False}
    with pytest.raises(ValueError, match='b are writable but not applied'):   # a set taken and then ignored
        runtime('n', ['a', 'b'], [writable, writable], frozenset({'a'}))
    with pytest.raises(ValueError, match='a are writable'):   # applied, but rclpy refuses every set
        runtime('n', ['a'], [fixed], frozenset({'a'}))
