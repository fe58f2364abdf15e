"""The documentation's reference pages, generated from the code so that they cannot drift from it.

- parameters.md: every node's parameters, from the descriptors the node declares and what fastep_ros.common.declare
  was given (unit, component), the planner's and the plant's in one table per component (COMPONENTS: a parameter
  declared without one of its node's components stops the generator); `runtime` from the node's
  DynamicParameters;
- topics.md: every node's publishers and subscriptions as the node makes them (name, type, QoS);
- commands.md: every command line's --help, from its argument parser;
- status.md: the planner's status messages and failure reasons with their Nav2 error codes;
- config/fastep.yaml: a params file with every parameter of the planner and the plant at its default.

    python -m fastep_ros.reference docs/reference config/fastep.yaml
        (make docs; tests/fastep_ros/test_reference.py checks that the files in the repository are what it writes)

The nodes are built in a context of their own with discovery off: another graph on the domain stays out of the
pages.
"""

from __future__ import annotations

import contextlib
import io
import json
import math
import os
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Sequence

from rcl_interfaces.msg import ParameterDescriptor, ParameterType

if TYPE_CHECKING:
    from fastep_ros.common import Param

__all__ = ['COMPONENTS', 'NODES', 'COMMANDS', 'components', 'main', 'pages', 'runtime']

ROBOT_NS = '/r1'
NODES: tuple[tuple[str, str, str, str, dict[str, Any]], ...] = (
    # (executable, module, class, namespace, parameters it needs to start: their defaults are shown, not these)
    ('fastep-planner', 'fastep_ros.planner', 'PlannerNode', ROBOT_NS, {}),
    ('fastep-plant', 'fastep_ros.plant', 'PlantNode', ROBOT_NS, {}),
    ('fastep-map', 'fastep_ros.map_server', 'MapNode', '/', {'scenario': 'crossing_movers'}),
    ('fastep-clock', 'fastep_ros.clock', 'ClockNode', '/', {}),
    ('fastep-record', 'fastep_ros.recorder', 'RecorderNode', '/', {'output': '{tmp}/reference.mcap'}),
)
DEFAULTS = {('fastep-map', 'scenario'): '', ('fastep-record', 'output'): ''}   # what the nodes declare
COMMANDS: tuple[tuple[str, str, str], ...] = (
    # (command, module, function taking argv)
    ('fastep-sim', 'msg_tools.sim_cli', 'main'),
    ('fastep-bench', 'msg_tools.bench_cli', 'main'),
    ('fastep-tune', 'fastep_core.experiments.tuning', 'main'),
    ('fastep-launch', 'fastep_ros.launch', 'main'),
    ('fastep-report', 'msg_tools.report', 'main'),
    ('fastep-replay', 'fastep_ros.replay', 'main'),
    ('fastep-recover', 'msg_tools.recover', 'main'),
)
TYPE_NAMES = {ParameterType.PARAMETER_BOOL: 'bool', ParameterType.PARAMETER_INTEGER: 'int',
              ParameterType.PARAMETER_DOUBLE: 'double', ParameterType.PARAMETER_STRING: 'string',
              ParameterType.PARAMETER_BYTE_ARRAY: 'byte[]', ParameterType.PARAMETER_BOOL_ARRAY: 'bool[]',
              ParameterType.PARAMETER_INTEGER_ARRAY: 'int[]', ParameterType.PARAMETER_DOUBLE_ARRAY: 'double[]',
              ParameterType.PARAMETER_STRING_ARRAY: 'string[]'}
PARAMS_FILE = 'fastep.yaml'
HELP_WIDTH = '110'   # COLUMNS for argparse: the same wrapping on every terminal
SKIPPED = ('use_sim_time', 'start_type_description_service')   # rclpy's own, on every node


def _cell(text: str) -> str:
    return ' '.join(str(text).split()).replace('|', '\\|')


def _number(value: float) -> str:
    return '-inf' if value == -math.inf else 'inf' if value >= sys.float_info.max or value == math.inf else f'{value:g}'


