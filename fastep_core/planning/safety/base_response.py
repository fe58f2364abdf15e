"""What the base has shown it does: the rate at which it changes speed and turn rate, measured from odometry.

A planner's stopping distances come from its acceleration limits, and a base that cannot keep to them (a heavy robot
on weak motors, a diff_drive_controller with lower limits of its own, a slippery floor) overshoots every stop
planned with them. `BaseResponse` compares each control period's command with the velocity odometry measured at the
end of it. An interval counts as a measurement when the command asked for at least the configured rate of change
(the velocity smoother's ramp does, as do its stops) and the base ended off what its recent commands asked
(`off_commands`: by more than FEEDBACK_BOUND): the base changed as fast as it could,
and what it achieved is what it can do. A run of such intervals lasting RUN_TIME gives a rate (change of speed over
time, the run's first interval left out: a servo's onset); the latest run of each kind (braking, accelerating) is
kept. A base that does what it is told (every kinematic plant) never falls short, so its estimate stays the
configured limit, and it is never above it.

`braking` is what stopping distances use (the guard's look-ahead, FAStep-Route's approach to its goal, the turn to a
goal's heading): the braking measured, or, before the base has braked hard, UNSEEN_BRAKING of the acceleration
measured (motors that cannot speed a base up quickly rarely stop it quickly, and on a slippery floor a braking
base's weight leaves its driven wheels: 1.3 m/s^2 braking after 2.0 accelerating, fastep_core/dynamics), or the
configured limit. Nav2 has no such estimate: its velocity_smoother's CLOSED_LOOP feedback (planning/safety/smoother.py)
is the anchor for taking odometry over commands.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ['FEEDBACK_BOUND', 'FEEDBACK_COMMANDS', 'RUN_TIME', 'WEAK_SHARE', 'AxisResponse', 'BaseResponse',
           'ShownResponse', 'all_finite', 'off_commands', 'speed_of']

FloatArray = NDArray[np.float64]
FEEDBACK_BOUND = (0.05, 0.1)   # m/s (a point mass: each component), rad/s: within this of a command, it was done
FEEDBACK_COMMANDS = 3          # the commands a measured velocity may be behind
EXACT = 1e-9                   # m/s, rad/s: a velocity this near a command is that command, as applied
RUN_TIME = 0.2                 # s: the least time of a run of saturated intervals that makes a measurement
WEAK_SHARE = 0.8               # status says the base tracks worse than configured below this share of a limit
LONGEST_INTERVAL = 0.5         # s: a gap between observations longer than this (a pause) measures nothing
LEAST_RATE = 0.05              # m/s^2, rad/s^2: the least rate a measurement gives
UNSEEN_BRAKING = 0.6           # braking assumed, before any is measured, as a share of the acceleration measured
DEMANDED = 0.8                 # an interval measures when its command asked at least this share of the limit
_isfinite = math.isfinite        # all_finite: a global's lookup, not an attribute's


@dataclass
class AxisResponse:
    """One axis (the speed, or the turn rate): the rates measured in its latest runs, by kind."""

    braking: float | None = None         # rate (per s) of the latest braking run, None: not measured yet
    accelerating: float | None = None
    _kind: str = ''                      # the run under way: 'braking', 'accelerating' or '' (none)
    _change: float = 0.0                 # achieved change over the run so far (its first interval left out)
    _time: float = 0.0
    _intervals: int = 0

    def interval(self, demand: float, achieved: float, off: bool, dt: float, limit: float,
                 window: float | None = None) -> None:
        """One control period of dt seconds: `demand` the change the command asked of the measured velocity
        (negative: less speed), `achieved` what the base did in the command's direction, `off` whether the base
        ended off its recent commands, `limit` the configured rate (0: unlimited), `window` the most time one
        command's change is spread over (the smoother's period; None: dt): a late tick asks no more than that."""
        span = dt if window is None else min(dt, window)
        counts = off and limit > 0.0 and abs(demand) >= DEMANDED * limit * span
        kind = ('braking' if demand < 0.0 else 'accelerating') if counts else ''
        if not kind:
            self.unsaturated()
            return
        if kind != self._kind:
            self._kind, self._change, self._time, self._intervals = kind, 0.0, 0.0, 0
        self._intervals += 1
        if self._intervals == 1:
            return   # the onset: a servo's lag, odometry's latency
        self._change += max(achieved, 0.0)
        self._time += dt
        if self._time >= RUN_TIME - 1e-9:
            # Never 0: 0 is "unlimited" to every limit; a base that does not move at all is planned with LEAST_RATE.
            setattr(self, kind, max(self._change / self._time, LEAST_RATE))

    def unsaturated(self) -> None:
        """An interval that measures nothing (`interval` with a command within the base's reach or done): the run
        under way, if any, ends."""
        if self._kind:
            self._kind, self._change, self._time, self._intervals = '', 0.0, 0.0, 0

    @property
    def shown(self) -> float | None:
        """The rate to plan stops with, as measured: braking, else UNSEEN_BRAKING of the acceleration (a base
        seen only speeding up slower than configured may brake slower still: its weight leaves the driven wheels
        as it brakes), None before either."""
        if self.braking is not None:
            return self.braking
        return None if self.accelerating is None else max(UNSEEN_BRAKING * self.accelerating, LEAST_RATE)

    def stopping(self, limit: float) -> float:
        """`shown` within a positive configured `limit`; the limit itself before anything is measured."""
        shown = self.shown
        if shown is None:
            return limit
        return shown if limit <= 0.0 else min(limit, shown)


@dataclass
class BaseResponse:
    """A robot's base as measured (module docstring). holonomic: velocities are map-frame (vx, vy) (a point mass);
    else body-frame (v, omega). `observe` once per command sent, with the velocity measured before it."""

    holonomic: bool
    max_acceleration: float = 0.0          # the configured limits (PlannerParams; `retune`)
    max_turn_acceleration: float = 0.0
    period: float | None = None            # the control period, the most a command's ramp spans (None: any)
    linear: AxisResponse = field(default_factory=AxisResponse)
    turn: AxisResponse = field(default_factory=AxisResponse)
    sent: deque[FloatArray] = field(default_factory=lambda: deque(maxlen=FEEDBACK_COMMANDS))
    _last: tuple[float, FloatArray, FloatArray] | None = None   # (t, measured, command sent then)
    _pose: tuple[float, list[float]] | None = None   # (t, state) of the last `slide`
    _slid: FloatArray | None = None    # the velocity the poses showed over the last interval, when faster

    def slide(self, at: float, measured: FloatArray, state: FloatArray) -> FloatArray:
        """The velocity to act on at `at`: the measured one (odometry's twist), unless the robot's poses (its state,
        localized) moved at a speed more than FEEDBACK_BOUND from it since the last call: then what they show (wheels
        that spin or slow on a slippery floor while the base slides: encoders do not see it). A kinematic plant's
        poses move as its twist says (a steered robot's chord is a little shorter than its arc), so for it this is
        the twist itself."""
        # In Python floats: the same IEEE operations as numpy's on these few numbers, without an array for each
        # (this runs every control tick).
        pose = np.asarray(state, dtype=float).tolist()
        last = self._pose
        if last is None or at > last[0]:
            self._pose = (at, pose)
        if last is not None and at > last[0] and at - last[0] <= LONGEST_INTERVAL and len(pose) >= 2:
            dt = at - last[0]
            moved_x, moved_y = (pose[0] - last[1][0]) / dt, (pose[1] - last[1][1]) / dt
            if self.holonomic:
                apart = math.hypot(moved_x - float(measured[0]), moved_y - float(measured[1]))
                self._slid = np.array([moved_x, moved_y]) if apart > FEEDBACK_BOUND[0] else None
            else:
                along = moved_x * math.cos(pose[2]) + moved_y * math.sin(pose[2])
                self._slid = np.array([along, 0.0]) if abs(along - float(measured[0])) > FEEDBACK_BOUND[0] else None
        elif last is None or at - last[0] > LONGEST_INTERVAL:
            self._slid = None
        return self.corrected(measured)

    def corrected(self, measured: FloatArray) -> FloatArray:
        """`measured` with the slide the last `slide` found (its turn rate kept), if any."""
        slid = self._slid
        if slid is None:
            return measured
        return slid.copy() if self.holonomic else np.array([float(slid[0]), float(measured[1])])

    def retune(self, max_acceleration: float, max_turn_acceleration: float) -> None:
        self.max_acceleration, self.max_turn_acceleration = max_acceleration, max_turn_acceleration

    def observe(self, t: float, measured: ArrayLike | None, sent: ArrayLike, measured_at: float | None = None) -> None:
        """At time t the base was sent `sent`, having measured `measured` (None: not known, nothing is learnt) at
        `measured_at` (None: t). A measurement no newer than the last one (odometry slower than the control loop,
        or not coming) measures nothing; the command sent is then the one in effect until the next."""
        command = np.asarray(sent, dtype=float).reshape(2)
        now = None if measured is None else np.asarray(measured, dtype=float).reshape(2)
        at = t if measured_at is None else measured_at
        if now is None or not (all_finite(now) and all_finite(command) and math.isfinite(at)):
            self._last = None
            self.sent.clear()
            return
        if self._last is not None and at <= self._last[0]:
            self._last = (self._last[0], self._last[1], command)
            self.sent.append(command)
            return
        last, self._last = self._last, (at, now, command)
        off = off_commands(now, self.sent, self.holonomic)
        self.sent.append(command)
        if last is None:
            return
        t0, before, held = last
        dt = at - t0
        if not 0.0 < dt <= LONGEST_INTERVAL:
            return
        if not off:
            # The base ended on its commands: no interval measures (AxisResponse.interval), whatever it asked; the
            # demands are not worked out (every tick of a base that does as told, every kinematic plant).
            self.linear.unsaturated()
            if not self.holonomic:
                self.turn.unsaturated()
            return
        if self.holonomic:
            change = held - before
            size = math.hypot(float(change[0]), float(change[1]))
            along = (change / size) if size > 0.0 else np.zeros(2)
            less = math.hypot(float(held[0]), float(held[1])) < math.hypot(float(before[0]), float(before[1]))
            self.linear.interval(-size if less else size, float(np.dot(now - before, along)), off, dt,
                                 self.max_acceleration, self.period)
            return
        for axis, i, limit in ((self.linear, 0, self.max_acceleration), (self.turn, 1, self.max_turn_acceleration)):
            wanted = float(held[i] - before[i])
            less = abs(float(held[i])) < abs(float(before[i]))
            achieved = (1.0 if wanted >= 0.0 else -1.0) * float(now[i] - before[i])
            axis.interval(-abs(wanted) if less else abs(wanted), achieved, off, dt, limit, self.period)

    @property
    def braking(self) -> float:
        """The deceleration (m/s^2) to plan stops with (module docstring), within max_acceleration (0: unlimited)."""
        return self.linear.stopping(self.max_acceleration)

    @property
    def turn_braking(self) -> float:
        """Likewise for the turn rate (rad/s^2); 0 for a point mass or an unlimited configuration."""
        return 0.0 if self.holonomic else self.turn.stopping(self.max_turn_acceleration)

    def stop_within(self, deceleration: float) -> float:
        """A stop asked at `deceleration` (the guard's emergency_deceleration; 0: immediate) as the base has shown
        it brakes: no harder than it measurably did, once it has been seen braking or accelerating."""
        return _stop_within(self.linear.shown, deceleration)

    def shown(self) -> ShownResponse:
        """What it has measured so far, as one immutable value (for a planning pass on another thread)."""
        return ShownResponse(self.holonomic, self.braking, self.turn_braking, self.linear.shown,
                             None if self._slid is None else self._slid.copy())

    def problem(self) -> str:
        """What status says when the base tracks worse than configured ('' when it does not), with the figures."""
        parts = []
        for name, shown, limit, unit, what in (
                ('braking', self.braking, self.max_acceleration, 'm/s^2', 'max_acceleration'),
                ('turn braking', self.turn_braking, 0.0 if self.holonomic else self.max_turn_acceleration, 'rad/s^2',
                 'max_turn_acceleration')):
            if limit > 0.0 and shown < WEAK_SHARE * limit:
                parts.append(f'{name} {shown:.2g} {unit} measured, {what} {limit:g}')
        return '; '.join(parts)


@dataclass(frozen=True)
class ShownResponse:
    """What a BaseResponse had measured at one moment: what a planning pass reads of the base while the control
    loop that measures it goes on, on another thread (BaseResponse.shown; the same answers as the response then)."""

    holonomic: bool
    braking: float
    turn_braking: float
    linear_shown: float | None     # the braking the base has shown (None: not seen yet)
    slid: FloatArray | None        # the velocity the poses showed, when faster than the twist said

    def stop_within(self, deceleration: float) -> float:
        """BaseResponse.stop_within."""
        return _stop_within(self.linear_shown, deceleration)

    def corrected(self, measured: FloatArray) -> FloatArray:
        """BaseResponse.corrected."""
        slid = self.slid
        if slid is None:
            return measured
        return slid.copy() if self.holonomic else np.array([float(slid[0]), float(measured[1])])


def _stop_within(shown: float | None, deceleration: float) -> float:
    if shown is None:
        return deceleration
    return shown if deceleration <= 0.0 else min(deceleration, shown)


def all_finite(values: ArrayLike) -> bool:
    """np.isfinite(values).all() for the few numbers of a state or a velocity, at a fifth of its cost (~2 us a call
    here; a control tick asks six to a dozen times)."""
    if type(values) is np.ndarray and values.ndim == 1 and values.dtype.char == 'd':   # float64
        for value in values.tolist():
            if not _isfinite(value):
                return False
        return True
    return bool(np.isfinite(values).all())


def speed_of(velocity: FloatArray, holonomic: bool) -> float:
    """The speed of a velocity in a model's command form: the norm of (vx, vy), else |v| of (v, omega)."""
    return math.hypot(float(velocity[0]), float(velocity[1])) if holonomic else abs(float(velocity[0]))


def off_commands(measured: FloatArray, recent: Sequence[FloatArray], holonomic: bool) -> bool:
    """Is the measured velocity off the last of the recent commands by more than FEEDBACK_BOUND, and none of them
    exactly (a plant that applies its commands as given, its odometry a command or two behind on a graph)? Without
    commands: no. Why not within the range they span: a base that cannot follow a ramp stays within it."""
    if not recent:
        return False
    last = recent[-1]
    bound = (FEEDBACK_BOUND[0], FEEDBACK_BOUND[0]) if holonomic else FEEDBACK_BOUND
    m0, m1 = float(measured[0]), float(measured[1])
    if abs(m0 - float(last[0])) <= bound[0] and abs(m1 - float(last[1])) <= bound[1]:
        return False
    return not any(abs(m0 - float(c[0])) <= EXACT and abs(m1 - float(c[1])) <= EXACT for c in recent)
