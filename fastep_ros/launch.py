"""fastep-launch: run a scenario through the live ROS 2 graph and report what every robot did.

    fastep-launch SCENARIO [--rtf X] [--timeout S] [--algorithm fastep|aco|optimal|dwa] [--seed N]
                  [--json OUT] [--plot OUT.png] [--no-clock | --realtime] [--layout node|robot|graph|cores]
                  [--executor events|single] [--step-iterations K] [--foxglove PORT] [--no-progress] [--verbose]

Starts, in the processes --layout says (fastep_ros.layouts, fastep_ros.processes), gated until it has seen no other
graph on the domain, the map and a plant and a planner per robot with the scenario's parameters; waits until every
planner knows the world and the other robots; sends the goals, starts the clock (exact lock step at --rtf, so the run
is fastep-sim's tick for tick; --realtime counts planning latency; --no-clock runs on wall time), follows status and
odom (fastep_ros.monitor) and prints one line per robot: arrived, path length, time. On wall time with more than
WALL_ROBOTS_PER_CORE robots per core, planners without step_iterations get WALL_STEP_ITERATIONS. Every process it
started is stopped at the end, also on Ctrl-C. Exit 0 if every robot arrived without colliding, 1 otherwise, 2 with
one line for bad input checked first (--rtf outside [0.001, 10000], a bad robot name, an unwritable output file).
"""

from __future__ import annotations

import argparse
import dataclasses
import importlib
import json
import math
import os
import signal
import sys
import threading
import time
from pathlib import Path
from typing import Any, Callable, Mapping, NoReturn, Sequence

from fastep_core.cli import Parser, fail, guard, seed, tcp_port, tcp_port_problem
from fastep_core.dynamics.params import dynamics_data
from fastep_core.errors import ParameterError, ScenarioError
from fastep_core.planning.algorithms import ALGORITHMS, DEFAULT_ALGORITHM, check_drives
from fastep_core.planning.params import PlannerParams
from fastep_core.scenario import RobotSpec, Scenario, builtin_names, load_scenario
from fastep_ros.dds_profile import PROFILE_ENV, use_discovery_profile
from fastep_ros.errors import GraphConflict, LaunchError
from fastep_ros.executors import DEFAULT_EXECUTOR, EXECUTOR_ENV, EXECUTORS
from fastep_ros.launch_progress import Progress
from fastep_ros.launch_report import report
from fastep_ros.layouts import GRAPH_ROBOTS, LAYOUTS, Member, default_layout, usable_cores
from fastep_ros.layouts import command as layout_command
from fastep_ros.limits import RATE_RANGE, RTF_RANGE, graph_problem, robot_name_problem
from fastep_ros.monitor import STOP, Monitor, RobotLive, watched_topics
from fastep_ros.processes import Placement, Processes, ros_value

__all__ = ['main']

PROG = 'fastep-launch'
STARTUP_TIMEOUT = 60.0  # wall seconds for every node to come up and see the world and the other robots
END_WAIT = 5.0          # wall seconds the report waits at most for odometry up to the end of each robot's run
STALL = 45.0            # wall seconds without simulated time advancing before the run is given up: longer than the
                        # clock's wait_timeout (30 s): a clock that gives up on a node that never answered runs on first
INTERRUPT_WAIT = 1.0    # wall seconds a Ctrl-C'd run waits at most for the recorder to reach the time it was stopped at
OBSERVER_LAG = 20       # ticks the observers (this monitor, fastep-record) may lag behind the lock step ...
ACK_TICKS = 5           # ... acknowledging every ACK_TICKS ticks: each tick waited for both (and for an
# acknowledgement of each, 2 more messages into the graph's process) ran 25.8x real time, these 28.7x (make demo,
# 5 runs each; docs/benchmarks.md, "Observers behind the lock step")
DISCOVERY_WAIT = 0.6    # wall seconds the launcher looks for another graph on its domain before its nodes join DDS
# (DDS showed an existing publisher to a new process after 0.3-0.45 s in most starts, up to 3.2 s in some (a
# participant that missed the others' endpoints, fastep_ros.dds_profile): one seen later stops the launch, by the
# checks every CONFLICT_CHECK while the nodes come up and the run goes on, and one just before the goals go out)