def _limits(d: ParameterDescriptor) -> str:
    if d.floating_point_range:
        r = d.floating_point_range[0]
        return f'[{_number(r.from_value)}, {_number(r.to_value)}]'
    if d.integer_range:
        r = d.integer_range[0]
        return f'[{r.from_value}, {r.to_value}]'
    return d.additional_constraints


def _value(value: Any) -> str:
    if isinstance(value, str):
        return f'`{value!r}`'
    if isinstance(value, (list, tuple)) or type(value).__name__ == 'array':
        return f'`{list(value)}`'
    return f'`{value}`'


def _node(module: str, cls: str, namespace: str, params: dict[str, Any], context: Any) -> Any:
    import importlib

    from rclpy.parameter import Parameter
    node_class = getattr(importlib.import_module(module), cls)
    return node_class(context=context, namespace=namespace,
                      parameter_overrides=[Parameter(k, value=v) for k, v in params.items()])


def _shown_name(topic: str) -> str:
    return '`<ns>' + topic[len(ROBOT_NS):] + '`' if topic.startswith(ROBOT_NS + '/') else f'`{topic}`'


def _qos(profile: Any) -> str:
    reliability = 'reliable' if profile.reliability.name == 'RELIABLE' else profile.reliability.name.lower()
    durability = 'transient-local' if profile.durability.name == 'TRANSIENT_LOCAL' else profile.durability.name.lower()
    return f'{reliability}, {durability}, depth {profile.depth}'


def _type_name(msg_type: Any) -> str:
    module = msg_type.__module__.split('.')
    return f'{module[0]}/{module[1]}/{msg_type.__name__}'


PARAMS_FILE_NODES = {'fastep-planner': 'planner', 'fastep-plant': 'plant'}   # executable: node name
COMPONENTS: dict[str, tuple[tuple[str, str, str], ...]] = {
    # executable: its components in page order, (key, title, what they set); every parameter declares one
    'fastep-planner': (
        ('node', 'Node', 'frames, topics, rates and timeouts, threads, the lifecycle'),
        ('robot', 'Robot', 'its model and body, and the other robots'),
        ('controller', 'Controller', 'the kinematic control laws (eq. 12 / 13, the diff_drive law) and the goal '
         'checker'),
        ('safety', 'Safety', 'the speed, turn and acceleration limits the guard and the velocity smoother enforce, '
         'the emergency stop, the look-ahead at movers'),
        ('swarm', 'Step planning', 'FAStep\'s firefly swarm (Table 1), its fitness (eq. 10) and when it runs; ACO_R '
         'for aco'),
        ('route', 'Route', 'FAStep-Route, driving the shortest path'),
        ('recovery', 'Recovery', 'the progress checker, the trap escape, a goal that fails'),
        ('dwa', 'DWA', 'the Dynamic Window Approach (algorithm dwa)'),
        ('perception', 'Perception', 'obstacle detection, the laser scan and how far the map pose may be off'),
        ('simulator', 'Simulator only', 'read by fastep-sim (and fastep-launch); the node takes it and does not use '
         'it'),
    ),
    'fastep-plant': (
        ('node', 'Node', 'frames, topics, rates and timeouts, the lifecycle'),
        ('robot', 'Robot', 'its model, body, limits and dynamics'),
        ('sensor', 'Sensor', 'the simulated laser scanner'),
    ),
}


def _yaml(value: Any) -> str | None:
    """A parameter's value as YAML the rcl parser reads with the parameter's type; None for an empty array (its
    type cannot be told from `[]`)."""
    if isinstance(value, bool):
        return 'true' if value else 'false'
    if isinstance(value, float):
        return '.inf' if value == math.inf else '-.inf' if value == -math.inf else repr(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, (list, tuple)) or type(value).__name__ == 'array':
        items = [_yaml(v) for v in value]
        return None if not items else '[' + ', '.join(str(i) for i in items) + ']'
    return str(value)


