"""A simulated robot's senses: each tick its scanner reads the true world and its perception updates its belief.

What the in-process simulator calls for a robot with a `sensor` (fastep_core/simulator.py): the scan is of
the truth (every still obstacle, known or not, where it really is; every mover where it is now; the other
robots as circles of their radius), its noise drawn from the robot's own stream (belief.sensor_generator);
the navigator is given the belief's world (only when it changed) and, beside the other robots and known
movers it is told of, the movers it tracks. With a `PoseError` (perception/uncertainty.py, off by default) the
scan is still taken from the true pose but placed at the estimate, as a robot whose localization is off does.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from fastep_core.dynamic_world import DynamicWorld
from fastep_core.perception.belief import Belief, Perception, heading, perception_margin, sensor_generator
from fastep_core.perception.uncertainty import PoseError
from fastep_core.planning.navigator import Navigator
from fastep_core.planning.others import OtherRobot
from fastep_core.planning.recovery.back_up import RecentScans
from fastep_core.planning.safety.guard import ScanReturns
from fastep_core.planning.safety.guard_inputs import GuardInputs
from fastep_core.sensing.laser import LaserSpec

__all__ = ['SensingRobot']

FloatArray = NDArray[np.float64]


class SensingRobot:
    """One robot's scanner and perception in a simulated run."""

    def __init__(self, spec: LaserSpec, model: str, index: int, truth: DynamicWorld, navigator: Navigator,
                 seed: int, pose_error: PoseError | None = None) -> None:
        self.spec, self.model, self.index, self.truth = spec, model, index, truth
        self.pose_error = pose_error
        self.rng = sensor_generator(seed, index)
        self.perception = Perception(spec, navigator.world)
        navigator.take_perception(GuardInputs(perception_margin(spec)))

    @property
    def recent(self) -> RecentScans:
        """The free space its recent scans saw: where it may back up (planning/control.py)."""
        return self.perception.recent

    @property
    def belief(self) -> Belief:
        return self.perception.belief

    def sense(self, navigator: Navigator, t: float, state: FloatArray, others: Sequence[OtherRobot],
              robots: Sequence[OtherRobot], estimate: FloatArray | None = None) -> list[OtherRobot]:
        """Scan the truth at t from state, update the belief, give the navigator its world; returns what the
        navigator sees move: `others` (what it is told of) and the movers it tracks. `robots`: every robot at
        its true place (this one among them, left out of the scan). `estimate`: where the robot believes it is
        (pose_error's), where the scan is placed; None: at state."""
        visible = [r for k, r in enumerate(robots) if k != self.index]
        centres = np.array([r.position for r in visible], dtype=float).reshape(-1, 2)
        radii = np.array([r.radius for r in visible], dtype=float)
        pose = self.spec.pose_on((float(state[0]), float(state[1]), heading(self.model, state)))   # the scanner's
        scan = self.truth.scan(self.spec, pose, t, self.rng, (centres, radii))
        error = self.pose_error
        uncertainty = None
        if estimate is not None and error is not None:
            turned = heading(self.model, estimate) + (error.heading_error if self.model == 'point_mass' else 0.0)
            pose = self.spec.pose_on((float(estimate[0]), float(estimate[1]), turned))
            state, uncertainty = estimate, error.uncertainty()
        belief = self.perception.update(t, pose, scan, others, uncertainty=uncertainty)
        returns = ScanReturns(self.perception.returns, state, navigator.radius)
        navigator.take_perception(replace(navigator.guard_inputs, scan_points=returns, taken=t), belief.world)
        return [*others, *belief.movers]
