"""launch/planner.launch.py, the robot bring-up a ROS install runs with `ros2 launch fastep_ros planner.launch.py`.

`launch` and `launch_ros` are not among the registry's ROS wheels, so the file is read with stand-ins for the
four names it uses, each keeping what it is given; the test then makes the command line launch_ros's Node makes
of it (the executable, the node's `arguments`, then `--ros-args` with the node's name, namespace and parameters)
and runs that command on an isolated graph.
"""

from __future__ import annotations

import importlib.util
import subprocess
import sys
import types
from pathlib import Path
from typing import Any

import pytest

from fastep_testing.graph import ROOT, Graph, Helper

LAUNCH_FILE = ROOT / 'launch' / 'planner.launch.py'


class _Recorded:
    def __init__(self, *args: Any, **kwargs: Any) -> None:
        self.args, self.kwargs = args, kwargs


class LaunchConfiguration(_Recorded):
    pass


def _stand_ins(share: Path) -> dict[str, types.ModuleType]:
    modules = {name: types.ModuleType(name) for name in (
        'launch', 'launch.actions', 'launch.substitutions', 'launch_ros', 'launch_ros.actions',
        'ament_index_python', 'ament_index_python.packages')}
    modules['launch'].LaunchDescription = lambda actions: list(actions)   # type: ignore[attr-defined]  # stand-in
    modules['launch.actions'].DeclareLaunchArgument = type('DeclareLaunchArgument', (_Recorded,), {})  # type: ignore[attr-defined]  # stand-in
    modules['launch.substitutions'].LaunchConfiguration = LaunchConfiguration  # type: ignore[attr-defined]  # stand-in
    modules['launch_ros.actions'].Node = type('Node', (_Recorded,), {})  # type: ignore[attr-defined]  # stand-in
    modules['ament_index_python.packages'].get_package_share_directory = \
        lambda package: str(share)   # type: ignore[attr-defined]  # stand-in
    return modules


def described(monkeypatch: pytest.MonkeyPatch, share: Path) -> list[Any]:
    """What generate_launch_description() returns, read with the stand-ins."""
    for name, module in _stand_ins(share).items():
        monkeypatch.setitem(sys.modules, name, module)
    spec = importlib.util.spec_from_file_location('planner_launch', LAUNCH_FILE)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return list(module.generate_launch_description())


def command_line(actions: list[Any], **arguments: str) -> tuple[str, list[str]]:
    """(executable, its arguments) as `ros2 launch ... name:=value` runs the file's one node."""
    values = {a.args[0]: a.kwargs['default_value'] for a in actions if type(a).__name__ == 'DeclareLaunchArgument'}
    unknown = set(arguments) - set(values)
    assert not unknown, f'not launch arguments: {unknown}'
    values.update(arguments)

    def resolve(value: Any) -> Any:
        return values[value.args[0]] if isinstance(value, LaunchConfiguration) else value

    [node] = [a for a in actions if type(a).__name__ == 'Node']
    kw = node.kwargs
    args = [resolve(a) for a in kw.get('arguments', [])] + ['--ros-args', '-r', f'__node:={kw["name"]}']
    namespace = resolve(kw.get('namespace', ''))
    if namespace:
        args += ['-r', f'__ns:={namespace}']
    for entry in kw.get('parameters', []):
        if isinstance(entry, dict):
            args += [arg for key, value in entry.items() for arg in ('-p', f'{key}:={resolve(value)}')]
        else:
            args += ['--params-file', resolve(entry)]
    assert kw['package'] == 'fastep_ros'
    return kw['executable'], args


def test_the_launch_file_declares_what_a_nav2_bring_up_takes(monkeypatch: pytest.MonkeyPatch) -> None:
    actions = described(monkeypatch, ROOT)
    declared = [a.args[0] for a in actions if type(a).__name__ == 'DeclareLaunchArgument']
    assert declared == ['namespace', 'params_file', 'use_sim_time', 'autostart', 'log_level']
    executable, args = command_line(actions)
    assert executable == 'fastep-planner'
    assert args[args.index('--params-file') + 1] == str(ROOT / 'config' / 'planner.yaml')
    assert 'use_sim_time:=false' in args and 'autostart:=true' in args


def test_the_launched_planner_comes_up_in_the_robot_namespace_with_its_params_file(
        monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    """The command the launch file stands for starts the planner under /r7, configured from the params file."""
    executable, args = command_line(described(monkeypatch, ROOT), namespace='/r7')
    scripts = Path(sys.executable).parent
    graph = Graph(tmp_path)
    log = open(tmp_path / 'planner.log', 'wb')
    proc = subprocess.Popen([str(scripts / executable), *args], env=graph.env, stdout=log, stderr=subprocess.STDOUT,
                            stdin=subprocess.DEVNULL)
    log.close()
    graph.procs['planner'] = proc
    try:
        graph.helper = helper = Helper(graph.domain)
        helper.record_status('/r7')
        status = helper.wait_status('/r7', lambda s: s.get('reason', '').startswith('waiting'), 120.0,
                                    'the planner up and waiting for its inputs')
        assert status['algorithm'] == 'fastep_route', status
        # Node names travel on their own discovery topic (ros_discovery_info), not with the status publisher's
        # endpoint: in CI the status came while the helper's node list still held only itself. Wait for it.
        helper.spin_until(lambda: ('planner', '/r7') in helper.node.get_node_names_and_namespaces(), 60.0,
                          'the planner in the graph\'s node list as /r7/planner')
        # The params file's values, asked of the node: config/planner.yaml's base (max_speed 0.5, not 1.0).
        from rclpy.parameter_client import AsyncParameterClient
        client = AsyncParameterClient(helper.node, '/r7/planner')
        helper.spin_until(lambda: client.services_are_ready(), 60.0, 'the planner\'s parameter services')
        future = client.get_parameters(['max_speed', 'model', 'obstacle_source'])
        helper.spin_until(future.done, 60.0, 'the parameters')
        values = [v.double_value or v.string_value for v in future.result().values]
        assert values == [0.5, 'diff_drive', 'map']
    finally:
        graph.close()
