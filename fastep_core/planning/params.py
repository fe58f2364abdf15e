"""Planner parameters: Table 1 of the paper plus what a navigation stack needs and the paper leaves open.

Each field carries a description, a valid range, a unit and a component (the part of the planner it sets); the
ROS planner node declares exactly these as ROS parameters, and a scenario's top-level `planner:` mapping
overrides them by name.
"""

from __future__ import annotations

import math
import reprlib
from dataclasses import dataclass, field, fields, replace
from typing import Any, Mapping

from fastep_core.errors import ParameterError
from fastep_core.planning.limits import LIMIT_NAMES, Limits, limit_problem

__all__ = ['PlannerParams']


# A bad value is shown within bounds: the repr of a hostile one (a YAML alias bomb's 10^9 shared items) never ends.
_shown = reprlib.Repr()
_shown.maxlevel, _shown.maxlist, _shown.maxdict = 1, 3, 3
_shown.maxstring = _shown.maxother = _shown.maxlong = 40


def _show(value: Any) -> str:
    if isinstance(value, int) and value.bit_length() > 128:   # repr() refuses ints of over 4300 digits
        return f'an integer of {value.bit_length()} bits'
    return _shown.repr(value)


def _is_finite_number(value: Any) -> bool:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return False
    try:
        return math.isfinite(value)
    except OverflowError:   # an int too large for a float
        return False


def _p(default: float | int, description: str, low: float, high: float = math.inf, *, unit: str = '',
       component: str) -> Any:
    """A field with its description, valid range, unit ('' for a count or a ratio) and component: the part of the
    planner it sets, its section of the parameter reference (fastep_ros.reference)."""
    return field(default=default, metadata={'description': description, 'range': (low, high), 'unit': unit,
                                            'component': component})


