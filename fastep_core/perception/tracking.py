"""Tracks of circular obstacles over time: a constant-velocity Kalman filter per track, data association by
the Hungarian method with a chi-square gate, and track birth, confirmation and deletion.

A small numpy Kalman filter (filterpy would fit, but is unmaintained since 2018 and one 4-state model does not
need it), all tracks filtered at once as arrays (n, 4) and (n, 4, 4). The model is the discrete
white-noise-acceleration constant-velocity model (Bar-Shalom, Li and Kirubarajan 2001, section 6.3.2): state
[x, y, vx, vy], F = [[I, dt I], [0, I]], Q = q [[dt^4/4 I, dt^3/2 I], [dt^3/2 I, dt^2 I]], position measured
with H = [I 0], R = r^2 I; predict and update as in Thrun, Burgard and Fox (2005), table 3.1.
Association: the cost of pairing track i with detection j is the Mahalanobis distance of the innovation; pairs
beyond the 99 % chi-square gate of 2 degrees of freedom (9.21), or farther than GATE_DISTANCE apart, are not
allowed; scipy.optimize.linear_sum_assignment picks the pairing of least total cost. Unpaired detections start
tentative tracks; a track seen CONFIRM_HITS times is confirmed; one not seen for MAX_COAST seconds is deleted.
Nothing here draws random numbers.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = ['CONFIRM_HITS', 'GATE', 'GATE_DISTANCE', 'MAX_COAST', 'TrackParams', 'Tracker']

FloatArray = NDArray[np.float64]

GATE = 9.21            # chi-square, 2 degrees of freedom, 99 %
GATE_DISTANCE = 2.0    # metres: never pair farther apart (a tentative track's large covariance would allow it)
CONFIRM_HITS = 3
MAX_COAST = 1.0        # seconds a track lives unseen (occlusions), predicted at constant velocity


@dataclass(frozen=True)
class TrackParams:
    """The filter's noise: q (m^2/s^3, acceleration spectral density), r (m, measurement standard deviation of
    a fitted centre), the initial velocity standard deviation (m/s)."""

    q: float = 0.5
    r: float = 0.05
    velocity_sigma: float = 1.0
    radius_gain: float = 0.2     # exponential smoothing of the fitted radius


class Tracker:
    """Every track of one robot: states (n, 4), covariances (n, 4, 4), radii, hits, last seen, ids, where each
    was confirmed (origins (n, 2): its position then) and whether its user found it moving (moved)."""

    def __init__(self, params: TrackParams | None = None) -> None:
        # Imported with the first tracker (a robot with a laser), not with the module (scipy.optimize costs ~0.3 s
        # of import in every planner process) nor on the first association: that stalled a moving robot's planning
        # for 0.37 s (the robot harness, docs/benchmarks.md).
        from scipy.optimize import linear_sum_assignment
        self._assign = linear_sum_assignment
        self.params = params or TrackParams()
        self.states = np.zeros((0, 4))
        self.covariances = np.zeros((0, 4, 4))
        self.radii = np.zeros(0)
        self.hits = np.zeros(0, dtype=np.int64)
        self.born = np.zeros(0)
        self.seen = np.zeros(0)
        self.ids = np.zeros(0, dtype=np.int64)
        self.origins = np.zeros((0, 2))
        self.moved = np.zeros(0, dtype=bool)
        self._next_id = 0
        self._t: float | None = None

    def __len__(self) -> int:
        return len(self.radii)

    @property
    def time(self) -> float:
        """The time of the last update (-inf before the first)."""
        return -np.inf if self._t is None else self._t

    @property
    def confirmed(self) -> NDArray[np.bool_]:
        return self.hits >= CONFIRM_HITS

    def predict(self, t: float) -> None:
        """Move every track to time t (predict step)."""
        dt = 0.0 if self._t is None else max(t - self._t, 0.0)
        self._t = t
        if dt == 0.0 or not len(self):
            return
        f = np.eye(4)
        f[0, 2] = f[1, 3] = dt
        # Q = q [[dt^4/4 I, dt^3/2 I], [dt^3/2 I, dt^2 I]], written out (np.block costs more than the filter).
        a, b, c = dt ** 4 / 4, dt ** 3 / 2, dt ** 2
        noise = self.params.q * np.array([[a, 0.0, b, 0.0], [0.0, a, 0.0, b], [b, 0.0, c, 0.0], [0.0, b, 0.0, c]])
        self.states = self.states @ f.T
        self.covariances = f @ self.covariances @ f.T + noise

    def update(self, t: float, centres: FloatArray, radii: FloatArray) -> None:
        """One scan's circle detections at time t: predict, associate, update, start and delete tracks."""
        self.predict(t)
        r2 = self.params.r ** 2
        paired_tracks = np.zeros(0, dtype=np.int64)
        paired_detections = np.zeros(0, dtype=np.int64)
        if len(self) and len(centres):
            s = self.covariances[:, :2, :2] + r2 * np.eye(2)                       # (n, 2, 2)
            inverse = np.linalg.inv(s)
            y = centres[None, :, :] - self.states[:, None, :2]                       # (n, m, 2)
            cost = np.einsum('nmi,nij,nmj->nm', y, inverse, y)
            allowed = (cost <= GATE) & (np.hypot(y[..., 0], y[..., 1]) <= GATE_DISTANCE)
            rows, cols = self._assign(np.where(allowed, cost, 1e6))
            good = allowed[rows, cols]
            paired_tracks, paired_detections = rows[good], cols[good]
            if len(paired_tracks):
                p = self.covariances[paired_tracks]
                gain = p[:, :, :2] @ inverse[paired_tracks]                          # K = P H^T S^-1, (k, 4, 2)
                innovation = y[paired_tracks, paired_detections]
                self.states[paired_tracks] += np.einsum('kij,kj->ki', gain, innovation)
                self.covariances[paired_tracks] = p - gain @ p[:, :2, :]             # (I - K H) P
                a = self.params.radius_gain
                self.radii[paired_tracks] += a * (radii[paired_detections] - self.radii[paired_tracks])
                self.hits[paired_tracks] += 1
                self.seen[paired_tracks] = t
                confirmed_now = paired_tracks[self.hits[paired_tracks] == CONFIRM_HITS]
                self.origins[confirmed_now] = self.states[confirmed_now, :2]
        # Births: every detection no track took.
        unpaired = np.ones(len(centres), dtype=bool)
        unpaired[paired_detections] = False
        fresh = np.flatnonzero(unpaired)
        if len(fresh):
            k = len(fresh)
            states = np.column_stack([centres[fresh], np.zeros((k, 2))])
            cov = np.zeros((k, 4, 4))
            cov[:, 0, 0] = cov[:, 1, 1] = r2
            cov[:, 2, 2] = cov[:, 3, 3] = self.params.velocity_sigma ** 2
            self.states = np.concatenate([self.states, states])
            self.covariances = np.concatenate([self.covariances, cov])
            self.radii = np.concatenate([self.radii, radii[fresh]])
            self.hits = np.concatenate([self.hits, np.ones(k, dtype=np.int64)])
            self.born = np.concatenate([self.born, np.full(k, t)])
            self.seen = np.concatenate([self.seen, np.full(k, t)])
            self.ids = np.concatenate([self.ids, self._next_id + np.arange(k)])
            self.origins = np.concatenate([self.origins, centres[fresh]])
            self.moved = np.concatenate([self.moved, np.zeros(k, dtype=bool)])
            self._next_id += k
        self.keep(t - self.seen <= MAX_COAST)

    def keep(self, keep: NDArray[np.bool_]) -> None:
        """Drop the tracks where keep is false."""
        if keep.all():
            return
        for name in ('states', 'covariances', 'radii', 'hits', 'born', 'seen', 'ids', 'origins', 'moved'):
            setattr(self, name, getattr(self, name)[keep])
