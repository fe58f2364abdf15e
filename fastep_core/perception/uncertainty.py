"""How far a scan's origin may be from where the robot's localization puts it, and what that makes of each return.

A scan is placed at the robot's estimated pose. When the estimate is off by a translation e and a yaw error psi,
a return at range r lands up to e + psi r from where it truly is (the yaw turns it about the scanner), so a mapped
wall's returns lie beside the map's wall by up to that much, and more so the farther they are. `PoseUncertainty`
is that bound (the scanner's translation and yaw error, in metres and radians) and `slack` its share for each
return; perception (belief.Perception) counts a return within EXPLAINED plus its slack of a mapped obstacle as that
obstacle, not a new one, and a beam as seeing through a mapped obstacle only past its slack.

The bound comes from whatever the robot knows of its localization: a fixed tolerance, a localizer's pose covariance
(`from_covariance`: geometry_msgs/PoseWithCovarianceStamped's, SIGMAS standard deviations), and without a localizer
an odometry drift bound that grows with the distance driven (`OdometryDrift`). Never more than MAX_SLACK per
return: beyond that the map says little about where the robot is, and a looser match would hide what is really
new beside the map's obstacles (the guard still stops at every return: planning/safety/guard.py).

`PoseError` is the simulator's side (fastep_core/simulator.py, off by default): a localization that is off the
truth by a constant offset and a drift that grows with the distance driven, seeded.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ['MAX_SLACK', 'NO_DRIFT', 'NO_UNCERTAINTY', 'SIGMAS', 'OdometryDrift', 'PoseError', 'PoseUncertainty']

FloatArray = NDArray[np.float64]

SIGMAS = 3.0
"""Standard deviations of a pose covariance taken as its bound (3: 99.7 % of a normal error's yaw)."""
MAX_SLACK = 0.5
"""Metres: the most a return's position may be off by pose uncertainty for perception's match (module docstring)."""


@dataclass(frozen=True)
class PoseUncertainty:
    """A bound on the error of the pose a scan is placed at: `translation` metres and `yaw` radians."""

    translation: float = 0.0
    yaw: float = 0.0

    def __post_init__(self) -> None:
        if not (self.translation >= 0.0 and self.yaw >= 0.0 and math.isfinite(self.translation) and
                math.isfinite(self.yaw)):
            raise ValueError(f'pose uncertainty must be finite and >= 0 (translation {self.translation} m, '
                             f'yaw {self.yaw} rad)')

    @property
    def none(self) -> bool:
        return self.translation == 0.0 and self.yaw == 0.0

    def slack(self, ranges: ArrayLike) -> FloatArray:
        """How far each return at these ranges from the scanner may be from where it is placed (at most
        MAX_SLACK)."""
        slack: FloatArray = np.minimum(self.translation + self.yaw * np.asarray(ranges, dtype=float), MAX_SLACK)
        return slack

    def __add__(self, other: PoseUncertainty) -> PoseUncertainty:
        """Two independent bounds on one pose (a tolerance and a covariance's, a localizer's and the odometry's
        since its last fix): their sum, the worst case."""
        return PoseUncertainty(self.translation + other.translation, self.yaw + other.yaw)

    @classmethod
    def from_covariance(cls, covariance: Sequence[float] | ArrayLike, sigmas: float = SIGMAS) -> PoseUncertainty:
        """The bound of a pose covariance: a 6 x 6 (x, y, z, roll, pitch, yaw) as geometry_msgs'
        PoseWithCovariance carries it (36 values, row-major), or 3 x 3 (x, y, yaw). Translation: `sigmas` times the
        standard deviation along the worst direction in the plane (the xy block's largest eigenvalue); yaw:
        `sigmas` times yaw's. NaN or negative variances (a localizer that does not know) give no bound: ValueError."""
        matrix = np.asarray(covariance, dtype=float)
        size = 6 if matrix.size == 36 else 3 if matrix.size == 9 else 0
        if not size:
            raise ValueError(f'a pose covariance has 36 (6 x 6) or 9 (3 x 3) values, not {matrix.size}')
        matrix = matrix.reshape(size, size)
        yaw_index = size - 1
        plane = matrix[:2, :2]
        if not np.isfinite(matrix[np.ix_([0, 1, yaw_index], [0, 1, yaw_index])]).all() or \
                plane[0, 0] < 0.0 or plane[1, 1] < 0.0 or matrix[yaw_index, yaw_index] < 0.0:
            raise ValueError('a pose covariance with a nan or negative variance bounds nothing')
        worst = float(np.linalg.eigvalsh(0.5 * (plane + plane.T))[-1])
        return cls(sigmas * math.sqrt(max(worst, 0.0)), sigmas * math.sqrt(float(matrix[yaw_index, yaw_index])))


NO_UNCERTAINTY = PoseUncertainty()


@dataclass(frozen=True)
class OdometryDrift:
    """A bound on wheel odometry's drift per metre driven: `translation` m/m (a wheel's scale error, slip) and
    `yaw` rad/m (the heading's drift). After driving s metres the heading may be off by yaw s and the position by
    translation s + yaw s^2 / 2 (the heading error, growing, turns each later metre: the integral of yaw s')."""

    translation: float = 0.0
    yaw: float = 0.0

    def bound(self, distance: float) -> PoseUncertainty:
        s = max(float(distance), 0.0)
        return PoseUncertainty(self.translation * s + 0.5 * self.yaw * s * s, self.yaw * s)


NO_DRIFT = OdometryDrift()


@dataclass
class PoseError:
    """A simulated localization off the truth (fastep_core/simulator.py): a constant `offset` (dx, dy, dyaw) plus
    a drift that grows with the distance driven, `drift` (m/m, rad/m) as OdometryDrift bounds it, its directions
    drawn once from `seed`. The estimate turns about the start as the heading drifts (as integrated odometry does:
    by the mean drift so far) and slides along a fixed direction as the translation drifts. `told` and
    `told_drift`: the uncertainty the robot's perception is told, a fixed part and a drift bound (both None: told
    nothing, perception as without a PoseError)."""

    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    drift: OdometryDrift = NO_DRIFT
    seed: int = 0
    told: PoseUncertainty | None = None
    told_drift: OdometryDrift | None = None
    robot: int = 0        # whose: each robot's drift its own directions

    def __post_init__(self) -> None:
        rng = np.random.default_rng(np.random.SeedSequence(self.seed, spawn_key=(0x6C6F63, self.robot)))   # 'loc'
        angle = float(rng.uniform(-math.pi, math.pi))
        self._slide = (math.cos(angle), math.sin(angle))
        self._turn = 1.0 if rng.random() < 0.5 else -1.0
        self._start: tuple[float, float] | None = None
        self._last: tuple[float, float] | None = None
        self.distance = 0.0   # metres driven (true), what the drift grows with
        self.heading_error = self.offset[2]   # radians the estimate's heading is off (a point mass's scanner too)

    def estimate(self, state: FloatArray) -> FloatArray:
        """The pose the robot believes it has, for its true state (x, y[, theta, ...]); called once per tick."""
        x, y = float(state[0]), float(state[1])
        if self._start is None:
            self._start = self._last = (x, y)
        assert self._last is not None
        self.distance += math.hypot(x - self._last[0], y - self._last[1])
        self._last = (x, y)
        s = self.distance
        drifted = self._turn * self.drift.yaw * s
        psi = self.heading_error = self.offset[2] + drifted
        slide = self.drift.translation * s
        # The way driven turned by the heading's mean drift along it (half the drift now): on a straight run the
        # position is then off by yaw s^2 / 2 across it, as OdometryDrift bounds it.
        c, n = math.cos(0.5 * drifted), math.sin(0.5 * drifted)
        sx, sy = self._start
        out = np.array(state, dtype=float)
        out[0] = sx + c * (x - sx) - n * (y - sy) + self.offset[0] + slide * self._slide[0]
        out[1] = sy + n * (x - sx) + c * (y - sy) + self.offset[1] + slide * self._slide[1]
        if len(out) > 2:
            out[2] = math.atan2(math.sin(state[2] + psi), math.cos(state[2] + psi))
        return out

    def uncertainty(self) -> PoseUncertainty | None:
        """What the robot's perception is told now: `told`, plus `told_drift`'s bound for the distance driven."""
        if self.told is None and self.told_drift is None:
            return None
        told = self.told or PoseUncertainty()
        return told if self.told_drift is None else told + self.told_drift.bound(self.distance)