@dataclass(frozen=True)
class PlannerParams:
    """Every tunable of FAStep-Kinematic, ACO-Kinematic and DWA, with the paper's Table 1 as defaults."""

    # Stepping Ahead Firefly swarm (Table 1, rows 1-5; gamma from the authors' code).
    n_fireflies: int = _p(50, 'fireflies in the swarm (Table 1: 50)', 2, 10_000, component='swarm')
    gamma: float = _p(1.0, 'light absorption coefficient (authors\' code: 1)', 0.0, component='swarm')
    beta0: float = _p(2.0, 'attraction at distance zero (Table 1: 2)', 0.0, component='swarm')
    alpha: float = _p(0.2, 'random-move scale, fraction of the search box (Table 1: 0.2)', 0.0, component='swarm')
    alpha_damping: float = _p(0.8, 'alpha multiplier per iteration (Table 1: 0.8)', 0.0, 1.0, component='swarm')
    max_iter: int = _p(30, 'swarm iterations per step at most', 1, 10_000, component='swarm')
    patience: int = _p(3, 'stop the swarm after this many iterations without improvement', 1, 10_000, component='swarm')
    tol: float = _p(1e-4, 'a swarm iteration improves only if the best fitness drops by more than this '
                          '(with c = 0.01, 1e-4 is 1 cm closer to the goal)', 0.0, component='swarm')
    attraction_sample: int = _p(0, 'FAStep attracts each firefly to at most this many brighter fireflies, drawn at '
                                   'random every iteration (fewer candidates per iteration; a departure from the '
                                   'paper); 0: to all of them, as the paper', 0, 10_000, component='swarm')
    merged_moves: int = _p(0, 'FAStep evaluates each iteration\'s attraction and stepping-ahead candidates in one '
                              'call, stepping ahead of the brightest firefly at the iteration\'s start instead of '
                              'after the attraction moves (a quarter less CPU per step plan, the same fitness '
                              'reached; a departure from the paper): 1; 0: two calls, as the paper', 0, 1,
                           component='swarm')
    step_iterations: int = _p(0, 'swarm iterations of a FAStep step plan per control tick at most: a plan that needs '
                                 'more is finished on the next ticks while the robot drives on toward its last target '
                                 '(a bound on a control tick\'s work among many robots; with 3 a plan takes 1-4 ticks, '
                                 'at most max_iter / step_iterations; ACO_R plans ignore it); 0: the whole plan in the '
                                 'tick it is needed, as the paper', 0, 10_000, component='swarm')
    # Step fitness f = a/f1 + b/f2 + c*d (eq. 10; Table 1 rows 6-8).
    a: float = _p(0.18, 'obstacle safety weight a, paper range [0.1, 1]', 0.0, component='swarm')
    b: float = _p(0.18, 'robot safety weight b, paper range [0.1, 1]', 0.0, component='swarm')
    c: float = _p(0.01, 'goal convergence weight c, paper range [1e-5, 0.01]', 0.0, component='swarm')
    # Kinematic controller gains (Table 1 rows 9-10).
    alpha1: float = _p(0.1, 'point-mass x gain: dx/dt = alpha1 (x1 - x)', 1e-6, unit='1/s', component='controller')
    alpha2: float = _p(0.1, 'point-mass y gain: dy/dt = alpha2 (y1 - y)', 1e-6, unit='1/s', component='controller')
    speed_gain: float = _p(0.1, 'tractor-trailer speed gain: v = speed_gain * distance', 1e-6,
                           unit='1/s', component='controller')
    max_speed: float = _p(1.0, 'speed limit; 0 means unlimited', 0.0, unit='m/s', component='safety')
    # A differential-drive base (kinematics/diff_drive.py): its law's turn gain and the base's limits. Defaults:
    # Nav2's TurtleBot3 DWB acceleration limits (2.5 m/s^2, 3.2 rad/s^2) and a TurtleBot3's turn rate (1.8-2.8).
    turn_gain: float = _p(2.0, 'diff_drive turn gain k2: omega = k2 alpha + ...', 1e-6,
                          unit='1/s', component='controller')
    max_turn_rate: float = _p(2.0, 'diff_drive turn-rate limit |omega|; 0 means unlimited', 0.0,
                              unit='rad/s', component='safety')
    max_acceleration: float = _p(2.5, 'acceleration and braking limit |dv/dt| of the diff_drive controller and of '
                                      'the velocity smoother (planning/safety/smoother.py; a point mass: of its '
                                      'velocity vector); 0 means unlimited', 0.0, unit='m/s^2', component='safety')
    max_turn_acceleration: float = _p(3.2, 'turn acceleration limit |domega/dt| of the diff_drive controller and of '
                                           'the velocity smoother; 0 means unlimited', 0.0,
                                      unit='rad/s^2', component='safety')
    # The velocity smoother, the last stage before cmd_vel (planning/safety/smoother.py), and backing up
    # (planning/recovery/back_up.py). The default reverse speed is the backing-up recovery's (BACKUP_SPEED).
    max_reverse_speed: float = _p(0.25, 'a steered robot (diff_drive, tractor_trailer) never reverses faster than '
                                        'this: the velocity smoother caps v >= -max_reverse_speed, and the backing-up '
                                        'recovery moves at 0.25 m/s or this if lower; 0 means unlimited',
                                  0.0, unit='m/s', component='safety')
    emergency_deceleration: float = _p(5.0, 'the guard\'s emergency stop brakes at this, every other '
                                             'command at max_acceleration: at least max_acceleration (default twice '
                                             'its default); 0: the stop is immediate', 0.0,
                                       unit='m/s^2', component='safety')
    min_approach_speed: float = _p(0.3, 'the kinematic controllers (eq. 12 / 13) drive at least this fast toward a '
                                        'waypoint or the goal, capped at max_speed and at the distance left per '
                                        'tick, so a robot arrives in bounded time where speed = gain x distance '
                                        'alone slows down exponentially (with Table 1\'s gain 0.1, 19 s to cover '
                                        'a 2 m step); 0: the paper\'s gains alone (Table 2 runs with 0)',
                                  0.0, 100.0, unit='m/s', component='controller')
    # What the paper leaves open: detection range, step size, tolerances, time step.
    sensing_range: float = _p(3.0, 'epsilon of eq. 11: obstacles whose surface is nearer are detected', 0.0,
                              unit='m', component='perception')
    detection_interval: float = _p(0.1, 'obstacle detection reruns after this much travel; every tick near '
                                   'other robots', 0.0, unit='m', component='perception')
    step_radius: float = _p(2.0, 'largest distance from the robot to a planned waypoint', 0.05,
                            unit='m', component='swarm')
    clearance_margin: float = _p(0.2, 'extra clearance beyond the robot radius for planned waypoints', 0.0,
                                 unit='m', component='route')
    goal_tolerance: float = _p(0.1, 'the goal counts as reached within this distance', 1e-4,
                               unit='m', component='controller')
    yaw_goal_tolerance: float = _p(0.25, 'a goal with a heading (diff_drive) counts as reached once the robot, within '
                                         'goal_tolerance of it, faces it within this angle (rad; Nav2\'s default)',
                                   1e-3, 3.1416, unit='rad', component='controller')
    trans_stopped_velocity: float = _p(0.25, 'a goal counts as reached only once the robot\'s measured speed '
                                             '(odometry) is at most this; until then it brakes at the goal (m/s; '
                                             'Nav2\'s stopped goal checker and its default)', 1e-4,
                                       unit='m/s', component='controller')
    rot_stopped_velocity: float = _p(0.25, '... and its measured turn rate at most this (rad/s; Nav2\'s default)',
                                     1e-4, unit='rad/s', component='controller')
    regulated_speed: int = _p(1, 'FAStep-Route drives its route at the speed the way allows: max_speed, slowing only '
                                 'to stop at the goal and to take a bend at the vertex ahead at max_acceleration, and '
                                 'in gaps tighter than radius + clearance_margin (Nav2\'s Regulated Pure Pursuit is '
                                 'the anchor): 1; 0: eq. 12 / 13 toward the goal (speed gain x distance)', 0, 1,
                              component='route')
    goal_heading: int = _p(1, 'turn in place to a goal\'s heading once at its position (robots that turn in '
                              'place): 1; 0: a goal\'s heading is ignored', 0, 1, component='controller')
    waypoint_tolerance: float = _p(0.3, 'a waypoint counts as reached within this distance', 1e-4,
                                   unit='m', component='controller')
    dt: float = _p(0.05, 'control and integration step; the planner node\'s is its control period, 1 / '
                         'control_rate_hz (a dt given that disagrees is refused)', 1e-4, 10.0,
                   unit='s', component='node')
    progress_distance: float = _p(0.5, 'progress checker: come this much closer to the goal ...', 0.0,
                                  unit='m', component='recovery')
    progress_timeout: float = _p(120.0, '... within this many seconds, else fail; 0 disables', 0.0,
                                 unit='s', component='recovery')
    blocked_timeout: float = _p(10.0, 'a robot planning in what its laser shows and finding no way to the goal there '
                                      'waits this long, planning again on each new belief, before the goal fails '
                                      '(no valid path): a belief can be wrong for a moment; 0: fail at once', 0.0,
                                unit='s', component='recovery')
    trap_timeout: float = _p(20.0, 'trap escape: no progress_distance (near the goal: half the distance) closer '
                                   'to the goal in this many seconds starts an escape along the exact shortest '
                                   'path; 0 disables', 0.0, unit='s', component='recovery')
    # FAStep-Kinematic's activation policy (docs/architecture.md, "When the swarm runs"): when the swarm runs.
    # Both 0 is the paper's literal policy (the 'fastep_paper' algorithm ignores them).
    plan_horizon: float = _p(2.0, 'FAStep-Kinematic plans a step only when the straight run to the goal is blocked '
                                  'within this many metres (the step it could take); farther blockers are driven '
                                  'toward in a straight line, as the swarm would step anyway; 0: anywhere on '
                                  'the run (the default is step_radius\'s default: set them together)', 0.0,
                             unit='m', component='swarm')
    stuck_steps: int = _p(1, 'FAStep-Kinematic starts the trap escape after this many planned steps in a row that '
                             'end within waypoint_tolerance of the robot (a greedy local minimum: each counts as '
                             'reached at once and is planned again every tick); 0: only the trap detector',
                          0, 1000, component='swarm')
    waypoint_lead: float = _p(0.0, 'FAStep-Kinematic aims a holonomic robot this far beyond a swarm waypoint, on the '
                                    'run to it, so eq. 12 does not slow it down to a crawl as it nears the waypoint '
                                    '(the path is the same straight run; it is reached within waypoint_tolerance as '
                                    'before); 0: aims at the waypoint', 0.0, unit='m', component='controller')
    # Moving obstacles (a v2 world's movers, tracked obstacles; planning/safety/yielding.py).
    mover_horizon: float = _p(3.0, 'each command is checked against where the movers will be over this many seconds '
                                   '(each at its velocity): the robot slows down, waits or gets out of the way '
                                   'instead of driving into a mover\'s path; 0: movers count only where they are, '
                                   'like still obstacles one tick ahead', 0.0, 30.0, unit='s', component='safety')
    max_sim_time: float = _p(1500.0, 'fastep-sim stops a run after this much simulated time', 1.0,
                             unit='s', component='simulator')
    # ACO_R for the ACO-Kinematic baseline (Socha & Dorigo 2008).
    aco_archive: int = _p(10, 'ACO_R solution archive size k', 2, 10_000, component='swarm')
    aco_ants: int = _p(40, 'ACO_R ants per iteration m', 1, 100_000, component='swarm')
    aco_q: float = _p(0.5, 'ACO_R locality of the search q', 1e-6, component='swarm')
    aco_xi: float = _p(1.0, 'ACO_R pheromone evaporation / spread xi', 1e-6, component='swarm')
    aco_iter: int = _p(30, 'ACO_R iterations per step at most', 1, 10_000, component='swarm')
    # DWA, the Dynamic Window Approach (Fox, Burgard & Thrun 1997; planning/navigators/dwa.py); defaults measured in
    # docs/benchmarks.md ("DWA").
    dwa_acceleration: float = _p(1.0, 'DWA acceleration and braking limit: the dynamic window is the disc of '
                                      'velocities within this times the tick of the current one', 1e-3, 100.0,
                                 unit='m/s^2', component='dwa')
    dwa_samples: int = _p(11, 'DWA velocity samples per axis of the dynamic window (odd: the current velocity is '
                              'one of them)', 2, 51, component='dwa')
    dwa_horizon: float = _p(2.0, 'DWA rollout: each sampled velocity is held this long', 0.1, 20.0,
                            unit='s', component='dwa')
    dwa_rollout_steps: int = _p(20, 'DWA rollout: straight segments per rollout, checked for collisions', 1, 200,
                                component='dwa')
    dwa_heading: float = _p(1.0, 'DWA objective weight of goal progress over the rollout (the paper\'s heading)',
                            0.0, component='dwa')
    dwa_clearance: float = _p(0.2, 'DWA objective weight of the clearance the rollout keeps (the paper\'s dist)',
                              0.0, component='dwa')
    dwa_velocity: float = _p(0.2, 'DWA objective weight of speed / max_speed (the paper\'s vel)', 0.0, component='dwa')
    dwa_clearance_cap: float = _p(1.0, 'DWA clearance beyond this no longer scores', 1e-3, unit='m', component='dwa')
    dwa_escape: int = _p(0, 'DWA leaves a trap along the exact shortest path like fastep and aco do (the '
                            'navigator\'s trap escape, trap_timeout), steering by DWA to the path\'s carrot: 1; '
                            '0: pure DWA, a local planner that fails in a local minimum', 0, 1, component='dwa')

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            low, high = f.metadata['range']
            if not _is_finite_number(value):
                raise ParameterError(f'planner parameter {f.name} must be a finite number, got {_show(value)}')
            if f.type in ('int', int) and value != int(value):
                raise ParameterError(f'planner parameter {f.name} must be an integer, got {_show(value)}')
            if not low <= value <= high:
                raise ParameterError(f'planner parameter {f.name}={_show(value)} is outside [{low}, {high}]')
        for name in LIMIT_NAMES:   # a positive limit is a positive cap: never one that lifts it by underflowing
            problem = limit_problem(name, getattr(self, name))
            if problem:
                raise ParameterError(problem)
        if 0.0 < self.emergency_deceleration < self.max_acceleration:
            raise ParameterError(f'planner parameter emergency_deceleration={self.emergency_deceleration:g} is below '
                                 f'max_acceleration={self.max_acceleration:g}: the emergency stop brakes at least as '
                                 f'hard as any command (set both at once, or 0 for an immediate stop)')

    @property
    def limits(self) -> Limits:
        """The speed and acceleration limits and the control period, as the one value every reader takes."""
        return Limits.of(self)

    @classmethod
    def names(cls) -> tuple[str, ...]:
        return tuple(f.name for f in fields(cls))

    @classmethod
    def descriptions(cls) -> dict[str, str]:
        return {f.name: f.metadata['description'] for f in fields(cls)}

    def with_overrides(self, overrides: Mapping[str, Any]) -> PlannerParams:
        """A copy with some fields replaced; unknown names raise ParameterError."""
        unknown = sorted(set(overrides) - set(self.names()))
        if unknown:
            raise ParameterError(f'unknown planner parameter(s): {", ".join(unknown)}')
        cast = {}
        for f in fields(self):
            if f.name in overrides:
                value = overrides[f.name]
                cast[f.name] = int(value) if f.type in ('int', int) and _is_finite_number(value) \
                    and float(value).is_integer() else value
        return replace(self, **cast)
