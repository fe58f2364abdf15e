"""DWA: the Dynamic Window Approach (Fox, Burgard & Thrun 1997) for the holonomic point mass and a differential-drive
base (kinematics/diff_drive.py); a tractor-trailer is refused when the navigator is made.

It is the yardstick: the local planner a ROS user would pick instead of FAStep-Kinematic (Nav2's DWB descends from
it), run in the same harness (the shared Navigator loop, its guard, 'no valid path' check and progress checker).
Every tick it samples velocities in the dynamic window (`dwa_samples` per axis, within one tick's acceleration),
rolls each out for `dwa_horizon` s against obstacles, walls and robots moving on, keeps those it can stop from
before the first hit (the paper's V_a), and takes the best of G = dwa_heading * progress + dwa_clearance *
clearance + dwa_velocity * velocity, ties in grid order (no random numbers). Vectorised over samples x rollout
steps x the obstacles the rollouts can reach. Being local it stays in a U-trap ("failed to make progress ...
(DWA: a local minimum)") unless `dwa_escape` = 1 gives it the exact-path trap escape.
Why each step departs from the paper (a disc window on goal-aligned axes, progress for heading, the unicycle's
heading and look-ahead terms): docs/architecture.md, "DWA, the yardstick".
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from fastep_core.errors import ParameterError
from fastep_core.geometry import point_segment_distance, segment_segment_distance
from fastep_core.kinematics.model import Controller, RobotModel
from fastep_core.planning.navigator import FloatArray, Mode, Navigator
from fastep_core.planning.others import OtherRobot, other_arrays
from fastep_core.planning.params import PlannerParams
from fastep_core.planning.safety.base_response import off_commands
from fastep_core.world import World

__all__ = ['DynamicWindow', 'Choice', 'HEADING_SHARE', 'LOCAL_MINIMUM']

LOCAL_MINIMUM = 'DWA: a local minimum'
"""Added to the progress checker's reason when a DWA run fails to make progress."""
HEADING_SHARE = 0.5
"""A unicycle's heading term weighs this times dwa_heading (module docstring)."""


@dataclass(frozen=True)
class Choice:
    """The outcome of one tick's search: the command, its score and what the search saw."""

    velocity: FloatArray   # the command: (vx, vy) for a point mass, (v, omega) for a unicycle
    score: float           # G of the chosen sample (-inf when none was admissible and the robot brakes)
    admissible: int        # how many samples were admissible
    near: bool             # was any obstacle, wall or robot within reach of the rollouts