def components(executable: str, names: Sequence[str], given: dict[str, Param]) -> dict[str, list[str]]:
    """The parameters `names` of a node by component key (COMPONENTS of `executable`, in page order), from what
    their declarations gave (`given`: fastep_ros.common.declared); ValueError naming every parameter declared
    without one of its node's components."""
    keys = [key for key, _, _ in COMPONENTS[executable]]
    missing = [name for name in names if name not in given or given[name].component not in keys]
    if missing:
        raise ValueError(f'{executable}: parameter(s) {", ".join(missing)} declared without a component of '
                         f'{" | ".join(keys)} (component= in the declaration; fastep_ros.reference.COMPONENTS)')
    return {key: [name for name in names if given[name].component == key] for key in keys}


def runtime(executable: str, names: Sequence[str], descriptors: Sequence[ParameterDescriptor],
            applied: frozenset[str]) -> dict[str, bool]:
    """Whether each parameter changes while the node runs: writable (not read_only) and applied by the node's
    DynamicParameters (`applied`: fastep_ros.parameters.runtime_names); ValueError for one that is only one of
    the two (a set rclpy takes and the node ignores, or one it applies and rclpy refuses)."""
    odd = [name for name, d in zip(names, descriptors) if (not d.read_only) != (name in applied)]
    if odd:
        raise ValueError(f'{executable}: parameter(s) {", ".join(odd)} are writable but not applied at runtime, or '
                         f'applied but read-only (read_only= in the declaration, DynamicParameters\' names)')
    return {name: not d.read_only for name, d in zip(names, descriptors)}


def _row(name: str, d: ParameterDescriptor, default: Any, unit: str, changes: bool) -> str:
    return (f'| `{name}` | {TYPE_NAMES.get(d.type, "?")} | {_cell(_value(default))} | {_cell(unit)} | '
            f'{_cell(_limits(d))} | {"yes" if changes else "no"} | {_cell(d.description)} |')


ROW_HEAD = ['| parameter | type | default | unit | range | runtime | description |', '|---|---|---|---|---|---|---|']


