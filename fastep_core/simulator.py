"""In-process simulator: every robot of a scenario, its navigator and its kinematic model in one loop.

It mirrors the ROS graph (a plant integrates each robot, a navigator commands it, each robot sees the others
as moving obstacles) without DDS, so experiments run fast and are reproducible: each robot's swarm draws from
its own Generator spawned from the run's seed.

A v2 world (fastep_core/dynamic_world.py): movers move every tick; planners are given the map (known still
obstacles, misplaced ones where the map says) and see known movers, at their positions (with their map error)
and velocities at the start of each tick, as moving obstacles beside the other robots ('mover K'); unknown
obstacles are absent from everything a planner is given, unless a robot's own `sensor` shows them: such a
robot scans the truth every tick and plans in what it believes (fastep_core/perception/robot.py). Collisions
and min_clearance are judged against the truth: every still obstacle where it is, every mover where it is at
each step's time.

Each robot has a plant (fastep_core/dynamics/plant.py): its kinematic model integrated as commanded, or, for a
robot whose spec has `dynamics`, a differential-drive base with mass in MuJoCo behind its own controller. A
planner is given the plant's TRUE pose as its state (as a perfect localizer would give it) and the plant's
measured velocity (its odometry's twist) before the tick's command; trajectories, path length and collisions are
the true state's; the other robots see its true map-frame velocity. A robot with mass goes through the control loop
as on a robot (fastep_core/planning/control.py: the velocity smoother, closed on its odometry), with or without
realtime; without, its plan is each tick's own. A kinematic plant's measured velocity is the
command it last applied, so kinematic runs are what they were before plants, bit for bit.

`pose_error` (off by default): each robot with a sensor is localized off the truth (perception/uncertainty.py,
PoseError: a seeded offset and drift, each robot its own); its navigator is given the estimate as its state and its
scans are placed there, while the plant, the scans themselves and every judgement stay the truth's.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace
from typing import Callable

import numpy as np
from numpy.typing import NDArray

from fastep_core.dynamic_world import DynamicWorld, map_generator
from fastep_core.dynamics.plant import Plant, make_plant, odometry_generator
from fastep_core.errors import GoalError
from fastep_core.metrics import trajectory_margins
from fastep_core.perception.belief import Belief
from fastep_core.perception.robot import SensingRobot
from fastep_core.perception.uncertainty import PoseError
from fastep_core.planning.algorithms import make_navigator
from fastep_core.planning.control import ControlTick, Plan, PlanLatency
from fastep_core.planning.navigator import Mode, Navigator
from fastep_core.planning.others import OtherRobot, OtherRobots
from fastep_core.scenario import Scenario

__all__ = ['RobotRun', 'Run', 'Tick', 'simulate']

FloatArray = NDArray[np.float64]
SAMPLE_SPACING = 0.1  # metres of travel between trajectory samples (DESIGN: at least every 0.1 m)


@dataclass
class RobotRun:
    """What happened to one robot in one run (the JSON of fastep-sim, plus series for figures)."""

    name: str
    model: str
    reached: bool = False
    collided: bool = False
    path_length: float = 0.0
    sim_time: float | None = None
    compute_time: float = 0.0
    plan_time: float = 0.0        # the part of compute_time spent inside the step optimizer
    min_clearance: float = math.inf
    activations: int = 0
    escapes: int = 0              # trap escapes (planning/navigator.py)
    manoeuvres: int = 0           # tractor-trailer manoeuvres planned, replans included (recovery/manoeuvre_search.py)
    status: str = ''
    trajectory: list[list[float]] = field(default_factory=list)
    waypoints: list[list[float]] = field(default_factory=list)
    cost: list[tuple[float, float]] = field(default_factory=list)        # (t, fitness of the step in use)
    velocity: list[tuple[float, float, float]] = field(default_factory=list)  # (t, vx, vy) map frame
    belief: Belief | None = None  # a robot with a sensor: what it believed at the end (figures; not in the JSON)
    realtime: PlanLatency | None = None   # --realtime: ticks without a fresh plan, the longest planning latency

    def to_json(self) -> dict[str, object]:
        return {
            'name': self.name, 'model': self.model, 'reached': self.reached, 'collided': self.collided,
            'path_length': round(self.path_length, 6),
            'sim_time': None if self.sim_time is None else round(self.sim_time, 6),
            'compute_time': round(self.compute_time, 6), 'plan_time': round(self.plan_time, 6),
            'min_clearance': None if math.isinf(self.min_clearance) else round(self.min_clearance, 6),
            'activations': self.activations, 'escapes': self.escapes, 'manoeuvres': self.manoeuvres,
            'status': self.status,
            'waypoints': [[round(v, 6) for v in w] for w in self.waypoints],
            'trajectory': [[round(v, 6) for v in row] for row in self.trajectory],
            **({} if self.realtime is None else {'realtime': self.realtime.to_json()}),
        }


@dataclass
class Run:
    seed: int
    algorithm: str
    robots: list[RobotRun]

    def to_json(self) -> dict[str, object]:
        return {'seed': self.seed, 'robots': [r.to_json() for r in self.robots]}


@dataclass(frozen=True)
class Tick:
    """What an observer sees after each simulated step of one robot (used to record runs)."""

    t: float
    name: str
    state: FloatArray
    command: FloatArray
    velocity: FloatArray
    navigator: Navigator
    belief: Belief | None = None   # what a robot with a sensor believes (fastep_core/perception)


def simulate(scenario: Scenario, algorithm: str = 'fastep', seed: int = 0,
             observer: Callable[[Tick], None] | None = None, realtime: float | None = None,
             pose_error: PoseError | None = None) -> Run:
    """Run every robot of the scenario until each has arrived, failed, or max_sim_time has passed.

    realtime (FACTOR, >= 0): planning is not free. A planning pass (perception of the scan and Navigator.update)
    starts on a tick's state and its plan reaches the control loop only once its wall time x FACTOR has passed on
    the simulated clock, at the next tick at the earliest; every tick meanwhile drives on the plan it has
    (fastep_core/planning/control.py), as the planner node does. Not deterministic: it depends on the machine.
    None (the default): the clock waits for the planner, every tick plans, same seed same run.

    pose_error: robots with a sensor localized off the truth (module docstring); None: at the truth.

    min_clearance is the smallest margin a robot kept (fastep_core.metrics.trajectory_margins): distance from
    its reference point to the nearest obstacle surface minus its radius (a robot with a footprint: from its
    outline placed at its pose), or to another robot's centre minus both radii, measured at every robot's
    position after each step; negative means it collided.
    """
    params = scenario.planner
    world = scenario.world                     # the true still world
    specs = scenario.robots
    truth = DynamicWorld(world.workspace, scenario.obstacle_specs)
    # The planner's map: a v1 world is its own map (the same object, as before); a v2 one is drawn from the seed.
    planner_map = None if scenario.is_static else truth.planner_map(map_generator(seed))
    planner_world = world if planner_map is None else planner_map.world
    streams = np.random.SeedSequence(seed).spawn(len(specs))
    navigators = [make_navigator(algorithm, spec, spec.radius, planner_world, params, np.random.default_rng(s))
                  for spec, s in zip(specs, streams)]
    # Robots with a sensor scan the truth each tick and plan in what they believe (fastep_core/perception).
    errors = [None if pose_error is None or spec.sensor is None else replace(pose_error, robot=i)
              for i, spec in enumerate(specs)]
    senses = [None if spec.sensor is None else SensingRobot(spec.sensor, spec.model, i, truth, nav, seed, errors[i])
              for i, (spec, nav) in enumerate(zip(specs, navigators))]
    states = [np.array(spec.start, dtype=float) for spec in specs]
    plants: list[Plant] = [make_plant(spec.model, nav.model, state, spec.dynamics,
                                      None if spec.dynamics is None else odometry_generator(seed, i))
                           for i, (spec, nav, state) in enumerate(zip(specs, navigators, states))]
    velocities = [np.zeros(2) for _ in specs]
    runs = [RobotRun(spec.name, spec.model) for spec in specs]
    latencies = [PlanLatency(realtime) for _ in specs] if realtime is not None else None
    controls = [ControlTick(nav) for nav in navigators] if realtime is not None else None
    # A robot with mass is driven as on a robot: each tick's plan through the control loop (smoother, guard,
    # closed loop on its odometry: planning/control.py), the clock still waiting for the plan in lock step.
    smoothed = [ControlTick(nav) if realtime is None and spec.dynamics is not None else None
                for nav, spec in zip(navigators, specs)]
    for run, latency in zip(runs, latencies or ()):
        run.realtime = latency
    for nav, spec, run, state in zip(navigators, specs, runs, states):
        try:
            nav.set_goal(spec.goal, heading=spec.goal_heading)
        except GoalError as exc:   # a misplaced obstacle covers the goal on the map: the robot refuses it
            nav.fail(f'goal refused on the map: {exc}')
        run.trajectory.append([0.0, *state.tolist()])
    last_sample = [s[:2].copy() for s in states]
    pending: list[list[float] | None] = [None] * len(specs)
    dt = params.dt
    n_ticks = int(math.ceil(params.max_sim_time / dt))
    by_name = sorted(range(len(specs)), key=lambda k: specs[k].name)   # robot indices in the order of their names
    name_rank = [by_name.index(k) for k in range(len(specs))]          # each robot's place in that order
    step_times: list[float] = []               # every robot's position after each step, for the margins
    step_positions: list[list[float]] = []     # (x, y) of robot 0, 1, ... in one row
    posed = [i for i, spec in enumerate(specs) if spec.footprint is not None]   # judged by their outline
    step_headings: list[list[float]] = []      # ... and their headings

    def mode(i: int) -> Mode:
        """Where robot i stands: its navigator's mode, or with realtime the mode of the plan it drives on."""
        if latencies is None:
            return navigators[i].mode
        plan = latencies[i].plan
        return Mode.IDLE if plan is None else plan.mode

    for k in range(n_ticks):
        t = k * dt
        active = [mode(i) not in (Mode.ARRIVED, Mode.FAILED) for i in range(len(specs))]
        if not any(active):
            break
        commands = []
        # Every robot sees the others as they are at the start of the tick: made once, viewed by each robot.
        robots = [OtherRobot(spec.name, (state[0], state[1]), (velocity[0], velocity[1]), spec.radius)
                  for spec, state, velocity in zip(specs, states, velocities)]
        # In the order of their names, as a planner node lists the robots it follows (it hears of them in
        # whatever order DDS discovers them): the order of a sum decides its last bits, and so a near tie.
        seen_robots = [robots[k] for k in by_name]
        if planner_map is not None:   # known movers where the map reports them now, seen by every robot
            robots += planner_map.others(t)
            seen_robots += robots[len(specs):]
        named_views = OtherRobots.views(seen_robots, len(specs))
        views = [named_views[rank] for rank in name_rank]
        for i, nav in enumerate(navigators):
            if not active[i]:
                commands.append(np.zeros(2))
                continue
            start = time.perf_counter()
            sense = senses[i]
            error = errors[i]
            state = states[i] if error is None else error.estimate(states[i])   # where it believes it is
            estimate = None if error is None else state
            measured = plants[i].measured_velocity()   # the odometry's twist, before this tick's command
            control = smoothed[i]
            if control is not None:
                seen = views[i] if sense is None else \
                    sense.sense(nav, t, states[i], views[i], robots[:len(specs)], estimate)
                if sense is not None:
                    nav.take_perception(replace(nav.guard_inputs, seen=sense.recent.seen()))
                plan = Plan.of(nav, t, nav.update(t, state, seen, velocity=measured), seen[len(views[i]):])
                commands.append(control.command(t, state, views[i], plan, dt, velocity=measured))
            elif latencies is None or controls is None:
                seen = views[i] if sense is None else \
                    sense.sense(nav, t, states[i], views[i], robots[:len(specs)], estimate)
                commands.append(nav.update(t, state, seen, velocity=measured))
            else:
                latency = latencies[i]
                latency.take(t)
                if latency.idle:   # the next pass starts on this tick's state
                    seen = views[i] if sense is None else \
                        sense.sense(nav, t, states[i], views[i], robots[:len(specs)], estimate)
                    if sense is not None:   # backing up only where its scans saw free space
                        nav.take_perception(replace(nav.guard_inputs, seen=sense.recent.seen()))
                    plan = Plan.of(nav, t, nav.update(t, state, seen, velocity=measured), seen[len(views[i]):])
                    latency.submit(plan, t, time.perf_counter() - start)
                commands.append(controls[i].command(t, state, views[i], latency.plan, dt, velocity=measured))
            runs[i].compute_time += time.perf_counter() - start
            if mode(i) is Mode.ARRIVED:
                runs[i].reached, runs[i].sim_time = True, t
                active[i] = False
                # It stands still from now on (a plant publishes the zero twist it is sent): its last velocity,
                # kept, made the others see a parked robot as a moving one and never plan round it.
                velocities[i] = np.zeros(2)
        t_next = t + dt
        for i, nav in enumerate(navigators):
            if not active[i]:
                continue
            start = time.perf_counter()
            plant = plants[i]
            plant.step(commands[i], dt)
            new_state = plant.state
            # The others see it as it truly moves (kinematic: the twist it drives at, along its new heading).
            velocities[i] = plant.velocity()
            runs[i].compute_time += time.perf_counter() - start
            # Distances in Python floats through np.hypot (math.hypot's last bit can differ, and runs are compared
            # bit for bit): the same numbers as numpy's arrays gave, without making two arrays for two numbers.
            values = new_state.tolist()
            x, y = values[0], values[1]
            x0, y0 = states[i][:2].tolist()
            runs[i].path_length += float(np.hypot(x - x0, y - y0))
            states[i] = new_state
            run = runs[i]
            run.cost.append((t_next, nav.cost))
            run.velocity.append((t_next, float(velocities[i][0]), float(velocities[i][1])))
            # Trajectory samples at most SAMPLE_SPACING apart: when the newest point is too far from the
            # last sample, the point before it is sampled first.
            row = [t_next, *values]
            before = pending[i]
            sample_x, sample_y = last_sample[i].tolist()
            gap = np.hypot(x - sample_x, y - sample_y)
            if gap > SAMPLE_SPACING and before is not None:
                run.trajectory.append(before)
                last_sample[i] = np.array(before[1:3])
                pending[i] = None
                gap = np.hypot(x - before[1], y - before[2])
            if gap >= SAMPLE_SPACING:
                run.trajectory.append(row)
                last_sample[i] = new_state[:2].copy()
                pending[i] = None
            else:
                pending[i] = row
            if observer is not None:
                sense = senses[i]
                observer(Tick(t_next, specs[i].name, new_state, commands[i], velocities[i], nav,
                              None if sense is None else sense.belief))
        step_times.append(t_next)
        step_positions.append([c for s in states for c in s[:2].tolist()])
        if posed:
            step_headings.append([float(states[i][2]) for i in posed])

    # Robots that have stopped (arrived, failed) keep their place among the others.
    times = np.array(step_times)
    positions = np.array(step_positions).reshape(len(times), len(specs), 2)
    tracks = [np.column_stack([times, positions[:, i]]) for i in range(len(specs))]
    headings = np.array(step_headings).reshape(len(times), len(posed))
    for k, i in enumerate(posed):   # rows (t, x, y, heading): the outline placed at each step's pose
        tracks[i] = np.column_stack([tracks[i], headings[:, k]])
    margins = trajectory_margins(tracks, [spec.radius for spec in specs], world.obstacles, truth.movers,
                                 [spec.footprint for spec in specs] if posed else None).overall
    for i, (nav, run) in enumerate(zip(navigators, runs)):
        run.min_clearance = float(margins[i])
        run.collided = bool(margins[i] < 0.0)
        last = pending[i]
        if last is not None:
            run.trajectory.append(last)
        adopted = None if latencies is None else latencies[i].plan
        if adopted is not None and adopted.mode in (Mode.ARRIVED, Mode.FAILED):
            run.status = f'{adopted.mode.value}: {adopted.reason}'
        else:
            if nav.mode not in (Mode.ARRIVED, Mode.FAILED) or latencies is not None:
                nav.fail(f'not arrived within max_sim_time={params.max_sim_time:g} s')
            run.status = f'{nav.mode.value}: {nav.reason}'
        run.activations = nav.activations
        run.escapes = nav.escapes
        run.manoeuvres = nav.manoeuvres
        run.plan_time = nav.plan_time
        run.waypoints = [w.tolist() for w in nav.plan]
        sense = senses[i]
        run.belief = None if sense is None else sense.belief
    return Run(seed, algorithm, runs)