def _parser() -> argparse.ArgumentParser:
    p = Parser(prog=PROG, description='Run a scenario through the live ROS 2 graph.')
    p.add_argument('scenario', help='scenario YAML file or built-in name (' + ', '.join(builtin_names()) + ')')
    p.add_argument('--rtf', type=float, default=1.0, help='real-time factor of the simulated clock, at most '
                   '(default 1): each tick waits for every plant and planner, so a busy machine runs slower')
    p.add_argument('--timeout', type=float, default=None,
                   help='give up after this many simulated seconds (default: the scenario\'s max_sim_time)')
    p.add_argument('--algorithm', choices=ALGORITHMS, default=DEFAULT_ALGORITHM,
                   help=f'planner (default {DEFAULT_ALGORITHM}: README, "Which planner")')
    p.add_argument('--seed', type=seed, default=0, help='seed of the swarms (default 0; robot k uses stream k '
                   'of the seed, as fastep-sim does)')
    p.add_argument('--json', type=Path, metavar='OUT', help='write the summary and odometry trajectories')
    p.add_argument('--plot', type=Path, metavar='OUT.png', help='draw the paths like fastep-sim --plot')
    p.add_argument('--record', type=Path, metavar='OUT.mcap',
                   help='record every fastep topic into an MCAP file (fastep-record), finished on exit')
    p.add_argument('--no-clock', action='store_true', help='no simulated clock: every node runs on wall time')
    p.add_argument('--realtime', action='store_true', help='lock step with planning latency counted: the planners '
                   'plan on their planning thread, a plan reaching the control loop when its pass is done while the '
                   'simulated clock goes on (at --rtf), as on a robot; not deterministic')
    p.add_argument('--foxglove', type=tcp_port, metavar='PORT', help='serve a live view for Foxglove (fastep-foxglove) '
                   'on ws://localhost:PORT while the run goes')
    p.add_argument('--no-progress', action='store_true', help='no progress on stderr (robots arrived, simulated '
                   'time, real-time factor: a bar on a terminal, a line every 10 s otherwise)')
    p.add_argument('--layout', choices=LAYOUTS, default=None,
                   help=f'which nodes share a process (default: {default_layout(True)} for up to {GRAPH_ROBOTS} '
                   f'robots with the clock, else {default_layout(False)}): node (one process each), robot (a robot\'s '
                   'plant and planner together), '
                   'graph (all in one), cores (one per CPU core, the robots dealt in turn); the topics are the same')
    p.add_argument('--executor', choices=EXECUTORS, default=None,
                   help=f'rclpy executor of every node (default: ${EXECUTOR_ENV}, else {DEFAULT_EXECUTOR}): events '
                   '(rclpy.experimental.EventsExecutor) or single (SingleThreadedExecutor)')
    p.add_argument('--step-iterations', type=_step_iterations, metavar='K',
                   help='the planners\' step_iterations: swarm iterations of a step plan per control tick, 0 for a '
                   'whole plan in the tick it is needed (default: the scenario\'s; on wall time with more than '
                   f'{WALL_ROBOTS_PER_CORE} robots per CPU core, {WALL_STEP_ITERATIONS} if it has none)')
    p.add_argument('--startup-timeout', type=float, default=STARTUP_TIMEOUT, help=argparse.SUPPRESS)
    p.add_argument('--verbose', action='store_true', help='show the nodes\' INFO logs')
    return p


def _step_iterations(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'not an integer: {text!r}') from None
    try:
        PlannerParams(step_iterations=value)   # its range
    except ParameterError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return value


# ----------------------------------------------------------------------------------------------- processes

def _command(module: str, namespace: str, params: dict[str, Any], verbose: bool) -> list[str]:
    return layout_command([Member(module, module, namespace, params)], 'info' if verbose else 'warn', ros_value)


def _planner_overrides(params: PlannerParams) -> dict[str, Any]:
    defaults = PlannerParams()
    return {name: getattr(params, name) for name in params.names() if getattr(params, name) != getattr(defaults, name)}