class DynamicWindow(Navigator):
    """Samples velocities in the dynamic window, rolls each out, keeps the admissible ones, takes the best."""

    method = 'dwa'
    escapes_traps = False   # a local planner: no escape along the exact path, unless dwa_escape (module docstring)

    def __init__(self, model: RobotModel, controller: Controller, radius: float, world: World,
                 params: PlannerParams | None = None, rng: np.random.Generator | int | None = None) -> None:
        super().__init__(model, controller, radius, world, params, rng)
        if not (model.holonomic or (model.turns_in_place and not model.trailer)):
            raise ParameterError(f'dwa drives holonomic robots and unicycles (point_mass, diff_drive) only, '
                                 f'not a {type(model).__name__}')
        self.unicycle = not model.holonomic   # samples (v, omega) and rolls out arcs (module docstring)
        self.holonomic_window = bool(model.holonomic)
        self.check_params(self.params)
        self.velocity = np.zeros(2)   # the command last sent: the centre of the next dynamic window
        self.escapes_traps = bool(self.params.dwa_escape)

    @classmethod
    def check_params(cls, params: PlannerParams) -> None:
        if params.max_speed <= 0.0:
            raise ParameterError('dwa needs a speed limit: max_speed must be > 0')

    def retune(self, params: PlannerParams, controller: Controller | None = None) -> None:
        super().retune(params, controller)
        self.escapes_traps = bool(params.dwa_escape)

    def update(self, t: float, state: FloatArray, others: Sequence[OtherRobot] = (),
               velocity: FloatArray | None = None, measured_at: float | None = None,
               pose: FloatArray | None = None) -> FloatArray:
        if self._last_t is not None and t - self._last_t > 2.0 * self.limits.dt:
            self.velocity = np.zeros(2)   # ticks were missed (a planner node holding a robot): start from rest
        if velocity is not None and np.isfinite(velocity).all() and \
                off_commands(np.asarray(velocity, dtype=float), (self.velocity,), self.holonomic_window):
            self.velocity = np.array(velocity, dtype=float)   # the window is centred on what the base does
        command = super().update(t, state, others, velocity, measured_at, pose)
        # Whatever was sent (a guarded stop, zeros at the goal) is the velocity the next window starts from.
        self.velocity = np.array(command[:2], dtype=float)
        if self.failed and self.reason.startswith('failed to make progress') and LOCAL_MINIMUM not in self.reason:
            # Two robots face to face in a corridor hold each other there too: say so.
            x, y = float(state[0]), float(state[1])
            blocked = any(math.hypot(o.position[0] - x, o.position[1] - y) - o.radius - self.radius <
                          self.params.sensing_range for o in others)
            self.reason = f'{self.reason} ({LOCAL_MINIMUM}{", another robot in the way" if blocked else ""})'
        return command

    def choose_target(self, position: FloatArray, others: Sequence[OtherRobot]) -> FloatArray | None:
        return self.goal

    def drive_to(self, state: FloatArray, target: FloatArray, t: float, dt: float,
                 others: Sequence[OtherRobot]) -> FloatArray:
        """The best admissible velocity of the dynamic window, through the guard (the last check)."""
        self._target = target
        start = time.perf_counter()
        choice = self.search(state, target, dt, others)
        self.plan_time += time.perf_counter() - start
        self.activations += 1
        self.cost = choice.score if math.isfinite(choice.score) else 0.0
        if self.escaping:
            pass   # the status stays the escape's: DWA steers to the exact path's carrot
        elif choice.admissible == 0:
            self.mode, self.reason = Mode.AVOIDING, 'dwa: no admissible velocity; braking'
        elif choice.near:
            self.mode, self.reason = Mode.AVOIDING, 'dwa: steering round obstacles'
        else:
            self.mode, self.reason = Mode.KINEMATIC, 'dwa: way is clear'
        return self.guard(state, choice.velocity, dt, others)

    # ------------------------------------------------------------------------------------- the search
    def window(self, dt: float, bearing: float = 0.0) -> FloatArray:
        """The velocity samples (n, 2): a grid over the dynamic window (a disc) around the current velocity,
        its axes along `bearing` (radians) and across it."""
        reach = self.params.dwa_acceleration * dt
        offsets = np.linspace(-reach, reach, self.params.dwa_samples)
        along, across = np.meshgrid(offsets, offsets, indexing='ij')
        inside = along * along + across * across <= reach * reach * (1.0 + 1e-9)
        along, across = along[inside], across[inside]
        c, s = math.cos(bearing), math.sin(bearing)
        return self.velocity + np.column_stack([c * along - s * across, s * along + c * across])

    def accelerations(self) -> tuple[float, float]:
        """A unicycle's limits on dv/dt (m/s^2) and domega/dt (rad/s^2) (module docstring)."""
        p, lim = self.params, self.limits
        linear = lim.max_acceleration if lim.max_acceleration > 0.0 else p.dwa_acceleration
        angular = lim.max_turn_acceleration if lim.max_turn_acceleration > 0.0 else 2.0 * p.dwa_acceleration
        return linear, angular

    def unicycle_window(self, dt: float) -> FloatArray:
        """A unicycle's samples (n, 2) of (v, omega): a grid over the reachable rectangle, cut to the limits."""
        p, lim = self.params, self.limits
        linear, angular = self.accelerations()
        v0, w0 = float(self.velocity[0]), float(self.velocity[1])
        v_low, v_high = max(0.0, v0 - linear * dt), min(lim.max_speed, v0 + linear * dt)
        if v_low > v_high:   # faster than max_speed (a limit lowered at run time): brake toward it
            v_low = v_high = max(lim.max_speed, v0 - linear * dt)
        w_low, w_high = w0 - angular * dt, w0 + angular * dt
        if lim.max_turn_rate > 0.0:
            w_low, w_high = max(-lim.max_turn_rate, w_low), min(lim.max_turn_rate, w_high)
            if w_low > w_high:
                w_low = w_high = min(max(0.0, w0 - angular * dt), w0 + angular * dt) if w0 > 0 else \
                    max(min(0.0, w0 + angular * dt), w0 - angular * dt)
        v, w = np.meshgrid(np.linspace(v_low, v_high, p.dwa_samples), np.linspace(w_low, w_high, p.dwa_samples),
                           indexing='ij')
        return np.unique(np.column_stack([v.ravel(), w.ravel()]), axis=0)

    def rollout(self, position: FloatArray, samples: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Times (k + 1,) and positions (n, k + 1, 2) of each sample held over the horizon (straight lines; a
        unicycle's position is its state (x, y, theta) and its rollouts are arcs)."""
        times = np.linspace(0.0, self.params.dwa_horizon, self.params.dwa_rollout_steps + 1)
        if self.unicycle:
            return times, self.arcs(position, samples, times)
        return times, position[:2] + samples[:, None, :] * times[None, :, None]

    @staticmethod
    def arcs(state: FloatArray, samples: FloatArray, times: FloatArray) -> FloatArray:
        """Positions (n, k + 1, 2) of a unicycle at `state` holding each (v, omega) of samples: the exact arcs."""
        v, w = samples[:, 0, None], samples[:, 1, None]
        turn = w * times[None, :]                                    # (n, k + 1)
        half = 0.5 * turn
        small = np.abs(half) < 1e-4
        sinc = np.where(small, 1.0 - half * half / 6.0, np.sin(half) / np.where(small, 1.0, half))
        chord = v * times[None, :] * sinc
        middle = float(state[2]) + half
        return np.stack([state[0] + chord * np.cos(middle), state[1] + chord * np.sin(middle)], axis=-1)

    def search(self, state: FloatArray, goal: FloatArray, dt: float, others: Sequence[OtherRobot]) -> Choice:
        """One tick of DWA (module docstring, steps 1-4): state is the position (x, y), a unicycle's (x, y, theta)."""
        p, top = self.params, self.limits.max_speed
        position = state[:2]
        if self.unicycle:
            samples = self.unicycle_window(dt)
            speed = np.abs(samples[:, 0])
            braking = self.accelerations()[0]
        else:
            samples = self.window(dt, math.atan2(goal[1] - position[1], goal[0] - position[0]))
            speed = np.hypot(samples[:, 0], samples[:, 1])
            braking = p.dwa_acceleration
        times, points = self.rollout(state, samples)
        horizon = float(times[-1])
        starts, ends = points[:, :-1], points[:, 1:]                 # the rollout's segments (n, k, 2)

        # Step 2: the margin each segment keeps (negative: a hit), against obstacles and walls, then robots.
        reach = top * horizon + self.clearance + p.dwa_clearance_cap   # nothing farther can matter
        static, static_now = self._static_margins(position, starts, ends, points, reach)
        robots, robots_now = self._robot_margins(position, times, points, others, reach)
        hit = (static < 0.0) & (static < static_now)
        margin = static
        near = bool(static_now < reach - self.clearance)
        if robots is not None:
            hit |= ((robots < 0.0) & (robots < robots_now)).any(axis=-1)
            margin = np.minimum(margin, robots.min(axis=-1))
            near = True   # a robot whose path the rollouts can reach

        # Step 3: admissible if it can stop before the first hit (with none, before the end of the horizon).
        first = np.where(hit.any(axis=1), times[np.argmax(hit, axis=1)], horizon)
        admissible = (dt + speed / (2.0 * braking) <= first) & (speed <= top * (1 + 1e-9))
        count = int(admissible.sum())
        if count == 0:
            return Choice(self._brake(dt), -math.inf, 0, True)

        # Step 4: the objective.
        scale = top * horizon
        progress = (math.hypot(goal[0] - position[0], goal[1] - position[1]) -
                    np.hypot(goal[0] - points[:, -1, 0], goal[1] - points[:, -1, 1])) / scale
        clearance = np.minimum(margin.min(axis=1), p.dwa_clearance_cap) / p.dwa_clearance_cap
        score = p.dwa_heading * progress + p.dwa_clearance * clearance + p.dwa_velocity * speed / top
        if self.unicycle:
            score = score + self._unicycle_terms(state, goal, samples, points, horizon)
        score = np.where(admissible, score, -np.inf)
        best = int(np.argmax(score))
        return Choice(samples[best].copy(), float(score[best]), count, near)

    def _unicycle_terms(self, state: FloatArray, goal: FloatArray, samples: FloatArray, points: FloatArray,
                        horizon: float) -> FloatArray:
        """A unicycle's heading and look-ahead terms of the objective (module docstring), per sample."""
        p = self.params
        final = float(state[2]) + samples[:, 1] * horizon            # the heading at the rollout's end
        bearing = np.arctan2(goal[1] - points[:, -1, 1], goal[0] - points[:, -1, 0])
        off = np.abs(np.arctan2(np.sin(bearing - final), np.cos(bearing - final)))
        # Flat within 90 degrees far from the goal, narrowing to nothing at the goal (module docstring).
        left = np.hypot(goal[0] - points[:, -1, 0], goal[1] - points[:, -1, 1])
        free = 0.5 * math.pi * np.minimum(1.0, left / (self.limits.max_speed * horizon))
        heading = 1.0 - np.maximum(0.0, off - free) / (math.pi - free)
        cap = p.dwa_clearance_cap
        ahead = points[:, -1] + cap * np.column_stack([np.cos(final), np.sin(final)])
        room = np.clip(self.world.room(ahead) - self.clearance, -cap, cap) / cap
        terms: FloatArray = p.dwa_heading * HEADING_SHARE * heading + p.dwa_clearance * room
        return terms

    def _static_margins(self, position: FloatArray, starts: FloatArray, ends: FloatArray, points: FloatArray,
                        reach: float) -> tuple[FloatArray, float]:
        """Each segment's margin (n, k) to the obstacles and walls beyond the clearance, and the margin now."""
        contact = self.clearance
        walls = self.world.wall_distance(points) - contact                # the border: concave, ends suffice
        margin = np.minimum(walls[:, :-1], walls[:, 1:])
        now = float(self.world.wall_distance(position)) - contact
        obstacles = self.world.obstacles
        if not len(obstacles):
            return margin, now
        gaps = obstacles.distances(position)
        close = gaps < reach
        if not close.any():
            return margin, now
        now = min(now, float(gaps.min()) - contact)
        a, b = starts[:, :, None, :], ends[:, :, None, :]
        circles = close[:obstacles.n_circles]
        if circles.any():
            to_circles = point_segment_distance(obstacles.centers[circles], a, b) - obstacles.radii[circles]
            margin = np.minimum(margin, to_circles.min(axis=-1) - contact)
        segments = close[obstacles.n_circles:]
        if segments.any():
            to_segments = segment_segment_distance(a, b, obstacles.starts[segments], obstacles.ends[segments])
            margin = np.minimum(margin, to_segments.min(axis=-1) - contact)
        return margin, now

    def _robot_margins(self, position: FloatArray, times: FloatArray, points: FloatArray,
                       others: Sequence[OtherRobot], reach: float) -> tuple[FloatArray | None, FloatArray]:
        """Each segment's margin (n, k, m) to the m other robots within reach, moving on at their velocities,
        beyond both radii plus clearance_margin; and the margins now (m,). None when no robot is in reach."""
        if not len(others):
            return None, np.zeros(0)
        centres, velocities, radii = other_arrays(others)
        contact = self.radius + radii + self.params.clearance_margin
        now = np.hypot(*(centres - position).T) - contact
        close = now < reach + np.hypot(*velocities.T) * float(times[-1])
        if not close.any():
            return None, np.zeros(0)
        centres, velocities, contact, now = centres[close], velocities[close], contact[close], now[close]
        # Relative to each robot the motion on a segment is straight: its closest approach is exact.
        relative = points[:, :, None, :] - (centres + velocities * times[:, None, None])[None]   # (n, k+1, m, 2)
        gap = point_segment_distance(np.zeros(2), relative[:, :-1], relative[:, 1:])
        return gap - contact, now

    def _brake(self, dt: float) -> FloatArray:
        """The slowest velocity of the window along the current direction: braking at dwa_acceleration (a
        unicycle: v and omega toward 0 at the base's accelerations)."""
        if self.unicycle:
            linear, angular = self.accelerations()
            v, w = float(self.velocity[0]), float(self.velocity[1])
            return np.array([math.copysign(max(0.0, abs(v) - linear * dt), v),
                             math.copysign(max(0.0, abs(w) - angular * dt), w)])
        speed = float(np.hypot(*self.velocity))
        slower = max(0.0, speed - self.params.dwa_acceleration * dt)
        brake: NDArray[np.float64] = self.velocity * (slower / speed) if speed > 0.0 else np.zeros(2)
        return brake

