"""The result every optimizer in this package returns, and the plumbing they all share.

All optimizers here (FAStep, the standard firefly algorithm, ACO_R) minimise a *vectorised* objective over a box,
with every random draw taken from one `numpy.random.Generator` so that a seed reproduces a run bit for bit. What
they share is kept next to `OptimizeResult`, much as scipy keeps its result type next to its common helpers:

- `check_problem` turns `bounds`, `rng` and `x0` into arrays and a Generator, rejecting malformed input with a
  one-line `ParameterError`;
- `Objective` wraps the user's function: counts evaluated points (`nfev`), checks one value per candidate and
  maps NaN to +inf. Its batches are (m, d) float arrays, not necessarily C-contiguous: objectives must not
  depend on the memory layout;
- `initial_population` draws the uniform start population and lets `x0` replace its first rows.

The optimizers only *compare* objective values, never subtract them, so +inf or huge values (the planner
scores infeasible candidates 1e6 + violation) need no special care.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from fastep_core.errors import ParameterError

__all__ = ['OptimizeResult']

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]
VectorisedFunction = Callable[[FloatArray], ArrayLike]
RngLike = np.random.Generator | int | None


@dataclass(frozen=True)
class OptimizeResult:
    """Outcome of one optimisation run.

    x: best point found, shape (d,).
    fun: its objective value.
    nit: iterations performed (<= max_iter; fewer when the run stopped for lack of improvement).
    nfev: number of points evaluated, the initial population included.
    history: best objective value after each iteration, shape (nit,), non-increasing.
    """

    x: FloatArray
    fun: float
    nit: int
    nfev: int
    history: FloatArray


class Objective:
    """The user's vectorised objective, with the bookkeeping every optimizer needs."""

    def __init__(self, fun: VectorisedFunction) -> None:
        if not callable(fun):
            raise ParameterError(f'the objective must be callable, got {type(fun).__name__}')
        self.fun = fun
        self.nfev = 0

    def __call__(self, X: FloatArray) -> FloatArray:
        m = X.shape[0]
        f = np.asarray(self.fun(X), dtype=np.float64)
        if f.shape != (m,):
            raise ParameterError(f'the objective must return one value per candidate, shape ({m},); '
                                 f'got shape {f.shape}')
        self.nfev += m
        if m and np.isnan(np.minimum.reduce(f)):       # NaN propagates through the minimum
            f = np.where(np.isnan(f), np.inf, f)
        return f


Problem = tuple[FloatArray, FloatArray, np.random.Generator, FloatArray | None]


def check_problem(bounds: ArrayLike, rng: RngLike, x0: ArrayLike | None, n_pop: int) -> Problem:
    """Validate the problem description; return (low, high, generator, x0 as a (k, d) array or None)."""
    b = np.asarray(bounds, dtype=np.float64)
    if b.ndim != 2 or b.shape[1] != 2 or b.shape[0] < 1:
        raise ParameterError(f'bounds must have shape (d, 2) with d >= 1, got shape {b.shape}')
    if not np.all(np.isfinite(b)):
        raise ParameterError('bounds must be finite')
    low, high = b[:, 0].copy(), b[:, 1].copy()
    if np.any(low > high):
        raise ParameterError('every lower bound must be <= its upper bound')
    if x0 is not None:
        x0 = np.asarray(x0, dtype=np.float64)
        if x0.ndim == 1:
            x0 = x0[None, :]
        if x0.ndim != 2 or x0.shape[1] != b.shape[0]:
            raise ParameterError(f'x0 must have shape (k, {b.shape[0]}), got shape {x0.shape}')
        if x0.shape[0] > n_pop:
            raise ParameterError(f'x0 has {x0.shape[0]} rows but the population holds only {n_pop}')
        if not np.all(np.isfinite(x0)):
            raise ParameterError('x0 must be finite')
    if not isinstance(rng, np.random.Generator) and rng is not None and not isinstance(rng, (int, np.integer)):
        raise ParameterError(f'rng must be a numpy Generator, an int seed or None, got {type(rng).__name__}')
    return low, high, np.random.default_rng(rng), x0


def check_count(name: str, value: int, low: int) -> None:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < low:
        raise ParameterError(f'{name} must be an integer >= {low}, got {value!r}')


def check_number(name: str, value: float, low: float = 0.0) -> None:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.number)) \
            or not np.isfinite(value) or value < low:
        raise ParameterError(f'{name} must be a finite number >= {low}, got {value!r}')


def initial_population(n: int, low: FloatArray, high: FloatArray, rng: np.random.Generator,
                       x0: FloatArray | None) -> FloatArray:
    """n points uniform in the box; the first k are replaced by x0 (clipped into the box) when given.

    The full uniform draw is taken even when x0 is given, so the random stream does not depend on k.
    """
    X = rng.uniform(low, high, size=(n, low.size))
    if x0 is not None:
        X[:x0.shape[0]] = np.clip(x0, low, high)
    return X