def plant_params(spec: RobotSpec, sim_time: bool, params: PlannerParams | None = None, *, scenario: str = '',
                 seed: int = 0, index: int = 0) -> dict[str, Any]:
    """The plant's parameters; a diff-drive base saturates at the scenario's max_speed and max_turn_rate (`params`,
    the scenario's planner parameters), as fastep-sim's model does. A robot with a `sensor` scans the true world
    of `scenario` (the file or built-in name), its noise from the run's `seed` stream `index`, as in fastep-sim."""
    out: dict[str, Any] = {'model': spec.model, 'start': [float(v) for v in spec.start], 'use_sim_time': sim_time}
    if sim_time:
        # Exact lock step (fastep_ros.lock_step): one integration step per control period, each with the command
        # its planner stamped at the step's start.
        out.update(lock_step=True, use_stamped_cmd_vel=True, rate_hz=1.0 / (params or PlannerParams()).dt)
    else:
        # Integrated at 50 Hz, told at the planners' control rate: each planner takes every robot's odometry.
        out.update(odom_rate_hz=1.0 / (params or PlannerParams()).dt)
    if spec.sensor is not None:
        mount = [float(v) for v in spec.sensor.mount] if any(spec.sensor.mount) else []
        out.update(sensor=[float(spec.sensor.range), float(spec.sensor.fov), float(spec.sensor.beams),
                           float(spec.sensor.noise), *mount], scenario=scenario, seed=int(seed), robot_index=int(index),
                   scan_rate_hz=1.0 / (params or PlannerParams()).dt)
    if spec.model == 'tractor_trailer':
        out.update(length=float(spec.length), trailer_length=float(spec.trailer_length),
                   hitch_offset=float(spec.hitch_offset))
    if spec.model == 'diff_drive':
        limits = params or PlannerParams()
        out.update(max_speed=float(limits.max_speed), max_turn_rate=float(limits.max_turn_rate))
    if spec.dynamics is not None:
        # A physics base: its wheel odometry drifts, so the true pose goes out as a localizer's (planner_params).
        out.update(dynamics=dynamics_parameter(spec), ground_truth_topic=GROUND_TRUTH_TOPIC, seed=int(seed),
                   robot_index=int(index))
    return out


GROUND_TRUTH_TOPIC = 'ground_truth'
"""A physics robot's true pose (relative: <ns>/ground_truth), the localization its planner reads."""


def dynamics_parameter(spec: RobotSpec) -> str:
    """The plant's `dynamics` parameter of a robot: its preset's name, or its mapping as JSON quoted for YAML
    (a command line's `-p dynamics:=VALUE` is read as YAML: quoted, a mapping stays the string the node parses)."""
    assert spec.dynamics is not None
    data = dynamics_data(spec.dynamics)
    return data if isinstance(data, str) else "'" + json.dumps(data, sort_keys=True) + "'"


def planner_params(scenario: Scenario, index: int, algorithm: str, seed: int, sim_time: bool,
                   realtime: bool = False) -> dict[str, Any]:
    spec = scenario.robots[index]
    out: dict[str, Any] = {'algorithm': algorithm, 'model': spec.model, 'robot_radius': float(spec.radius),
                           'seed': int(seed), 'seed_stream': index,
                           'control_rate_hz': 1.0 / scenario.planner.dt, 'use_sim_time': sim_time,
                           # Its goals are in map: no planner follows /tf (every plant's 50 Hz, N x N on a graph).
                           'goal_frames_from_tf': False,
                           # A simulated robot's pose is the truth (a physics base's: its true pose), as in fastep-sim.
                           'localization_tolerance': [0.0, 0.0], 'odometry_drift': [0.0, 0.0]}
    if spec.footprint is not None:
        # Nav2's form "[[x, y], ...]", quoted: `-p footprint:=VALUE` is read as YAML, and a list is not a string.
        out['footprint'] = "'" + json.dumps(spec.footprint.to_list()) + "'"
    if sim_time:
        out.update(lock_step=True, use_stamped_cmd_vel=True)   # exact lock step (fastep_ros.lock_step)
        if realtime:
            out['realtime'] = True   # ... planning on its thread, its latency counted
    if spec.model == 'tractor_trailer':
        out.update(length=float(spec.length), trailer_length=float(spec.trailer_length),
                   hitch_offset=float(spec.hitch_offset))
    out.update(_planner_overrides(scenario.planner))
    if spec.sensor is not None:
        out['scan_mode'] = 'required'   # its plant scans: a robot whose scans stop or cannot be used is held
        if any(spec.sensor.mount):
            out['laser_mount'] = [float(v) for v in spec.sensor.mount]   # its scans come in <ns>/laser
    if spec.model == 'diff_drive' and spec.goal_heading is None:
        out['goal_heading'] = 0   # the goal's orientation is any: the robot stops where it arrives, as in fastep-sim
    if spec.dynamics is not None:
        out['localization_topic'] = GROUND_TRUTH_TOPIC   # map -> base_link from the plant's true pose (amcl-like)
    return out