def node_pages(context: Any, tmp: str) -> tuple[str, str, str]:
    """(parameters.md, topics.md, the params file) of every node of NODES; `tmp`: a folder for what they write
    (the recorder)."""
    from fastep_ros.common import declared
    from fastep_ros.parameters import runtime_names
    config = ['# Every parameter of fastep-planner and fastep-plant at its default, by component; above each, its',
              '# description (range; unit; `runtime` if the running node takes a new value). To start with it:',
              '#   fastep-planner --ros-args -r __ns:=/r1 --params-file config/fastep.yaml',
              '# (ros2 run fastep_ros fastep-planner ... on a ROS install). Change what differs on your robot and',
              '# delete the rest. Generated from the nodes\' declarations: python -m fastep_ros.reference;',
              '# docs/reference/parameters.md is the same as tables.']
    params = ['# Node parameters', '',
              'Generated from what each node declares (`python -m fastep_ros.reference`); set them with '
              '`-p name:=value` or `--params-file` (config/fastep.yaml holds every parameter of the planner and the '
              'plant at its default, by component). The planner\'s '
              'and the plant\'s parameters are in one table per component. **runtime** yes: the running node '
              'applies a new value at once (`ros2 param set`, rqt); no: the value is fixed when the node starts '
              '([Parameters, diagnostics, lifecycle](../parameters.md) says how each is applied). A range `[a, b]` '
              'is enforced on every set; a **unit** list is the unit of each element of an array.', '']
    topics = ['# Topics', '',
              'Generated from the publishers and subscriptions each node makes (`python -m fastep_ros.reference`), '
              'for a robot in namespace `<ns>` (names are relative, so `-r __ns:=/r1` puts them under `/r1`). '
              'The planner subscribes to other robots\' `<other>/odom` and `<other>/footprint` as it finds them on '
              'the graph (docs/robots_and_goals.md), and takes `/tf` when it resolves a goal in another frame (both '
              'polled, not listed: fastep_ros.polled).', '']
    for executable, module, cls, namespace, needed in NODES:
        needed = {k: v.format(tmp=tmp) if isinstance(v, str) else v for k, v in needed.items()}
        node = _node(module, cls, namespace, needed, context)
        try:
            names = sorted(n for n in node.list_parameters([], 0).names if n not in SKIPPED)
            descriptors = dict(zip(names, node.describe_parameters(names)))
            given = declared(node)
            changes = runtime(executable, names, list(descriptors.values()), runtime_names(node))
            rows_of = {name: _row(name, descriptors[name], DEFAULTS.get((executable, name),
                                                                        node.get_parameter(name).value),
                                  given[name].unit if name in given else '', changes[name]) for name in names}

            params += [f'## {executable}', '']
            grouped = components(executable, names, given) if executable in COMPONENTS else {'': names}
            titles = {key: (title, what) for key, title, what in COMPONENTS.get(executable, ())}
            for key, members in grouped.items():
                if key:
                    title, what = titles[key]
                    count = f'{len(members)} parameter{"s" if len(members) != 1 else ""}'
                    params += [f'### {executable.removeprefix("fastep-")}: {title}', '',
                               f'{what[0].upper()}{what[1:]}; {count}.', '']
                params += [*ROW_HEAD, *(rows_of[name] for name in members), '']
            if executable in PARAMS_FILE_NODES:
                config += ['', f'/**/{PARAMS_FILE_NODES[executable]}:', '  ros__parameters:']
                for key, members in grouped.items():
                    title, what = titles[key]
                    config += ['', f'    # ---- {title}: {what}']
                    for name in members:
                        d = descriptors[name]
                        limits = _limits(d)
                        unit = given[name].unit
                        notes = '; '.join(n for n in (limits, unit, 'runtime' if changes[name] else '') if n)
                        config.append(f'    # {" ".join(d.description.split())}{f" ({notes})" if notes else ""}')
                        value = _yaml(node.get_parameter(name).value)
                        config.append(f'    {name}: {value}' if value is not None else f'    # {name}: [] (none)')
            topics_rows = [(_shown_name(p.topic_name), 'publishes', _type_name(p.msg_type), _qos(p.qos_profile))
                           for p in node.publishers]
            topics_rows += [(_shown_name(s.topic_name), 'subscribes', _type_name(s.msg_type), _qos(s.qos_profile))
                            for s in node.subscriptions]
            rows = sorted({r for r in topics_rows if not r[0].startswith(('`/parameter_events', '`/rosout'))})
            actions = getattr(node, 'actions', None)   # the planner's Nav2 actions (fastep_ros.navigate_actions)
            if actions is not None:
                rows += [(f'`<ns>/{name}`', f'serves (action; node `<ns>/{actions.side.name}`)', _type_name(kind),
                          "rclpy's action defaults") for name, kind in actions.served.items()]
            topics += [f'## {executable}', '', '| topic | | type | QoS |', '|---|---|---|---|',
                       *(f'| {name} | {kind} | {kind_type} | {qos} |' for name, kind, kind_type, qos in rows), '']
        finally:
            node.destroy_node()
    return '\n'.join(params), '\n'.join(topics), '\n'.join(config)


def _help(module: str, function: str) -> str:
    import importlib
    main: Callable[[Sequence[str]], int] = getattr(importlib.import_module(module), function)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        try:
            main(['--help'])
        except SystemExit:
            pass
    return out.getvalue().rstrip()


def commands_page() -> str:
    lines = ['# Command lines', '',
             'Generated from each command\'s argument parser (`python -m fastep_ros.reference`). Bad input is one '
             'line on stderr and exit 2; Ctrl-C is exit 130 (fastep-launch: 1, after stopping every node).', '']
    before = os.environ.get('COLUMNS')
    os.environ['COLUMNS'] = HELP_WIDTH
    try:
        for command, module, function in COMMANDS:
            lines += [f'## {command}', '', '```text', _help(module, function), '```', '']
    finally:
        if before is None:
            del os.environ['COLUMNS']
        else:
            os.environ['COLUMNS'] = before
    return '\n'.join(lines)


