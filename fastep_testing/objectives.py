"""Test objectives shared by the optimizer tests (vectorised: (m, d) -> (m,))."""

import numpy as np

BOX = [[-2.0, 2.0], [-2.0, 2.0]]
RASTRIGIN_BOX = [[-5.12, 5.12], [-5.12, 5.12]]


def shifted_sphere(centre):
    """The sphere with its minimum (0) at `centre`: each optimizer's tests use their own centre."""
    centre = np.asarray(centre, dtype=float)
    return lambda X: np.sum((X - centre) ** 2, axis=1)


def rastrigin(X):
    return 10.0 * X.shape[1] + np.sum(X ** 2 - 10.0 * np.cos(2.0 * np.pi * X), axis=1)


class Recorder:
    """A vectorised objective that keeps every batch it is called with."""

    def __init__(self, fun):
        self.fun = fun
        self.batches = []

    def __call__(self, X):
        assert X.ndim == 2
        self.batches.append(np.array(X, copy=True))
        return self.fun(X)

    @property
    def points(self):
        return np.concatenate(self.batches)