WALL_ROBOTS_PER_CORE = 4
"""Robots per CPU core from which, on wall time, planning a whole step in one control tick makes the tick long
(16 robots on 2 cores: a planner's control p99 5.4-6.9 ms against 3.9-4.7 ms with step_iterations 3; docs/benchmarks.md,
"A step plan spread over control ticks")."""
WALL_STEP_ITERATIONS = 3
"""step_iterations of such a launch, unless told (with 2 FAStep-Route's worst path among diff-drive robots in the
families benchmark grew from 1.19 to 1.43 times the optimum; with 3 to 1.22)."""


def step_budget(robots: int, cores: int, sim_time: bool, algorithm: str, params: PlannerParams,
                given: int | None = None) -> tuple[int, str]:
    """The planners' step_iterations for a launch, and a line for the terminal ('' for none). --step-iterations
    (`given`) decides when set; otherwise the scenario's, except on wall time with more than WALL_ROBOTS_PER_CORE
    robots per CPU core whose FAStep planners would plan each step whole in one control tick (step_iterations 0):
    then WALL_STEP_ITERATIONS. In lock step a long tick only slows the run and changes nothing: the scenario's."""
    if given is not None:
        return given, ''
    if sim_time or params.step_iterations or algorithm in ('aco', 'dwa', 'optimal') or \
            robots <= WALL_ROBOTS_PER_CORE * cores:
        return params.step_iterations, ''
    return WALL_STEP_ITERATIONS, (
        f'note: {robots} robots on {cores} CPU core(s) on wall time: each planner spreads a step plan over its control '
        f'ticks, {WALL_STEP_ITERATIONS} swarm iterations a tick (step_iterations; --step-iterations 0: each step '
        f'planned whole in the tick it is needed, as the paper)')


# ----------------------------------------------------------------------------------------------- the run

def _alone(monitor: Monitor) -> None:
    """Refuse to start beside another graph: look for one for DISCOVERY_WAIT (DDS takes a moment to see it)."""
    end = time.monotonic() + DISCOVERY_WAIT
    while True:
        monitor.check_alone(launchers=True)
        if time.monotonic() >= end:
            return
        monitor.spin(0.1)


def _await_recording(monitor: Monitor, procs: Processes, until: float, dt: float) -> None:
    """Hold the report to the run up to simulated time `until` and wait until fastep-record has taken it: the
    nodes are stopped next, and in lock step the recorder may lag OBSERVER_LAG ticks behind (at load 10 a recording
    ended 0.35 s before the report's trajectory did). Waits while the recorder's acknowledgements come, up to the
    clock one tick after `until` (by then the odometry stamped `until` was published); after END_WAIT wall seconds
    without one, says so in one line unless it has taken `until` itself."""
    target, acked, heard = until + dt, monitor.recorder_acked, time.monotonic()
    while monitor.recorder_acked < target - 1e-6 and procs.running('fastep-record'):   # (one that exited: no wait)
        if monitor.recorder_acked > acked:
            acked, heard = monitor.recorder_acked, time.monotonic()
        elif time.monotonic() - heard > END_WAIT:
            if acked >= until - 1e-6:   # a clock that stands at the run's end (a stopped plant): all there is
                break
            print(f'{PROG}: warning: the recording may end before the run: fastep-record took simulated time '
                  f'{max(acked, 0.0):.2f} s of {until:.2f} s and then nothing for {END_WAIT:g} s', file=sys.stderr)
            break
        monitor.spin(0.02)
    for robot in monitor.robots.values():   # what came in meanwhile is after the run's end
        robot.rows = [row for row in robot.rows if row[0] <= until + 1e-9]


def _wait(monitor: Monitor, procs: Processes, deadline: float, unready: Callable[[], str], what: str) -> None:
    """Spin until `unready()` says nothing ('' : ready); a LaunchError that says what is still missing at the
    deadline, or which process exited."""
    while why := unready():
        monitor.check_alone()
        dead = procs.dead()
        if dead:
            label, code = dead[0]
            raise LaunchError(f'{label} exited with code {code} while {what}')
        if time.monotonic() > deadline:
            raise LaunchError(f'timed out while {what}: {why}')
        monitor.spin(0.01)   # (each stage of the start is seen within 10 ms: make demo's start waits for 4 of them)


