"""DWA: the Dynamic Window Approach (Fox, Burgard & Thrun, "The Dynamic Window Approach to Collision
Avoidance", IEEE Robotics & Automation Magazine 4(1), 1997), for the differential-drive base it was made for
and adapted to the holonomic point mass.

Why it is here: it is the local planner a ROS user would pick instead of FAStep-Kinematic (Nav2's DWB
controller descends from it), so it is the yardstick, run in the same harness (the shared Navigator loop, its
guard, its 'no valid path' check and progress checker; planning/navigator.py).

Every control tick, as in the paper:
1. The search space. Velocities (vx, vy) on a `dwa_samples` x `dwa_samples` grid
   over the dynamic window, the velocities reachable within one tick from the current one under the
   acceleration limit `dwa_acceleration`, minus those faster than `max_speed` (the paper's V_s). A holonomic
   robot's acceleration is a vector, so the window is a disc: a square one (a limit per axis) would let the
   velocity term favour its corners, and a robot starting from rest would veer off the straight line. The
   grid's axes lie along and across the bearing to the goal, for the same reason: on axes of the map a grid
   point just off a diagonal bearing is faster than the one on it, and the robot veered.
   The current velocity is the command last sent (the point mass's plant follows its command exactly), or
   rest after a gap of more than two ticks (a planner node that held the robot still).
2. The rollout: each sample is held for `dwa_horizon` seconds, in `dwa_rollout_steps` straight segments, and
   checked against the obstacles (circles, segments), the workspace walls and the other robots, which move
   on at their last known velocities (moving obstacles). A segment "hits" when it comes within the robot's
   clearance (radius + `clearance_margin`, the distance every planned waypoint of the other planners keeps)
   of an obstacle or wall, or within both radii plus `clearance_margin` of another robot, and nearer than
   the robot is now (a robot already that near may still move away, as the guard allows). Without the
   margin, the objective's pull to the goal makes the robot skim obstacles at exactly its radius.
3. Admissible velocities (the paper's V_a): those the robot can stop on before the first hit, braking at
   `dwa_acceleration` after one tick at the sampled speed: dt + speed / (2 a) <= time of the hit (the start
   of the first hitting segment, which errs on the safe side; with no hit, the end of the horizon, the only
   stretch known to be free). The others are discarded. With none left, the robot brakes as hard as allowed.
4. The objective (the paper's G, without its smoothing), maximised over the admissible samples:
       G(v) = dwa_heading * progress(v) + dwa_clearance * clearance(v) + dwa_velocity * velocity(v)
   - progress: how much closer to the goal the rollout ends, over max_speed * horizon (in [-1, 1]). The
     paper's heading term scores the angle to the goal of a robot that must turn first; a holonomic robot
     has no heading to turn, so the goal progress takes its place, and it slows the robot down at the goal;
   - clearance: the smallest margin the rollout keeps from any obstacle, wall or robot (beyond the contact
     distance of step 2), capped at `dwa_clearance_cap` and divided by it. The paper's dist term is the free
     run along the trajectory, which in a straight-line rollout is what the admissibility already uses; so
     the score here rewards keeping away, like DWB's obstacle critic. The margin is not floored at zero: a
     rollout that would cut less deep into another robot's way (admissible, as it could still stop) scores
     better, so the robot swerves for an oncoming one instead of driving on until it must brake;
   - velocity: speed / max_speed (the paper's vel term).
   The terms are scaled by fixed bounds, not by the spread of the samples (a tick where all the samples are
   alike would otherwise blow up noise), and the paper's smoothing of G over the window is left out. The
   best sample, ties broken by grid order, is the command: no random numbers are drawn.

Vectorised over the samples, the rollout steps and the obstacles: one tick is a few dozen numpy operations
on arrays of samples x steps x obstacles, only over the obstacles the rollouts can reach.

What it does not do: it is a local planner. In a U-shaped trap facing the robot it drives into the pocket and
stays where no admissible velocity brings it closer to the goal; FAStep-Kinematic and ACO-Kinematic leave
such traps along the exact path (the navigator's trap escape), which DWA deliberately does not get. The
progress checker then ends the run: "failed to make progress ... (DWA: a local minimum)", with ", another
robot in the way" when one is within sensing_range (two robots face to face in a corridor hold each
other). With `dwa_escape` = 1 it gets that escape too: after trap_timeout without progress, the target
whose progress DWA scores is the exact path's carrot instead of the goal, until the robot has left the trap
(the yardstick with the same safety net as the others; what a Nav2 user gets from a global planner above
DWB).

Robot models: the holonomic point mass (above) and a differential-drive base (a unicycle, the paper's own
robot; kinematics/diff_drive.py), which the model tells apart by what it declares (not holonomic, turns in place,
no trailer). For the unicycle, as in the paper:
- the window is the rectangle of commands (v, omega) reachable within one tick from the current one, v within
  max_acceleration * dt and omega within max_turn_acceleration * dt (the base's limits; dwa_acceleration, and
  twice it per second for omega, where those are 0), cut to 0 <= v <= max_speed (forward only, as Nav2's
  DWB with min_vel_x = 0) and |omega| <= max_turn_rate, `dwa_samples` values per axis;
- the rollout holds (v, omega) and follows the exact arc (kinematics/diff_drive.py's closed form), checked as
  `dwa_rollout_steps` chords;
- admissible: v can brake to rest at max_acceleration before the first hit;
- the objective adds two terms. The paper's heading term, dwa_heading * HEADING_SHARE * (1 - e / (pi - f))
  with e the angle by which the heading at the rollout's end points more than f away from the bearing from
  there to the goal (0 within f): the goal progress alone scores a base facing away from its goal at rest
  (every sample is slow) nearly equally for every turn rate. f is 90 degrees while the rollout ends farther
  from the goal than max_speed * dwa_horizon, narrowing in proportion to nothing at the goal. Flat within 90
  degrees because a base facing an obstacle on the way must be free to turn away from the goal to skirt it: a
  term that pulled it back to the goal held it there (diff_drive_walls: stuck 0.2 m from the first circle, 'a
  local minimum'); narrowing near the goal because there a base 0.2 m beside its goal, facing across, had no
  reason left to turn toward it and stood there (every forward arc ends farther away);
  And a look-ahead term, the paper's dist in spirit: dwa_clearance times the room beyond the clearance at
  dwa_clearance_cap metres ahead of the rollout's end along its final heading (capped at +-dwa_clearance_cap,
  over it): of the turns on the spot, whose rollouts all keep the same clearance, it picks the one that faces
  free room, so a base that drove up to an obstacle turns toward the side it can pass on;
- braking lowers v and omega toward 0 at their accelerations.
A tractor-trailer (steered, not turning in place) is refused when the navigator is made (one line, from
`make_navigator`).
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

    def update(self, t: float, state: FloatArray, others: Sequence[OtherRobot] = ()) -> FloatArray:
        if self._last_t is not None and t - self._last_t > 2.0 * self.params.dt:
            self.velocity = np.zeros(2)   # ticks were missed (a planner node holding a robot): start from rest
        command = super().update(t, state, others)
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
        if self.escape.active:
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
        p = self.params
        linear = p.max_acceleration if p.max_acceleration > 0.0 else p.dwa_acceleration
        angular = p.max_turn_acceleration if p.max_turn_acceleration > 0.0 else 2.0 * p.dwa_acceleration
        return linear, angular

    def unicycle_window(self, dt: float) -> FloatArray:
        """A unicycle's samples (n, 2) of (v, omega): a grid over the reachable rectangle, cut to the limits."""
        p = self.params
        linear, angular = self.accelerations()
        v0, w0 = float(self.velocity[0]), float(self.velocity[1])
        v_low, v_high = max(0.0, v0 - linear * dt), min(p.max_speed, v0 + linear * dt)
        if v_low > v_high:   # faster than max_speed (a limit lowered at run time): brake toward it
            v_low = v_high = max(p.max_speed, v0 - linear * dt)
        w_low, w_high = w0 - angular * dt, w0 + angular * dt
        if p.max_turn_rate > 0.0:
            w_low, w_high = max(-p.max_turn_rate, w_low), min(p.max_turn_rate, w_high)
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
        p = self.params
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
        reach = p.max_speed * horizon + self.clearance + p.dwa_clearance_cap   # nothing farther can matter
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
        admissible = (dt + speed / (2.0 * braking) <= first) & (speed <= p.max_speed * (1 + 1e-9))
        count = int(admissible.sum())
        if count == 0:
            return Choice(self._brake(dt), -math.inf, 0, True)

        # Step 4: the objective.
        scale = p.max_speed * horizon
        progress = (math.hypot(goal[0] - position[0], goal[1] - position[1]) -
                    np.hypot(goal[0] - points[:, -1, 0], goal[1] - points[:, -1, 1])) / scale
        clearance = np.minimum(margin.min(axis=1), p.dwa_clearance_cap) / p.dwa_clearance_cap
        score = p.dwa_heading * progress + p.dwa_clearance * clearance + p.dwa_velocity * speed / p.max_speed
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
        free = 0.5 * math.pi * np.minimum(1.0, left / (p.max_speed * horizon))
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

