"""The control loop's bounded tick: drive on the latest plan while planning runs elsewhere.

A planning pass (`Navigator.update`: exact paths, escapes, manoeuvres, the swarm) can take seconds, and a robot's
clock does not stop meanwhile. `ControlTick.command` turns the latest `Plan` into this tick's command from the
robot's current state in well under a millisecond: the controller toward the plan's target (or the plan's own
command), then yielding to movers and the guard against the newest robots, looking as far ahead as the robot needs
to brake; then the velocity smoother (planning/safety/smoother.py) and, for a steered robot backing up, its swept disc
checked against the world and the free space recent scans saw. Closed loop: given the velocity odometry measured,
the smoother ramps from it when the base is not doing what it was told, the guard looks as far ahead as the faster
of command and base takes to stop, braking no harder than the base has shown it can, and every command sent is
compared with what the base did (the navigator's BaseResponse, which this tick feeds). Nav2 splits its planner and
controller servers, and ends with its velocity_smoother, for the same reasons.

Used by the planner node's control timer while a thread plans (fastep_ros/planner.py) and by `fastep-sim
--realtime` (`PlanLatency` delays a pass's plan by the wall time it took). Lock-step runs use neither.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np
from numpy.typing import NDArray

from fastep_core.planning.navigator import Mode, Navigator, SpeedLaw
from fastep_core.planning.others import OtherRobot
from fastep_core.planning.outline import inflated
from fastep_core.planning.recovery.back_up import REVERSE_HORIZON, reverse_free
from fastep_core.planning.safety.base_response import all_finite, speed_of
from fastep_core.planning.safety.guard import Guard
from fastep_core.planning.safety.lateness import Lateness, stopping_speed
from fastep_core.planning.safety.smoother import VelocitySmoother
from fastep_core.world import World

__all__ = ['ControlTick', 'Plan', 'PlanLatency']

FloatArray = NDArray[np.float64]
UNDER_WAY = (Mode.KINEMATIC, Mode.AVOIDING)
PREDICT_MOVERS = 1.0   # s: a plan's tracked movers are predicted along their velocities at most this far


@dataclass(frozen=True)
class Plan:
    """What a planning pass leaves for the control loop until the next pass ends."""

    t: float                          # the time of the state it was planned from
    target: FloatArray | None         # what the controller drives to (drive_to's target); None: follow `command`
    command: FloatArray               # the pass's own command: held while there is no target
    world: World                      # the world it was planned in (the guard checks against it)
    movers: tuple[OtherRobot, ...]    # movers the robot's own perception tracked, as of t
    mode: Mode
    reason: str
    cost: float = 0.0
    speed: SpeedLaw | None = None     # the speed the way allows (FAStep-Route's), frozen with the plan

    @classmethod
    def of(cls, navigator: Navigator, t: float, command: FloatArray,
           movers: Sequence[OtherRobot] = ()) -> Plan:
        """The plan a pass of `navigator` at time t left, `command` being what its update returned."""
        return cls(t, navigator.driven, np.array(command, dtype=float), navigator.world, tuple(movers),
                   navigator.mode, navigator.reason, float(navigator.cost), navigator.speed_law())

    @property
    def under_way(self) -> bool:
        return self.mode in UNDER_WAY

    def movers_at(self, t: float) -> list[OtherRobot]:
        """The tracked movers predicted to t along their velocities (a plan can be seconds old; at most
        PREDICT_MOVERS ahead: a track is a guess, and after a pause the clock may have jumped)."""
        ahead = min(max(0.0, t - self.t), PREDICT_MOVERS)
        return [OtherRobot(m.name, (m.position[0] + m.velocity[0] * ahead, m.position[1] + m.velocity[1] * ahead),
                           m.velocity, m.radius, m.mover) for m in self.movers]


class ControlTick:
    """The per-tick part of a navigator, with its own controller, guard and yielding (the pass runs the originals,
    possibly on another thread)."""

    def __init__(self, navigator: Navigator, scan_allowance: float = math.inf) -> None:
        # The pass's guard looks as far ahead as this one does (retune: Navigator.braking): a stricter control tick
        # held robots for good while the pass, its own guard letting them go, never saw the hold (nor broke it).
        self.navigator = navigator
        navigator.response_fed_elsewhere = True   # the commands sent are this tick's, not the pass's
        self.response = navigator.response
        self.smoother = VelocitySmoother.for_model(navigator.model, navigator.limits)
        self._last_t: float | None = None
        self._measured: FloatArray | None = None   # the velocity measured at this tick, if given ...
        self._measured_at = 0.0                    # ... as of this time
        self._fed_at: float | None = None          # the newest measurement the smoother was given
        # How late this loop acts (planning/safety/lateness.py): looked ahead by the guard, and the speed it allows. A
        # scan the guard checks counts as late once older than scan_allowance (s; the node's scan_timeout).
        self.lateness = Lateness()
        self.scan_allowance = scan_allowance
        self.slowed = ''   # why this tick's speed was reduced for lateness ('' when it was not)
        self.retune()

    def retune(self) -> None:
        """Take the navigator's parameters, limits, model and controller afresh (after Navigator.retune): the
        smoother, the guard, yielding and FAStep-Route's speed law of the plans it drives on (`_speed_law`) all
        read the same limits from the next command on."""
        nav = self.navigator
        self.limits = limits = nav.limits
        nav.braking = limits.emergency_deceleration
        self.model = nav.model
        self.controller = copy.deepcopy(nav.controller)
        self._applied: Callable[[FloatArray], None] | None = getattr(self.controller, 'applied', None)
        self._tell(self.smoother.velocity)   # a new controller ramps from what the robot does now
        self.smoother.retune(limits)   # its period: each command's dt (command)
        self.guard = Guard(nav.model, nav.radius, nav.params, nav.footprint, limits)
        self.yielding = nav._yielding(nav.params)
        self._target: FloatArray | None = None
        self.reason = ''        # why this tick's command differs from the plan's ('' when it does not)

    def command(self, t: float, state: FloatArray, others: Sequence[OtherRobot], plan: Plan | None,
                dt: float, velocity: FloatArray | None = None, measured_at: float | None = None,
                pose: FloatArray | None = None) -> FloatArray:
        """This tick's command on `plan` (a stop without one, or when it is not under way), smoothed. velocity:
        what the base measurably does (odometry's twist, the model's command form) as of `measured_at` (its stamp;
        None: t); None: what it was told. pose: the odometry's own pose then (default: state; a state predicted
        forward with the command would show the command, not the base)."""
        elapsed = dt if self._last_t is None or not t > self._last_t else t - self._last_t
        self._last_t = t
        self.smoother.period = self.response.period = dt
        self._measured = self._feedback(velocity, t if measured_at is None else measured_at,
                                        state if pose is None else pose)
        self._late(t, dt, None if velocity is None else measured_at)
        others = inflated(others, self.navigator.outline_extra)   # a footprint's circumscribed circle (outline.py)
        wanted, emergency = self._unsmoothed(t, state, others, plan, dt)
        before = self.smoother.velocity.copy()
        sent = self.smoother.smooth(wanted, elapsed, emergency)
        state = np.asarray(state, dtype=float)
        if not emergency and not _equal(sent, wanted) and any(c != 0.0 for c in sent.tolist()) and \
                all_finite(state):
            # What the robot will really do, on its way from its velocity to the command (or to a stop), must pass
            # the guard too: a turn away from a robot, ramped, still heads at it for a tick or two.
            world = self.navigator.world if plan is None else plan.world
            movers = [] if plan is None else inflated(plan.movers_at(t), self.navigator.outline_extra)
            if self._guarded(world, state, sent, dt, [*others, *movers]) is not sent:
                self.reason = self.guard.reason
                self.smoother.take_back(before)
                sent = self.smoother.smooth(np.zeros(2), elapsed, emergency=True)
        self._sent(t, sent)
        return sent

    def _feedback(self, velocity: FloatArray | None, at: float, state: FloatArray) -> FloatArray | None:
        """The measured velocity (finite, or None), given to the smoother (its closed loop) when it is newer than the
        last one given (odometry slower than the control loop repeats itself: an old twist is not the base now);
        returned with a slide its poses show (BaseResponse.slide), for the guard, arrival and the braking measured."""
        self._measured_at = at
        if velocity is None:
            return None
        measured = np.asarray(velocity, dtype=float).reshape(2)
        position = np.asarray(state, dtype=float)
        if not (all_finite(measured) and all_finite(position)):
            return None
        if self._fed_at is None or at > self._fed_at:
            self._fed_at = at
            # The wheels' own velocity: what the base's controller follows (a slide's would ask the wheels for more).
            self.smoother.feedback(measured)
        return self.response.slide(at, measured, position)

    def _late(self, t: float, dt: float, measured_at: float | None) -> None:
        """This tick's lateness: its gap since the last, the age of the odometry acted on, the scan's."""
        taken = self.navigator.guard_inputs.taken
        self.lateness.tick(t, dt, 0.0 if measured_at is None else t - measured_at,
                           t - taken - self.scan_allowance if taken > -math.inf else 0.0)

    def _sent(self, t: float, sent: FloatArray) -> None:
        """`sent` goes to the base: the controller hears it, the base's response is measured against it."""
        self.lateness.moving(t, any(c != 0.0 for c in sent.tolist()))
        self._tell(sent)
        if self._measured is None:
            self.response.observe(t, self.smoother.velocity, sent)   # as told: nothing is learnt
        else:
            self.response.observe(t, self._measured, sent, self._measured_at)

    def reset(self, velocity: FloatArray) -> None:
        """What the robot does now (a stop sent past the control tick): the smoother and the controller ramp from it."""
        self.smoother.reset(velocity)
        self._tell(self.smoother.velocity)

    def _guarded(self, world: World, state: FloatArray, command: FloatArray, dt: float,
                 others: Sequence[OtherRobot]) -> FloatArray:
        """The guard's verdict a tick and the braking distance ahead (as the pass's guard: Navigator.braking)."""
        return self.guard.check(world, state, command, self._ahead(dt), others)

    def _ahead(self, dt: float) -> float:
        """How far ahead (s) the guard looks: a tick and the loop's lateness, and the time to brake from the robot's
        speed (the faster of the smoother's and the measured one) at emergency_deceleration, or at what the base has
        shown it brakes at if that is less (half of it: braking distance v^2 / 2a at speed v)."""
        braking = self.response.stop_within(self.limits.emergency_deceleration)
        holonomic = bool(self.model.holonomic)
        speed = speed_of(self.smoother.velocity, holonomic)
        if self._measured is not None:
            speed = max(speed, speed_of(self._measured, holonomic))
        return dt + self.lateness.late + (0.5 * speed / braking if braking > 0.0 else 0.0)

    def stop(self, t: float, dt: float, velocity: FloatArray | None = None,
             measured_at: float | None = None, pose: FloatArray | None = None) -> FloatArray:
        """A stop the control loop must make without a plan to judge by (a robot held still): braking at
        emergency_deceleration from what the robot does (velocity: as measured at measured_at with the odometry's
        pose then; None: as told)."""
        elapsed = dt if self._last_t is None or not t > self._last_t else t - self._last_t
        self._last_t = t
        self._measured = None if pose is None else \
            self._feedback(velocity, t if measured_at is None else measured_at, pose)
        self._late(t, dt, None if velocity is None or pose is None else measured_at)
        self.slowed = ''
        sent = self.smoother.smooth(np.zeros(2), elapsed, emergency=True)
        self._sent(t, sent)
        return sent

    def _unsmoothed(self, t: float, state: FloatArray, others: Sequence[OtherRobot], plan: Plan | None,
                    dt: float) -> tuple[FloatArray, bool]:
        """The tick's command before the smoother, and whether it is the guard's (or the reverse check's) stop."""
        stop = np.zeros(2)
        self.reason = self.slowed = ''
        state = np.asarray(state, dtype=float)
        if plan is None or not plan.under_way or not all_finite(state):
            return stop, False
        late = self.lateness.late
        horizon = dt + late   # the command holds until a tick that may come this late
        others = [*others, *inflated(plan.movers_at(t), self.navigator.outline_extra)]
        # Surfaces known only as well as the robot's scans show them: what the pass's perception made of its latest
        # scan, read once (one value, replaced whole by the planning side: margin, returns and free space together).
        perceived = self.navigator.guard_inputs
        self.guard.obstacle_margin, self.guard.scan_points = perceived.obstacle_margin, perceived.scan_points

        def allowed(c: FloatArray) -> bool:
            return self.guard.check(plan.world, state, c, horizon, others) is c

        target = plan.target
        if target is not None:
            if target is not self._target:
                self.controller.reset(state, target)
                self._target = target
            command = self.controller.command(state, target, dt)
            if plan.speed is not None:
                command = self._speed_law(plan.speed).regulate(state, command, dt)
        else:
            self._target = None
            command = plan.command
        if late > 0.0:
            command = self._within_lateness(state, command, dt, late)
        standing = not any(c != 0.0 for c in command.tolist())
        yielded = self.yielding.check(state, command, others, allowed)
        if yielded.kind and (not standing or yielded.kind == 'evading'):
            command, self.reason = yielded.command, yielded.reason
        guarded = self._guarded(plan.world, state, command, dt, others)
        if guarded is not command:
            self.reason = self.guard.reason
            return guarded, True
        seen = perceived.seen   # None without a laser: the map is known, and the guard checks it
        if seen is not None and not self.model.holonomic and float(command[0]) < 0.0 and \
                not reverse_free(self.model, state, self.navigator.radius, command, REVERSE_HORIZON, plan.world,
                                 seen, (), self.guard.obstacle_margin, self.navigator.footprint):
            # Still obstacles and what no scan has seen: the robots, which move, are the guard's (above).
            self.reason = 'stopped: no evidence the space behind is free'
            return stop, True
        return command, False

    def _within_lateness(self, state: FloatArray, command: FloatArray, dt: float, late: float) -> FloatArray:
        """`command` no faster than stops, `late` seconds behind its tick, where an on-time robot at max_speed
        would, and at the goal (planning/safety/lateness.py); scaled whole, so its path stays the same."""
        speed = speed_of(command, bool(self.model.holonomic))
        if speed <= 0.0:
            return command
        braking = self.response.stop_within(self.limits.max_acceleration)
        top = self.limits.max_speed
        allowed = math.inf
        if top > 0.0:
            on_time = top * dt + (0.5 * top * top / braking if braking > 0.0 else 0.0)
            allowed = stopping_speed(on_time, dt + late, braking)
        goal = self.navigator.goal
        if goal is not None:
            allowed = min(allowed, stopping_speed(math.hypot(float(goal[0]) - float(state[0]),
                                                             float(goal[1]) - float(state[1])), late, braking))
        if speed <= allowed:
            return command
        self.slowed = self.reason = f'speed reduced to {allowed:.2f} m/s: the control loop is ' \
                                    f'{self.lateness.describe()}'
        return command * (allowed / speed)

    def _speed_law(self, law: SpeedLaw) -> SpeedLaw:
        """A plan's speed law within this tick's limits: a plan made before a runtime change of them is driven on
        within the new ones (its stops planned at what the base has shown, within the new max_acceleration)."""
        if law.limits is self.limits or law.limits == self.limits:
            return law
        return law.under(self.limits, self.response.braking)

    def _tell(self, command: FloatArray) -> None:
        if self._applied is not None:
            self._applied(command)