def not_ready(name: str, robot: RobotLive, goal_readers: int, goal_readers_needed: int, cmd_vel_readers_needed: int,
              names: set[str], recorded: Mapping[str, Any] | None) -> str:
    """Why robot `name` is not ready for its goal ('' when it is), from its planner's status and this monitor's
    view: the goal's readers (the planner, and the recorder when recording), the odometry heard here and by the
    planner, cmd_vel's readers (the plant, and the clock in lock step), the other robots followed, and the
    odometry recorded (`recorded`: fastep-record's topics, None when not recording)."""
    from msg_tools.interface import CMD_VEL, GOAL_POSE, ODOM, robot_topic

    status = robot.status
    message = status.get('message')
    if message is None:
        return f'no status from the planner of {name} yet'
    if message != 'idle':
        return f'the planner of {name} is {message}' + (f': {status["reason"]}' if status.get('reason') else '')
    if goal_readers < goal_readers_needed:
        return (f'{robot_topic(name, GOAL_POSE)} has {goal_readers} of {goal_readers_needed} readers (the planner'
                f'{", fastep-record" if goal_readers_needed > 1 else ""})')
    # Odometry is volatile: a plant this monitor has not matched yet when the clock starts would drive a run it
    # never sees (on a loaded machine, DDS matches endpoints seconds after the graph lists them). Plants publish
    # their start state until time starts: wait until it is heard here and by the planner.
    if not robot.rows:
        return f'no odometry on {robot_topic(name, ODOM)} heard by fastep-launch yet'
    if int(status.get('odom_heard', 0)) < 1:
        return f'the planner of {name} has heard no odometry yet'
    # Nor may a planner's commands go unheard: its plant (and the clock's lock step) must have matched.
    readers = int(status.get('cmd_vel_readers', 0))
    if readers < cmd_vel_readers_needed:
        return (f'{robot_topic(name, CMD_VEL)} has {readers} of {cmd_vel_readers_needed} readers (the plant'
                f'{", fastep-clock" if cmd_vel_readers_needed > 1 else ""})')
    missing = sorted(names - {name} - set(status.get('others', '').split()))
    if missing:
        return f'the planner of {name} does not follow {", ".join(missing)} yet'
    # And the recording holds the run from its start.
    if recorded is not None and robot_topic(name, ODOM) not in recorded:
        return f'fastep-record has not recorded {robot_topic(name, ODOM)} yet'
    return ''


