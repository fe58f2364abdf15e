"""Nav2's behavior_server actions, served by the planner: `spin`, `backup`, `drive_on_heading`.

nav2_msgs/action/Spin, BackUp and DriveOnHeading with Nav2 Jazzy's definitions, on the planner's navigation node
(accepted on the action thread while the planner is active and handed to its executor, as the navigation goals
are: fastep_ros/navigate_actions.py), so that nav2_simple_commander's BasicNavigator.spin, backup and
driveOnHeading move a fastep robot. As Nav2's behaviours (nav2_behaviors: plugins/spin.cpp, back_up.cpp,
drive_on_heading.hpp on timed_behavior.hpp): spin turns in place by target_yaw (its sign the direction), backup
drives straight backward |target.x| m at |speed|, drive_on_heading forward (backward when target.x and speed are
both negative); feedback (angular_distance_traveled, distance_traveled) and success come from odometry, the
robot's measured pose, not the commands; time_allowance 0 means none. Error codes (each action's own): TIMEOUT
past time_allowance, COLLISION_AHEAD when the robot's disc or outline along the motion ahead (SIMULATE_AHEAD s of
it at the speed asked, at least the way to a stop, never past the distance or angle left) would come within reach
of an obstacle, another robot, a laser return or the map's border (the planner's own swept-motion and outline
checks: recovery.reverse_free, outline.py), TF_ERROR while the robot's pose is not known, INVALID_INPUT for a
target off x or a speed the run cannot be driven at, UNKNOWN for the rest (a point_mass asked to spin).

What differs from Nav2's behavior_server, and why:
- no node of its own: the planner's control tick asks the behaviour under way for its command (`command`, through
  `behaviour_plan` / `behaviour_command`) and sends it through its own control loop (fastep_core.planning.control:
  the velocity smoother, the guard, yielding to movers, the reverse check), so one node commands cmd_vel. One
  behaviour at a time (a new one preempts it: ABORTED, 0), and a behaviour and a navigation goal preempt each other
  (the navigation goal dropped as a cancel drops it; ABORTED, 0): Nav2's behaviours and controller would publish
  cmd_vel side by side.
- the limits are the planner's (fastep_core/planning/limits.py), read each tick (a speed limit caps a behaviour
  too): the speed asked capped by max_speed (max_reverse_speed backing up), a spin at max_turn_rate
  (DEFAULT_TURN_RATE where that is 0), every command ramped within max_acceleration and max_turn_acceleration and
  slowed so that the robot stops where the distance or angle ends (`stopping_speed`), where Nav2 sends its speed to
  the end and then a zero. Any end (succeeded, canceled, failed) brakes to a stop within them.
- point_mass: no heading, so no spin (UNKNOWN); it backs up along -x of base_link and drives on heading along +x,
  base_link's heading as its odometry gives it when the goal comes, held in the map frame (a holonomic base
  driven by Nav2's behaviours moves the same way). tractor_trailer: no spin (it turns only while moving) and no
  backing up (straight back its trailer folds; fastep reverses it only by its manoeuvres): UNKNOWN; it drives on
  heading forward.
- backup refuses a speed of 0 or one that is not finite (INVALID_INPUT): Nav2 Jazzy would sit until its
  time_allowance (or for ever without one).

The behaviour lives on the planner's executor (fastep_ros/planner_threads.py): started and ended on the control
and wall ticks (`start`, `check`), its command made on the control tick; it changes the planning side only by the
typed request a cancel uses (DropGoal).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np
from numpy.typing import NDArray

from fastep_core.geometry import point_segment_distance
from fastep_core.planning.control import Plan
from fastep_core.planning.limits import Limits
from fastep_core.planning.mode import Mode
from fastep_core.planning.others import OtherRobot
from fastep_core.planning.outline import inflated, predicted_poses
from fastep_core.planning.recovery.back_up import reverse_free, swept_centres
from fastep_core.planning.safety.smoother import VelocitySmoother
from fastep_core.world import World
from fastep_ros.companion import PREEMPTED, CompanionServers

__all__ = ['BACKUP', 'DRIVE_ON_HEADING', 'SPIN', 'BehaviourActions', 'behaviour_command', 'behaviour_plan',
           'stopping_speed']

FloatArray = NDArray[np.float64]
SPIN, BACKUP, DRIVE_ON_HEADING = 'spin', 'backup', 'drive_on_heading'
SIMULATE_AHEAD = 2.0      # s of the motion at the speed asked checked for collisions (Nav2's simulate_ahead_time)
DEFAULT_TURN_RATE = 1.0   # rad/s: a spin where max_turn_rate is 0 (unlimited): Nav2's max_rotational_vel default
FEEDBACK_PERIOD = 0.1     # node seconds between feedback messages (Nav2: one a cycle, cycle_frequency 10 Hz)
REACHED = {SPIN: 0.005, BACKUP: 0.005, DRIVE_ON_HEADING: 0.005}   # rad, m: odometry this close to the end is there
NEAR_ROOM = 0.5           # m beyond the motion checked: the obstacles kept for the checks while the robot is near


def stopping_speed(left: float, deceleration: float, dt: float) -> float:
    """The most speed from which braking at `deceleration` (0: unlimited) in steps of one control period `dt`, as the
    velocity smoother brakes, stops within `left`; never more than covers `left` in one period. Speeds s, s - a dt,
    ... each held dt cover s^2 / 2a + s dt / 2, hence s = sqrt((a dt / 2)^2 + 2 a left) - a dt / 2: the next tick's
    speed is then exactly a dt less (the continuous law sqrt(2 a left) asks for more and overshoots)."""
    if not left > 0.0:
        return 0.0
    if deceleration <= 0.0:
        return left / dt
    half = 0.5 * deceleration * dt
    return min(math.sqrt(half * half + 2.0 * deceleration * left) - half, left / dt)


@dataclass
class Behaviour:
    """One behaviour goal under way (or braking after its end): what it asked, and what odometry shows of it."""

    goal: Any                  # the ActionGoal handed over (kind, handle, done)
    began: float               # node time it started
    deadline: float            # node time it times out after (inf: no time_allowance)
    target: float              # m (rad for a spin) to travel, >= 0
    asked: float               # m/s (rad/s) asked, capped each tick by the limits then
    unit: FloatArray           # the command at unit speed: (0, +-1) a spin, (+-1, 0) a run, a point mass's (vx, vy)
    start: tuple[float, float]   # odometry's position when it came (its own frame)
    yaw: float                 # odometry's heading at the last measurement (a spin's turn adds up from it)
    stamp: float               # the stamp of the odometry last measured
    known: tuple[Any, ...]     # goal messages under way when it came, dropped for it (not new navigation goals)
    travelled: float = 0.0     # m, or a spin's signed turn (rad), as odometry shows
    ended: str = ''            # how its goal ended ('' while it runs): the robot brakes to a stop, then it is gone
    feedback_at: float = -math.inf
    last_t: float | None = None
    asked_tick: int = -1       # the control tick that last drove on its command (node.control_count)
    near: tuple[World, FloatArray, float, World] | None = None   # (world, centre, room, its obstacles near there)

    @property
    def kind(self) -> str:
        return str(self.goal.kind)

    @property
    def progress(self) -> float:
        """How far it has gone toward its target (a spin: its turn along the direction asked)."""
        return self.travelled * float(self.unit[1]) if self.kind == SPIN else self.travelled


class BehaviourActions(CompanionServers):
    """spin, backup and drive_on_heading (the module docstring). `run`: the behaviour under way, or braking after its
    end (None: none; the planner's control loop drives)."""

    def __init__(self, actions: Any) -> None:
        from nav2_msgs.action import BackUp, DriveOnHeading, Spin
        super().__init__(actions)
        self.served = {SPIN: Spin, BACKUP: BackUp, DRIVE_ON_HEADING: DriveOnHeading}
        self.run: Behaviour | None = None
        self.smoother: VelocitySmoother | None = None
        self.reason = ''   # what the behaviour is doing, in words (the plan's reason while it drives)

    # ------------------------------------------------------------------------------------------ goals
    def start(self, goal: Any, active: bool) -> None:
        """A goal handed over: checked, then under way at once (preempting the behaviour or navigation goal under
        way); refused with its action's code, saying why."""
        kind, node = goal.kind, self.node
        result = self.served[kind].Result
        if not active or goal.epoch != self.actions.epoch:
            self.end(goal, 'aborted', 'the planner was deactivated', total_elapsed_time=_duration(0.0))
            return
        problem, code = self.refusal(kind, goal.handle.request)
        now = node.now()
        state, missing = node.inputs.state(now)
        odom = node.inputs.odom
        if not problem and (state is None or odom is None):
            problem, code = f'robot pose not available: {missing}', int(result.TF_ERROR)
        if problem:
            self.end(goal, 'aborted', f'{kind} refused: {problem}', code, total_elapsed_time=_duration(0.0))
            return
        assert odom is not None
        request = goal.handle.request
        if kind == SPIN:
            target, asked = abs(float(request.target_yaw)), 0.0
            unit = np.array([0.0, math.copysign(1.0, float(request.target_yaw))])
        else:
            backward = kind == BACKUP or float(request.speed) < 0.0
            target, asked = abs(float(request.target.x)), abs(float(request.speed))
            if node.model == 'point_mass':   # along base_link's -x (backward) or +x, held in the map frame
                heading = node.inputs.body_yaw + (math.pi if backward else 0.0)
                unit = np.array([math.cos(heading), math.sin(heading)])
            else:
                unit = np.array([-1.0 if backward else 1.0, 0.0])
        previous = self.run
        if previous is not None and not previous.ended:
            self.finish(previous, 'aborted', f'preempted by a new {kind} goal', PREEMPTED)
        allowance = _seconds(getattr(request, 'time_allowance', None))
        self.run = Behaviour(goal, now, now + allowance if allowance > 0.0 else math.inf, target, asked, unit,
                             (float(odom.pose[0]), float(odom.pose[1])), float(odom.pose[2]), float(odom.stamp),
                             self.drop_navigation(kind))
        self.reason = f'{kind}: {target:g} {"rad" if kind == SPIN else "m"}'
        node.get_logger().info(f'{self.reason} ({"turning" if kind == SPIN else f"at {asked:g} m/s"})')

    def refusal(self, kind: str, request: Any) -> tuple[str, int]:
        """Why a goal cannot be driven ('' when it can) and its action's code for that."""
        result = self.served[kind].Result
        unknown, invalid = int(result.UNKNOWN), int(getattr(result, 'INVALID_INPUT', result.UNKNOWN))
        node = self.node
        model = node.model
        if node.navigator is None:
            return 'the planner knows no world yet (waiting for /obstacles or /map)', unknown
        if kind == SPIN:
            if model == 'point_mass':
                return 'a point_mass robot has no heading to spin (model point_mass)', unknown
            if model != 'diff_drive':
                return f'a {model} cannot turn in place', unknown
            if not math.isfinite(float(request.target_yaw)):
                return f'target_yaw {float(request.target_yaw)} is not finite', unknown
            return '', 0
        target, speed = request.target, float(request.speed)
        if target.y != 0.0 or target.z != 0.0:
            return f'target ({target.x:g}, {target.y:g}, {target.z:g}): only x is driven, y and z must be 0', invalid
        if not (math.isfinite(target.x) and math.isfinite(speed)):
            return f'target.x {target.x} and speed {speed} must be finite', invalid
        if kind == BACKUP:
            if speed == 0.0:
                return 'speed 0: backing up needs a speed (m/s, its sign ignored, as Nav2 ignores it)', invalid
            if model == 'tractor_trailer':
                return 'a tractor_trailer does not back up straight (its trailer folds)', unknown
            return '', 0
        if (target.x > 0.0) != (speed > 0.0):
            return f'target.x {target.x:g} and speed {speed:g} must have the same sign', invalid
        if speed < 0.0 and model == 'tractor_trailer':
            return 'a tractor_trailer does not back up straight (its trailer folds)', unknown
        return '', 0

    def drop_navigation(self, kind: str) -> tuple[Any, ...]:
        """The navigation goal under way, if any, ends (ABORTED, preempted) and the planner drops its goal, as a
        cancel does; returns the goal messages it may still show until the drop is applied (not new goals)."""
        actions, node = self.actions, self.node
        run = actions.run
        reason = f'preempted by a {kind} goal'
        if run is not None:
            actions.finish(run, 'aborted', reason, PREEMPTED)
        if run is not None or node.goal is not None or node.goal_msg is not None:
            node.drop_goal(reason)
        return (node.goal_msg, None if run is None else run.sent)

    def navigation_came(self, run: Behaviour) -> str:
        """A navigation goal that came since `run` began ('' when none): an action's, or one on goal_pose that the
        planner has taken."""
        if self.actions.run is not None:
            return f'a {self.actions.run.kind} goal'
        msg = self.node.goal_msg
        if msg is not None and not any(msg is known for known in run.known):
            return 'a goal on goal_pose'
        return ''

    def check(self) -> None:
        """Every control tick (and wall tick): the end of the behaviour under way by what the planner says (inactive,
        a cancel, a navigation goal, its time_allowance, the robot's pose not known)."""
        run = self.run
        if run is None:
            return
        node = self.node
        came = self.navigation_came(run)
        active = node.lifecycle.is_active
        if run.ended:
            if came or not active:
                self.run = None   # braking after its end: the navigator drives on (or deactivate sent the zero)
            return
        if not active:
            self.finish(run, 'aborted', 'the planner was deactivated')
            self.run = None   # deactivate sent the zero
            return
        if run.goal.handle.is_cancel_requested:
            self.finish(run, 'canceled', 'canceled', 0)
            return
        if came:
            self.finish(run, 'aborted', f'preempted by {came}', PREEMPTED)
            self.run = None
            return
        result = self.served[run.kind].Result
        now = node.now()
        if now > run.deadline:
            self.finish(run, 'aborted', f'time_allowance {run.deadline - run.began:g} s exceeded after '
                        f'{self.told(run)} of {self.told(run, run.target)}', int(result.TIMEOUT))
            return
        if node.hold:
            self.finish(run, 'aborted', f'robot pose not available: {node.hold}', int(result.TF_ERROR))

    def finish(self, run: Behaviour, how: str, message: str, code: int | None = None) -> None:
        """`run`'s goal ends `how`, with its elapsed time; the robot brakes to a stop (`command`)."""
        run.ended = how
        self.reason = f'{run.kind} {how}' + (f': {message}' if how != 'succeeded' else '')
        self.end(run.goal, how, message, code, total_elapsed_time=_duration(self.node.now() - run.began))

    def destroy(self) -> None:
        run = self.run
        if run is not None and not run.ended:
            self.finish(run, 'aborted', 'the planner is shutting down')
        self.run = None

    @staticmethod
    def told(run: Behaviour, value: float | None = None) -> str:
        return f'{run.progress if value is None else value:.3f} {"rad" if run.kind == SPIN else "m"}'

    # ------------------------------------------------------------------------------------------ driving
    def command(self, t: float, state: FloatArray, others: Sequence[OtherRobot]) -> FloatArray | None:
        """The control tick's command at t from `state` (the planner's, in the map frame) while a behaviour runs or
        brakes after its end, within the limits (ramped from the command sent last); None when none does."""
        run, node, nav = self.run, self.node, self.node.navigator
        if run is None or nav is None:
            return None
        limits = nav.limits
        if self.smoother is None or self.smoother.holonomic != bool(nav.model.holonomic):
            self.smoother = VelocitySmoother.for_model(nav.model, limits)
        smoother = self.smoother
        if smoother.limits is not limits:
            smoother.retune(limits)
        sent = np.asarray(node.last_command, dtype=float)
        if not np.array_equal(sent, smoother.velocity):
            smoother.reset(sent)   # what the control loop sent (its guard's stop, a command of the navigator's)
        elapsed = limits.dt if run.last_t is None or not t > run.last_t else t - run.last_t
        run.last_t = t
        wanted = np.zeros(2)
        if not run.ended:
            wanted = self.drive(run, t, np.asarray(state, dtype=float), others, limits)
            run.asked_tick = node.control_count
        command = smoother.smooth(wanted, elapsed)
        if run.ended and not any(c != 0.0 for c in command.tolist()):
            self.run = None   # stopped: the planner's control loop drives from the next tick on
        return command

    def drive(self, run: Behaviour, t: float, state: FloatArray, others: Sequence[OtherRobot],
              limits: Limits) -> FloatArray:
        """The command run wants now (before the ramp), or its end: reached (as odometry shows), a collision
        ahead, a state that is not finite."""
        node, nav = self.node, self.node.navigator
        assert nav is not None
        result = self.served[run.kind].Result
        self.measure(run)
        left = run.target - run.progress
        if left <= REACHED[run.kind]:
            self.publish_feedback(run, t, force=True)
            node.get_logger().info(f'{run.kind} succeeded: {self.told(run)} travelled')
            self.finish(run, 'succeeded', '')
            return np.zeros(2)
        self.publish_feedback(run, t)
        if not np.isfinite(state).all():
            self.finish(run, 'aborted', f'robot state {state.tolist()} is not finite', int(result.TF_ERROR))
            return np.zeros(2)
        control = node.control_tick
        if control is not None and run.asked_tick == node.control_count - 1 and control.reason.startswith('stopped'):
            # The control loop's guard stopped its last command: something within reach it had not seen coming.
            self.finish(run, 'aborted', f'collision ahead: {control.reason}', int(result.COLLISION_AHEAD))
            return np.zeros(2)
        spin = run.kind == SPIN
        if spin:
            rate, deceleration = limits.max_turn_rate or DEFAULT_TURN_RATE, limits.max_turn_acceleration
        else:
            reverse = not nav.model.holonomic and float(run.unit[0]) < 0.0
            rate = (limits.max_reverse_speed if reverse else limits.max_speed) if not nav.model.holonomic else \
                limits.max_speed
            deceleration = limits.max_acceleration
        cruise = rate if spin else (min(run.asked, rate) if rate > 0.0 else run.asked)
        sent = np.asarray(node.last_command, dtype=float)
        speed_now = abs(float(sent[1])) if spin else (math.hypot(*sent) if nav.model.holonomic else abs(float(sent[0])))
        odom = node.inputs.odom
        lag = 0.0 if odom is None else node.inputs.lag(t, odom.stamp)
        left_now = left - lag * speed_now   # odometry a little old: what the last command has driven since
        problem = self.collision(run, state, others, cruise, speed_now, deceleration, left, limits.dt)
        if problem:
            node.get_logger().warning(f'{run.kind}: {problem}')
            self.finish(run, 'aborted', problem, int(result.COLLISION_AHEAD))
            return np.zeros(2)
        return np.asarray(run.unit * min(cruise, stopping_speed(left_now, deceleration, limits.dt)), dtype=float)

    def measure(self, run: Behaviour) -> None:
        """What the newest odometry shows of the run (its own frame: where it started, how far it has turned)."""
        odom = self.node.inputs.odom
        if odom is None or not odom.stamp > run.stamp:
            return
        x, y, yaw = (float(v) for v in odom.pose)
        if run.kind == SPIN:
            run.travelled += math.atan2(math.sin(yaw - run.yaw), math.cos(yaw - run.yaw))
            run.yaw = yaw
        else:
            run.travelled = math.hypot(x - run.start[0], y - run.start[1])
        run.stamp = float(odom.stamp)

    def publish_feedback(self, run: Behaviour, t: float, force: bool = False) -> None:
        if not force and t - run.feedback_at < FEEDBACK_PERIOD - 1e-9:
            return
        run.feedback_at = t
        feedback = self.served[run.kind].Feedback()
        if run.kind == SPIN:
            feedback.angular_distance_traveled = float(run.travelled)
        else:
            feedback.distance_traveled = float(run.travelled)
        run.goal.handle.publish_feedback(feedback)

    def collision(self, run: Behaviour, state: FloatArray, others: Sequence[OtherRobot], cruise: float,
                  speed_now: float, deceleration: float, left: float, dt: float) -> str:
        """Why the motion ahead may not be driven ('' when it may): the robot's disc (its outline, with a
        footprint) swept along SIMULATE_AHEAD s of it at the cruise speed, at least the way to stop from the speed
        now and a tick, never past the end, meets an obstacle surface, another robot, the map's border
        (recovery.reverse_free: no nearer than now where it is near already) or a return of the latest scan; a
        steered robot reversing with a laser: space no recent scan has seen free (as the control loop's reverse
        check)."""
        nav = self.node.navigator
        assert nav is not None
        footprint, model = nav.footprint, nav.model
        spin = run.kind == SPIN
        if spin and footprint is None:
            return ''   # a disc turning in place sweeps nothing new
        stop = speed_now * dt + (speed_now * speed_now / (2.0 * deceleration) if deceleration > 0.0 else 0.0)
        reach = min(max(SIMULATE_AHEAD * cruise, stop + cruise * dt), left + REACHED[run.kind])
        if not (reach > 0.0 and cruise > 0.0):
            return ''
        command, horizon = run.unit * cruise, reach / cruise
        unit = 'rad' if spin else 'm'
        perceived = nav.guard_inputs
        others = inflated(others, nav.outline_extra)   # kept from the circumscribed circle (outline.py)
        body = 'outline' if footprint is not None else 'disc'
        world = self.near_world(run, state, (nav.radius if footprint is None else footprint.radius) +
                                perceived.obstacle_margin + (0.0 if spin else reach))
        if not reverse_free(model, state, nav.radius, command, horizon, world, None, others,
                            perceived.obstacle_margin, footprint):
            return f'collision ahead: the robot\'s {body} would meet an obstacle, a robot or the map\'s border ' \
                   f'within {reach:.2f} {unit}'
        if self.laser_hit(state, command, horizon, reach if not spin else 0.0):
            return f'collision ahead: the laser shows an obstacle within {reach:.2f} {unit}'
        if perceived.seen is not None and not model.holonomic and float(command[0]) < 0.0 and \
                not reverse_free(model, state, nav.radius, command, horizon, world, perceived.seen, (),
                                 perceived.obstacle_margin, footprint):
            return f'collision ahead: no evidence the space behind is free (no recent scan has seen it) within ' \
                   f'{reach:.2f} m'
        return ''

    def near_world(self, run: Behaviour, state: FloatArray, reach: float) -> World:
        """The world with only the obstacles within `reach` + NEAR_ROOM of a centre the robot is within NEAR_ROOM of
        (made again when it leaves, or the world changes): an obstacle farther off is beyond `reach` of every point
        the motion checked comes to, so it decides nothing, and a map of thousands of walls cost 3 ms a tick."""
        nav = self.node.navigator
        assert nav is not None
        world = nav.world
        here = np.asarray(state[:2], dtype=float)
        near = run.near
        if near is None or near[0] is not world or math.hypot(*(here - near[1])) + reach > near[2]:
            room = reach + NEAR_ROOM
            obstacles = world.obstacles
            kept = world if not len(obstacles) else \
                World(world.workspace, obstacles.subset(obstacles.distances(here) <= room).items)
            near = run.near = (world, here, room, kept)
        return near[3]

    def laser_hit(self, state: FloatArray, command: FloatArray, horizon: float, travel: float) -> bool:
        """Does the motion (`command` held for `horizon` s, `travel` m of it) bring the robot's disc (outline) over a
        return of the latest scan, nearer than it is now (the guard's rule, along the whole motion)?"""
        nav = self.node.navigator
        assert nav is not None
        returns = nav.guard_inputs.scan_points
        if returns is None or not len(returns.points):
            return False
        footprint = nav.footprint if not nav.model.holonomic else None
        reach = nav.radius if footprint is None else footprint.radius
        points = returns.points
        here = state[:2]
        near = points[np.hypot(points[:, 0] - here[0], points[:, 1] - here[1]) <= reach + travel + 1e-6]
        if not len(near):
            return False
        if footprint is not None:
            poses = predicted_poses(nav.model, state, command, horizon, footprint.radius)
            gaps = footprint.circle_distances(poses, near, np.zeros(len(near))).min(axis=-1)
            then, now = float(gaps[1:].min()), float(gaps[0])
            return then < 0.0 and then < now
        centres = swept_centres(nav.model, state, command, horizon, max(nav.radius, 0.01) / 4.0)
        then = float(point_segment_distance(near[:, None, :], centres[:-1], centres[1:]).min())
        now = float(np.hypot(near[:, 0] - here[0], near[:, 1] - here[1]).min())
        return then < nav.radius and then < now


# ------------------------------------------------------------------------------------------------ the planner's hook
def _running(node: Any) -> BehaviourActions | None:
    actions = getattr(node, 'actions', None)
    companion = None if actions is None else actions.handled_by.get(SPIN)
    return companion if isinstance(companion, BehaviourActions) and companion.run is not None else None


def behaviour_command(node: Any, t: float, state: FloatArray, others: Sequence[OtherRobot]) -> FloatArray | None:
    """The command of the behaviour under way on the planner `node` at t (None: none runs): lock step's hook, where
    the control tick sends the navigator's command as it is."""
    behaviours = _running(node)
    return None if behaviours is None else behaviours.command(t, state, others)


def behaviour_plan(node: Any, t: float, state: FloatArray, others: Sequence[OtherRobot],
                   plan: Plan | None) -> Plan | None:
    """What the control loop drives on at t: the behaviour's command while one runs (a plan holding it, with the
    movers the newest pass tracked, so that the control loop's smoother, guard and yielding treat it as any command
    and measure the base against what it sends), else `plan`."""
    behaviours, nav = _running(node), node.navigator
    if behaviours is None or nav is None:
        return plan
    movers = () if plan is None else tuple(plan.movers_at(t))
    command = behaviours.command(t, state, [*others, *movers])
    if command is None:
        return plan
    return Plan(t, None, command, nav.world, movers, Mode.KINEMATIC, behaviours.reason)


def _seconds(duration: Any) -> float:
    """A builtin_interfaces Duration in seconds (0 for none or one that is not finite)."""
    if duration is None:
        return 0.0
    value = float(duration.sec) + float(duration.nanosec) * 1e-9
    return value if math.isfinite(value) else 0.0


def _duration(seconds: float) -> Any:
    from builtin_interfaces.msg import Duration
    seconds = max(0.0, min(seconds, 2.0 ** 31 - 1))
    whole = math.floor(seconds)
    return Duration(sec=int(whole), nanosec=min(int((seconds - whole) * 1e9), 999_999_999))
