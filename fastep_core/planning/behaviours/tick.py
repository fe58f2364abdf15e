"""What a behaviour sees of one control tick (`Tick`), and what it may ask of its navigator (`Steering`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, Sequence

import numpy as np
from numpy.typing import NDArray

from fastep_core.footprint import Footprint
from fastep_core.kinematics.model import RobotModel
from fastep_core.planning.mode import Mode
from fastep_core.planning.others import OtherRobot
from fastep_core.planning.params import PlannerParams
from fastep_core.planning.recovery.back_up import SeenFree
from fastep_core.planning.recovery.progress import ProgressChecker, TrapDetector
from fastep_core.planning.safety.base_response import BaseResponse, ShownResponse
from fastep_core.planning.safety.yielding import Yield
from fastep_core.planning.shortest_path.optimal import OptimalPath
from fastep_core.world import World

__all__ = ['FloatArray', 'Steering', 'Tick']

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class Tick:
    """One control tick as the behaviours see it: the robot, the goal and the world believed now."""

    number: int                    # the navigator's count of ticks
    t: float
    dt: float
    state: FloatArray              # finite
    position: FloatArray           # state[:2]
    others: Sequence[OtherRobot]   # with finite positions
    distance: float                # to the goal
    velocity: FloatArray           # what the base does now, measured (the model's command form), finite
    goal: FloatArray
    goal_heading: float | None     # the heading to end in, if any
    world: World                   # what the robot knows now
    base: BaseResponse | ShownResponse   # what the base has measurably done (its braking)
    last_command: FloatArray | None      # the controller's last command, if it keeps one (acceleration limits)


class Steering(Protocol):
    """What a behaviour reads and calls of its navigator (navigator.py): the robot it plans for, the goal's
    status and clocks, and the moves every behaviour drives with (guarded, through the controller)."""

    params: PlannerParams
    model: RobotModel
    radius: float
    footprint: Footprint | None
    escapes_traps: bool
    # The goal's status, which the behaviours set.
    mode: Mode
    reason: str
    waypoint: FloatArray | None
    cost: float
    committed: bool                # drive the waypoint to its end (a step that broke a hold)
    reference: OptimalPath | None  # the goal's exact shortest path (PathCheck)
    escapes: int
    yield_kind: str
    # The goal's clocks: progress of any kind restarts them.
    progress: ProgressChecker
    trap: TrapDetector

    @property
    def target(self) -> FloatArray | None: ...
    @property
    def path_world(self) -> World: ...
    @property
    def seen(self) -> SeenFree | None: ...
    @property
    def obstacle_margin(self) -> float: ...
    @property
    def failed(self) -> bool: ...
    @property
    def step_deferred(self) -> bool: ...
    @property
    def step_pending_tick(self) -> int: ...
    def clear_target(self) -> None: ...
    def guard(self, state: FloatArray, command: FloatArray, dt: float,
              others: Sequence[OtherRobot]) -> FloatArray: ...
    def fail(self, reason: str) -> None: ...
    def fail_no_path(self, position: FloatArray) -> None: ...
    def exact_path(self, position: FloatArray, others: Sequence[OtherRobot] = ()) -> OptimalPath | None: ...
    def keep_waypoint(self, position: FloatArray, others: Sequence[OtherRobot]) -> bool: ...
    def start_escape(self, position: FloatArray, distance: float, t: float,
                     others: Sequence[OtherRobot] = ()) -> bool: ...
    def start_manoeuvre(self, state: FloatArray, t: float, others: Sequence[OtherRobot]) -> bool: ...
    def plan_next_step(self, position: FloatArray, others: Sequence[OtherRobot]) -> FloatArray | None: ...
    def yield_to_movers(self, state: FloatArray, command: FloatArray, dt: float,
                        others: Sequence[OtherRobot]) -> Yield: ...
    def choose_target(self, position: FloatArray, others: Sequence[OtherRobot]) -> FloatArray | None: ...
    def drive_to(self, state: FloatArray, target: FloatArray, t: float, dt: float,
                 others: Sequence[OtherRobot]) -> FloatArray: ...