def run(args: argparse.Namespace, scenario: Scenario, placement: Placement | None = None) -> int:
    from msg_tools.interface import CMD_VEL, GOAL_POSE, robot_topic

    sim_time = not args.no_clock
    timeout = args.timeout if args.timeout is not None else scenario.planner.max_sim_time
    # Before any participant of this launch exists: the launcher's own (the monitor's) and its processes'.
    profile = use_discovery_profile()
    procs = Processes(args.verbose, args.layout or default_layout(sim_time, len(scenario.robots)), args.executor,
                      placement)
    budget, note = step_budget(len(scenario.robots), usable_cores(), sim_time, args.algorithm, scenario.planner,
                               args.step_iterations)
    if note:
        print(note, flush=True)
    if budget != scenario.planner.step_iterations:
        scenario = dataclasses.replace(scenario, planner=dataclasses.replace(scenario.planner, step_iterations=budget))
    monitor: Monitor | None = None
    recording_followed = False   # the monitor follows the recorder's acknowledgements (lock step, --record)
    stopping: threading.Thread | None = None
    code = 1
    try:
        procs.start('fastep-map', 'map_server', '/', {'scenario': _scenario_arg(args.scenario),
                                                       'use_sim_time': sim_time, 'seed': int(args.seed)})
        for i, spec in enumerate(scenario.robots):
            procs.start(f'fastep-plant /{spec.name}', 'plant', f'/{spec.name}',
                        plant_params(spec, sim_time, scenario.planner, scenario=_scenario_arg(args.scenario),
                                     seed=args.seed, index=i))
            procs.start(f'fastep-planner /{spec.name}', 'planner', f'/{spec.name}',
                        planner_params(scenario, i, args.algorithm, args.seed, sim_time, args.realtime))
        if args.foxglove is not None:   # on wall time: not a /clock subscriber, nor in the lock step
            procs.start('fastep-foxglove', 'foxglove_bridge', '/', {'port': args.foxglove,
                                                                     'scenario': _scenario_arg(args.scenario)})
            print(f'live view: open ws://localhost:{args.foxglove} in Foxglove (Open connection)', flush=True)
        if args.record is not None:
            # Started before the goals and the clock, so the recording holds the whole run.
            procs.start('fastep-record', 'recorder', '/', {'output': str(args.record.resolve()),
                                                           'scenario': _scenario_arg(args.scenario),
                                                           'use_sim_time': sim_time, 'clock_ack': sim_time,
                                                           'clock_ack_period': ACK_TICKS * scenario.planner.dt})
        if sim_time:
            # The clock holds time 0 until the map, every plant and planner and, last, the monitor follow it.
            # Lock step: each tick of one control period waits for every planner's command stamped with it (each
            # planner acts on its plant's odometry of that tick), so simulated time never runs ahead of a busy node;
            # ticks as fast as --rtf asks (max_rate_hz not below it).
            procs.start('fastep-clock', 'clock', '/', {
                'rtf': float(args.rtf), 'step': scenario.planner.dt,
                'max_rate_hz': min(RATE_RANGE[1], max(400.0, float(args.rtf) / scenario.planner.dt)),
                # The recorder subscribes to /clock twice: for its own time, and to record it.
                'wait_for_subscribers': 2 + 2 * len(scenario.robots) + 2 * (args.record is not None),
                'sync_topics': [robot_topic(spec.name, CMD_VEL) for spec in scenario.robots],
                # ... and for the observers (this monitor, the recorder) to be at most OBSERVER_LAG ticks behind.
                'observer_topics': ['/fastep_launch/clock_ack'] + ['/recorder/clock_ack'] * (args.record is not None),
                'observer_lag': OBSERVER_LAG})
        procs.launch()   # the nodes above, in the processes of --layout: they import, then wait at their gates
        # Two launches on one domain drove each other's robots and clocks (one reported a 498 m path in a 50 m
        # map): look for another graph before any node of this launch joins DDS, and keep looking (run's loop,
        # _wait). The processes import meanwhile.
        monitor = Monitor(scenario)
        _alone(monitor)
        monitor.connect()
        monitor.expected = watched_topics(scenario, sim_time)
        procs.open_gates()
        robots = monitor.robots
        names = set(robots)
        deadline = time.monotonic() + args.startup_timeout

        goal_readers = 1 + (args.record is not None)   # the planner, and the recorder when recording

        def planners_ready() -> str:
            for name, robot in robots.items():
                why = not_ready(name, robot, monitor.goal_pubs[name].get_subscription_count(), goal_readers,
                                1 + sim_time, names, monitor.recorded if args.record is not None else None)
                if why:
                    return why
            return ''

        _wait(monitor, procs, deadline, planners_ready,
              'waiting for the planners to see the world and each other, and for every odometry topic')
        monitor.check_alone(now=True)
        monitor.send_goals()
        sent = time.monotonic()

        def goals_taken() -> str:
            nonlocal sent
            if time.monotonic() - sent > 1.0:  # a goal can be lost only if the planner was not yet matched
                monitor.send_goals()
                sent = time.monotonic()
            for name, robot in robots.items():
                if robot.status.get('message') in (None, 'idle'):
                    return f'the planner of {name} has not taken its goal'
                # ... and recorded: a recorder whose end of the goal's connection matched after the clock started got
                # the (latched) goal then, and fastep-report timed the run from then (1.45 s short in a make demo).
                if args.record is not None and robot_topic(name, GOAL_POSE) not in monitor.recorded:
                    return f'fastep-record has not recorded {robot_topic(name, GOAL_POSE)} yet'
            return ''

        _wait(monitor, procs, deadline, goals_taken, 'sending the goals')
        if sim_time:
            monitor.follow_clock(ACK_TICKS * scenario.planner.dt, recorder=args.record is not None)
            recording_followed = args.record is not None
            monitor.sim_now = 0.0
        t0 = monitor.now()
        pace = f'simulated time at rtf {args.rtf:g} at most' if sim_time else 'wall time'
        print(f'{scenario.name}: {len(robots)} robot(s) on their way ({args.algorithm}, seed {args.seed}, {pace})',
              flush=True)
        if args.plot is not None:
            # matplotlib's import (0.25 s) while the run goes, not after it: the graph's process has a core of its own.
            threading.Thread(target=importlib.import_module, args=('msg_tools.plots',), name='import-plots',
                             daemon=True).start()
        progress = Progress(PROG, len(robots), enabled=not args.no_progress)
        progress.start()
        last_now, last_change = monitor.now(), time.monotonic()
        while any(not r.outcome for r in robots.values()):
            monitor.spin(0.02)
            monitor.check_alone()
            now = monitor.now() - t0
            if now != last_now:
                last_now, last_change = now, time.monotonic()
            stalled = time.monotonic() - last_change > STALL
            for robot in robots.values():
                if robot.outcome:
                    continue
                message = robot.status.get('message')
                if message in ('arrived', 'failed'):
                    # The planner stamps its status with its own clock: that is when it happened, however late
                    # this monitor gets to the message.
                    try:
                        began = robot.started_at if robot.started_at is not None else t0
                        stamped = float(robot.status.get('since', robot.status['t'])) - began
                    except (KeyError, ValueError):
                        stamped = now
                    robot.outcome, robot.end_time = message, stamped
                robot.reason = robot.status.get('reason', '')
            dead = procs.dead()
            if dead:
                label, rc = dead[0]
                for robot in robots.values():
                    if not robot.outcome:
                        robot.outcome, robot.reason = 'failed', f'{label} exited with code {rc}'
            if now > timeout or stalled:
                for robot in robots.values():
                    if not robot.outcome:
                        robot.outcome = 'timeout'
                        why = f'simulated time stopped at {now:.1f} s' if stalled else \
                            f'not arrived within {timeout:g} s'
                        robot.reason = f'{why} ({robot.status.get("message")}: {robot.status.get("reason", "")})'
            outcomes = [r.outcome for r in robots.values()]
            progress.update(outcomes.count('arrived'), len(outcomes) - outcomes.count('') - outcomes.count('arrived'),
                            now)
        progress.close()
        # Let the last odometry in before reporting: at least 0.2 s (in lock step, where this monitor is at most
        # OBSERVER_LAG ticks behind the graph, 0.05 s), and until every robot's reaches the time its run ended (at a
        # high --rtf this monitor's odometry queue lagged its status messages by seconds of simulated time), for
        # END_WAIT wall seconds at most.
        short, end = time.monotonic() + (0.05 if sim_time else 0.2), time.monotonic() + END_WAIT

        def behind() -> bool:
            return any(r.end_time is not None and (not r.rows or r.rows[-1][0] < r.end_time - 1e-6 +
                                                   (r.started_at if r.started_at is not None else t0))
                       for r in robots.values())
        while time.monotonic() < short or (behind() and time.monotonic() < end):
            monitor.spin(0.02)
        if recording_followed:
            _await_recording(monitor, procs, monitor.now(), scenario.planner.dt)
        # The nodes stop (the recorder finishes its file) while the report is written and drawn.
        stopping = threading.Thread(target=procs.stop, name='stop-nodes')
        stopping.start()
        collided, written = report(PROG, args, scenario, monitor.robots, t0, sim_time)
        code = 0 if all(r.outcome == 'arrived' for r in robots.values()) and not collided else 1
        if not written:
            code = 2
    except GraphConflict as exc:
        code = fail(PROG, exc)
    except LaunchError as exc:
        fail(PROG, exc)
        code = 1
    except KeyboardInterrupt:
        print(f'{PROG}: interrupted; stopping every node', file=sys.stderr)
        code = 1
        if monitor is not None and recording_followed and procs.running('fastep-record'):
            monitor.await_recording(monitor.now(), INTERRUPT_WAIT)   # the recording holds the run up to here
    finally:
        if stopping is not None:
            stopping.join()
        if monitor is not None:
            monitor.close()
        procs.stop()   # (nothing left to stop after `stopping`)
        if profile is not None:
            os.environ.pop(PROFILE_ENV[0], None)
            profile.unlink(missing_ok=True)
    # Not when another graph was seen first: the recorder then exited at its gate, before it began.
    if procs.opened and any(label == 'fastep-record' for label, _ in procs.items):
        assert args.record is not None
        # "wrote" only when the recorder finished the file itself (exit 0); a recorder that failed (a full disk:
        # exit 1) or was killed left at most its complete chunks.
        recorder_code = next((proc.returncode for label, proc in procs.items if label == 'fastep-record'), None)
        if recorder_code == 0 and args.record.is_file():
            print(f'wrote {args.record}')
        elif args.record.is_file():
            fail(PROG, f'the recorder failed (exit code {recorder_code}): {args.record} is incomplete '
                       f'(fastep-recover rewrites what it holds)')
            code = code or 1
        else:
            fail(PROG, f'the recorder wrote no {args.record}')
            code = code or 1
    return code