DISCOVERY_ENV = ('ROS_AUTOMATIC_DISCOVERY_RANGE', 'ROS_STATIC_PEERS', 'ROS_LOCALHOST_ONLY')


def status_page() -> str:
    from fastep_ros.navigate_actions import (
        ERROR_CODES,
        NAVIGATION_TF,
        UNKNOWN_DRIVING,
        UNKNOWN_PLANNING,
        WAYPOINTS_FAILED,
    )
    from fastep_ros.planner_status import STATUS_MESSAGES
    lines = ['# Status and failure reasons', '',
             'Generated from the planner\'s tables (`python -m fastep_ros.reference`). The planner publishes '
             '`<ns>/status` (diagnostic_msgs/DiagnosticStatus, latched): `message` is one of these, `level` its '
             'level, the value `reason` says why, in words; /diagnostics carries the same '
             '([Parameters, diagnostics, lifecycle](../parameters.md)).', '',
             '| message | level | meaning |', '|---|---|---|',
             *(f'| `{message}` | {level} | {_cell(meaning)} |' for message, level, meaning in STATUS_MESSAGES), '',
             '## Failure reasons and Nav2 error codes', '',
             'A goal that fails, or is refused, ends its action (navigate_to_pose, navigate_through_poses, '
             'follow_waypoints) ABORTED with the error code of the first of these phrases its reason contains:', '',
             '| the reason contains | error code |', '|---|---|',
             *(f'| {words} | {code} |' for words, code in ERROR_CODES),
             f'| anything else, for a goal refused | {UNKNOWN_PLANNING} (ComputePathToPose UNKNOWN) |',
             f'| anything else, on the way | {UNKNOWN_DRIVING} (FollowPath UNKNOWN) |', '',
             f'As Nav2 Jazzy: a navigation goal whose pose TF cannot put in the map frame ends with {NAVIGATION_TF}; '
             f'follow_waypoints with stop_on_failure ends at a failed waypoint with {WAYPOINTS_FAILED} (the waypoint '
             'in missed_waypoints with its code); without, the waypoint goes into missed_waypoints and the goal goes '
             'on. The other servers\' codes: [From Nav2 to fastep](../nav2.md).']
    return '\n'.join(lines)


def pages() -> dict[str, str]:
    """Every generated file, by name: the reference pages and PARAMS_FILE (the params file)."""
    import tempfile

    import rclpy
    from rclpy.context import Context
    from rclpy.signals import SignalHandlerOptions
    context = Context()
    # Discovery off: the nodes see only themselves. With another graph on the domain (a test running beside make
    # docs), the recorder subscribed to that graph's topics and they went into topics.md.
    saved = {name: os.environ.pop(name, None) for name in DISCOVERY_ENV}
    os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'OFF'
    try:
        rclpy.init(args=[], context=context, signal_handler_options=SignalHandlerOptions.NO)
    finally:
        for name, value in saved.items():
            os.environ.pop(name, None)
            if value is not None:
                os.environ[name] = value
    try:
        with tempfile.TemporaryDirectory() as tmp:
            params, topics, config = node_pages(context, tmp)
    finally:
        rclpy.try_shutdown(context=context)
    return {'parameters.md': params, 'topics.md': topics, 'commands.md': commands_page(), 'status.md': status_page(),
            PARAMS_FILE: config}


def main(argv: Sequence[str] | None = None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    folder = Path(args[0] if args else 'docs/reference')
    config = Path(args[1] if len(args) > 1 else 'config/fastep.yaml')
    folder.mkdir(parents=True, exist_ok=True)
    for name, text in pages().items():
        path = config if name == PARAMS_FILE else folder / name
        path.write_text(text + '\n')
        print(f'wrote {path}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