def _equal(a: FloatArray, b: FloatArray) -> bool:
    """np.array_equal of two commands (the same shape and numbers, NaN equal to nothing) at a tenth of its cost:
    this is asked every control tick."""
    if type(a) is np.ndarray and type(b) is np.ndarray and a.ndim == 1 and a.shape == b.shape:
        return bool(a.tolist() == b.tolist())   # new floats each: no NaN is the same object, none equal
    return bool(np.array_equal(a, b))


@dataclass
class PlanLatency:
    """fastep-sim --realtime: a pass's plan reaches the control loop only once the wall time the pass took, times
    `factor`, has passed on the simulated clock (at the first tick after its start, at the earliest); meanwhile the
    robot drives on the plan it has, as the planner node does while its thread plans."""

    factor: float
    plan: Plan | None = None          # the plan the control loop drives on
    pending: Plan | None = None       # a pass's plan not yet available ...
    ready_at: float = math.inf        # ... from this simulated time
    ticks: int = 0                    # control ticks
    stale_ticks: int = 0              # control ticks with no plan newer than the last tick's
    passes: int = 0
    max_latency: float = 0.0          # the longest pass, in seconds of the simulated robot (wall x factor)

    def take(self, t: float) -> bool:
        """At the control tick of time t: adopt the pending plan if it is ready; True if the plan is fresh."""
        self.ticks += 1
        if self.pending is not None and self.ready_at <= t + 1e-9:
            self.plan, self.pending = self.pending, None
            return True
        self.stale_ticks += 1
        return False

    @property
    def idle(self) -> bool:
        """No pass under way: the next one starts on this tick's state."""
        return self.pending is None

    def submit(self, plan: Plan, t: float, wall: float) -> None:
        """A pass started at t that took `wall` seconds of wall time left `plan`."""
        latency = wall * self.factor
        self.pending, self.ready_at = plan, t + latency
        self.passes += 1
        self.max_latency = max(self.max_latency, latency)

    def to_json(self) -> dict[str, object]:
        return {'factor': self.factor, 'ticks': self.ticks, 'stale_ticks': self.stale_ticks, 'passes': self.passes,
                'max_plan_latency': round(self.max_latency, 6)}