# Formats matplotlib draws with the backends it always has (Agg, PDF, PS, SVG): --plot's usual suffixes are checked
# without importing it (0.25 s before any node starts); any other suffix is asked of matplotlib.
DRAWN_FORMATS = frozenset({'eps', 'jpeg', 'jpg', 'pdf', 'png', 'ps', 'svg', 'svgz', 'tif', 'tiff', 'webp'})


def _output_problem(path: Path, plot: bool = False) -> str:
    """Why `path` cannot be written as an output file ('' if it can). Tried, not guessed from permissions (root
    passes every check of those): missing folders are created, as the run would, and the file is opened for
    appending (an existing one is left as it is, a new one removed again)."""
    if plot and path.suffix and path.suffix[1:].lower() not in DRAWN_FORMATS:
        from matplotlib.backend_bases import FigureCanvasBase
        formats = FigureCanvasBase.get_supported_filetypes()
        if path.suffix[1:].lower() not in formats:
            return f'cannot draw a {path.suffix} file (formats: {", ".join(sorted(formats))})'
    if path.is_dir():
        return 'is a directory'
    existed = path.exists()
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with open(path, 'ab'):
            pass
        if not existed:
            path.unlink()
    except OSError as exc:
        where = f' ({exc.filename})' if exc.filename and str(exc.filename) != str(path) else ''
        return f'cannot be written: {exc.strerror or exc}{where}'
    return ''


def _scenario_arg(source: str) -> str:
    path = Path(source)
    return str(path.resolve()) if path.is_file() else source


def _request_stop(signum: int, frame: Any) -> None:
    """Ctrl-C / SIGTERM only set STOP. Python's own handler raised KeyboardInterrupt wherever the main thread
    was, inside rclpy's executor too, which then waited forever on shutdown (a test saw the launcher hang after
    Ctrl-C), and a second Ctrl-C during the shutdown of the nodes gave a traceback."""
    STOP.set()


def main(argv: Sequence[str] | None = None, placement: Placement | None = None) -> int:
    """fastep-launch with `argv`; `placement` puts processes on other computers (fastep_ros.processes)."""
    return guard(PROG, lambda: _main(argv, placement))


def _main(argv: Sequence[str] | None, placement: Placement | None = None) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    if not RTF_RANGE[0] <= args.rtf <= RTF_RANGE[1]:
        parser.error(f'--rtf must be in [{RTF_RANGE[0]:g}, {RTF_RANGE[1]:g}], got {args.rtf:g}')
    if args.timeout is not None and not (math.isfinite(args.timeout) and args.timeout > 0.0):
        parser.error(f'--timeout must be > 0, got {args.timeout:g}')
    if args.no_clock and args.rtf != 1.0:
        parser.error('--no-clock runs on wall time: --rtf cannot be used with it')
    if args.no_clock and args.realtime:
        parser.error('--no-clock runs on wall time, where planning latency always counts: --realtime is for lock step')
    scenario = load_scenario(args.scenario)  # a FastepError: guard's one line, exit 2
    problem = graph_problem(scenario)
    if problem:
        raise ScenarioError(f'scenario {args.scenario!r}: {problem}')
    for i, spec in enumerate(scenario.robots):
        problem = robot_name_problem(spec.name)
        if problem:
            raise ScenarioError(f'scenario {args.scenario!r}: robots[{i}].name {spec.name[:40]!r}'
                                f'{"..." if len(spec.name) > 40 else ""} cannot name a robot on the ROS graph: '
                                f'{problem}')
        check_drives(args.algorithm, spec.model, spec.name)   # dwa and a tractor-trailer: one line, nothing started
    # Outputs are checked before anything starts: a run is not wasted on a file that cannot be written.
    for flag, path in (('--json', args.json), ('--plot', args.plot), ('--record', args.record)):
        if path is not None:
            problem = _output_problem(path, plot=flag == '--plot')
            if problem:
                parser.error(f'{flag} {path}: {problem}')
    if args.foxglove is not None and (problem := tcp_port_problem(args.foxglove)):
        parser.error(f'--foxglove {args.foxglove}: {problem}')
    STOP.clear()
    previous = {sig: signal.signal(sig, _request_stop) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        return run(args, scenario, placement)
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)


def cli() -> NoReturn:
    """The console script (and `python -m fastep_ros.launch`): main(), then the process ends at once. Python's
    teardown of a process that held a DDS participant took 0.17-0.25 s here, a twentieth of make demo's whole
    command, for nothing a run needs: the nodes' processes have finished their files, the launcher's files are
    closed, and stdout and stderr are flushed first."""
    code = main()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):   # a closed pipe: nothing more can be said
            pass
    os._exit(code)


if __name__ == '__main__':
    cli()
