"""The standard firefly algorithm (Yang 2008), vectorised: the baseline FAStep builds on.

Why it is here: FAStep (`fastep.py`) is this algorithm plus stepping ahead and a preference rule, so the shared
machinery (`Swarm`: ranking, the attraction move, candidate generation) lives here, and `firefly()` lets a benchmark
show what stepping ahead adds. The attraction move is the paper's eq. 3 with the sign of the pull corrected (as
printed it pushes firefly i away from the brighter j): c_ij = x_i + beta0 exp(-gamma r_ij^2) (x_j - x_i) +
alpha_t eps_ij span, for every pair with j strictly brighter; r_ij is measured in box diagonals so gamma means the
same in every box, eps is uniform in [-0.5, 0.5]^d, and a firefly nobody outshines walks randomly (the pair (i, i)).
Candidates are clipped into the box; alpha_t = alpha alpha_damping^t. Each iteration ranks the swarm (a stable sort,
changing no move), builds all candidates from the iteration's start positions and evaluates them in ONE objective
call; each firefly moves to its best candidate even when worse (Yang's classic behaviour, no selection), while the
best point ever evaluated is kept apart (elitism). Random draws, in order: the initial population
(`rng.uniform(low, high, (n, d))`), then per iteration one `rng.random((d, m))` block, column p the p-th pair in
row-major order of the ranked swarm.
"""

from __future__ import annotations

import functools
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from fastep_core.optimize.result import (
    FloatArray,
    IntArray,
    Objective,
    OptimizeResult,
    RngLike,
    VectorisedFunction,
    check_count,
    check_number,
    check_problem,
    initial_population,
)

__all__ = ['firefly']


def firefly(fun: VectorisedFunction, bounds: ArrayLike, *, n_fireflies: int = 50, max_iter: int = 30,
            patience: int = 5, gamma: float = 1.0, beta0: float = 2.0, alpha: float = 0.2,
            alpha_damping: float = 0.8, tol: float = 0.0, rng: RngLike = None,
            x0: ArrayLike | None = None) -> OptimizeResult:
    """Minimise a vectorised function over a box with the standard firefly algorithm.

    Parameters are those of `fastep` (Table 1 of the paper as defaults): `fun` maps an (m, d) array of
    candidates to an (m,) array of values; `bounds` is (d, 2) of [low, high]; the run stops after `max_iter`
    iterations or after `patience` consecutive iterations without improvement of the best value.
    """
    _check_swarm_parameters(n_fireflies, max_iter, patience, gamma, beta0, alpha, alpha_damping)
    check_number('tol', tol)
    low, high, gen, x0 = check_problem(bounds, rng, x0, n_fireflies)
    objective = Objective(fun)
    swarm = Swarm(n_fireflies, low, high, gamma=gamma, beta0=beta0)

    X = initial_population(n_fireflies, low, high, gen, x0).T.copy()   # (d, n): see Swarm
    F = objective(X.T)
    elite = Elite(X, F, tol=tol, patience=patience)

    alpha_t = float(alpha)
    for _ in range(max_iter):
        X, F = swarm.rank(X, F)
        # Classic behaviour: every firefly moves to its best candidate, better or not.
        X, F = swarm.attraction(X, F, objective, gen, alpha_t * swarm.span)
        alpha_t *= alpha_damping
        if elite.update(X, F):
            break
    return elite.result(objective.nfev)

class Elite:
    """The best point ever evaluated, its history per iteration, and the stopping rule shared by the swarms.

    An iteration counts as an improvement only if the best value drops by more than `tol`; after `patience`
    iterations without one the run stops. Smaller gains still update the best point.
    """

    def __init__(self, X: FloatArray, F: FloatArray, *, tol: float, patience: int) -> None:
        i = int(F.argmin())
        self.x, self.f = X[:, i].copy(), float(F[i])
        self.tol, self.patience = tol, patience
        self.stall = 0
        self.history: list[float] = []

    def update(self, X: FloatArray, F: FloatArray) -> bool:
        """Take in one iteration's swarm (X is (d, n)); True when the run should stop."""
        i = int(F.argmin())
        if F[i] < self.f:
            self.stall = 0 if self.f - F[i] > self.tol else self.stall + 1
            self.x, self.f = X[:, i].copy(), float(F[i])
        else:
            self.stall += 1
        self.history.append(self.f)
        return self.stall >= self.patience

    def result(self, nfev: int) -> OptimizeResult:
        return OptimizeResult(x=self.x, fun=self.f, nit=len(self.history), nfev=nfev,
                              history=np.asarray(self.history, dtype=np.float64))


class Pairs(NamedTuple):
    """The attraction pairs of one iteration: firefly i is pulled toward firefly j, candidate p is pair p."""

    i: IntArray
    j: IntArray
    pair: IntArray                      # i * n + j, ascending
    brighter: NDArray[np.bool_] | None  # the (n, n) mask of the pairs; None: the precomputed lower triangle


class Swarm:
    """The geometry of one run and the moves shared by `firefly` and `fastep`.

    Positions are stored component-major, X of shape (d, n), and candidates are built as (d, m) arrays: with
    d = 2 every numpy operation then runs over long contiguous rows instead of rows of two numbers, several
    times faster. The objective receives the transposed view, an (m, d) array in Fortran order, on which the
    usual row-wise objectives (np.sum(..., axis=1), np.hypot(*X.T)) are fast as well (for a 2-D sphere and
    1226 candidates about 4 us against 30 us in C order).
    """

    def __init__(self, n: int, low: FloatArray, high: FloatArray, *, gamma: float, beta0: float) -> None:
        self.low, self.high = low[:, None], high[:, None]
        self.span = (high - low)[:, None]
        diag2 = float(np.sum((high - low) ** 2))
        # exp(-gamma r^2) with r in box diagonals is exp(absorption * |x_j - x_i|^2); a point box has r = 0.
        self.absorption = -gamma / diag2 if diag2 > 0.0 else 0.0
        self.beta0 = beta0
        self._ranked_i, self._ranked_j, self._ranked_pair, self._ranked_start = _ranked_pairs(n)
        self._rows = np.arange(n)
        self._value = np.full((n, n), np.inf)   # written only at the ranked pairs, +inf elsewhere
        self._ranked_steps: tuple[IntArray, IntArray] | None = None   # with_steps of the ranked pairs

    @staticmethod
    def rank(X: FloatArray, F: FloatArray) -> tuple[FloatArray, FloatArray]:
        """The swarm sorted brightest first (stable)."""
        order = np.argsort(F, kind='stable')
        return X.take(order, axis=1), F.take(order)

    def candidates(self, origin: FloatArray, towards: FloatArray, rng: np.random.Generator,
                   scale: FloatArray) -> FloatArray:
        """origin + beta0 exp(-gamma r^2) (towards - origin) + (u - 0.5) scale, clipped; all (d, m).

        `scale` is alpha_t * span as a (d, 1) column; u is one `rng.random((d, m))` block. Overwrites and
        returns `towards`.
        """
        C = towards
        C -= origin
        pull = C[0] * C[0]                       # |towards - origin|^2, summed in coordinate order
        for k in range(1, C.shape[0]):
            pull += C[k] * C[k]
        pull *= self.absorption
        np.exp(pull, out=pull)
        pull *= self.beta0
        C *= pull
        C += origin
        noise = rng.random(C.shape)
        noise -= 0.5
        noise *= scale
        C += noise
        np.clip(C, self.low, self.high, out=C)
        return C

    def attraction(self, X: FloatArray, F: FloatArray, objective: Objective, rng: np.random.Generator,
                   scale: FloatArray, sample: int | None = None) -> tuple[FloatArray, FloatArray]:
        """Eq. 3 for every pair (i, j) with j brighter than i; return each firefly's best candidate and value.

        X is (d, n); the result is a new (d, n) array and its (n,) values. One objective call. With `sample`
        = k, a firefly with more than k brighter fireflies is attracted to k of them only, drawn at random
        without replacement (see `sampled`); None: to all of them (the paper).
        """
        pairs = self.pairs(F, rng, sample)
        C = self.candidates(X.take(pairs.i, axis=1), X.take(pairs.j, axis=1), rng, scale)
        fc = objective(C.T)
        k = self.best_of_pairs(pairs, fc)
        return C.take(k, axis=1), fc.take(k)

    def pairs(self, F: FloatArray, rng: np.random.Generator, sample: int | None = None) -> Pairs:
        """The attraction pairs (i, j) of a ranked swarm with values F: j brighter than i, or (i, i) for a firefly
        nobody outshines (its random walk), row-major. With `sample`, draws the sampling keys (`sampled`)."""
        if sample is None and bool((F[1:] > F[:-1]).all()):   # ranked, no ties: the precomputed lower triangle
            return Pairs(self._ranked_i, self._ranked_j, self._ranked_pair, None)
        n = F.size
        brighter = F < F[:, None]                        # brighter[i, j]: firefly j outshines firefly i
        if sample is not None:
            brighter = self.sampled(brighter, rng, sample)
        lonely = np.flatnonzero(F == F.min())            # nobody outshines them: random walk, pair (i, i)
        brighter[lonely, lonely] = True
        pair = np.flatnonzero(brighter)                  # i * n + j, row-major
        i, j = np.divmod(pair, n)
        return Pairs(i, j, pair, brighter)

    def with_steps(self, pairs: Pairs) -> tuple[IntArray, IntArray]:
        """(origin, towards) firefly indices of the pairs' candidates followed by every firefly's step ahead of
        firefly 0 (the brightest of a ranked swarm): `fastep`'s merged moves build them all in one block."""
        if pairs.brighter is None and self._ranked_steps is not None:
            return self._ranked_steps
        n = len(self._rows)
        steps = (np.concatenate([pairs.i, np.zeros(n, dtype=pairs.i.dtype)]), np.concatenate([pairs.j, self._rows]))
        if pairs.brighter is None:
            self._ranked_steps = steps
        return steps

    def best_of_pairs(self, pairs: Pairs, fc: FloatArray) -> IntArray:
        """Index (among the pairs' candidates, values fc) of each firefly's best candidate: the first in j order
        among equal values."""
        n = len(self._rows)
        if pairs.brighter is None:
            value = self._value
            value.reshape(-1)[pairs.pair] = fc
            k: IntArray = self._ranked_start + value.argmin(axis=1)   # always a pair: column 0 or the diagonal
            return k
        value = np.full((n, n), np.inf)
        value.reshape(-1)[pairs.pair] = fc
        best = value.argmin(axis=1)
        unused = ~pairs.brighter[self._rows, best]       # every candidate of row i was +inf: take its first
        if unused.any():
            best[unused] = pairs.brighter[unused].argmax(axis=1)
        k = np.searchsorted(pairs.pair, self._rows * n + best)  # position of pair (i, best_i) among the candidates
        return k

    def sampled(self, brighter: NDArray[np.bool_], rng: np.random.Generator, sample: int) -> NDArray[np.bool_]:
        """Keep at most `sample` brighter fireflies per row of `brighter` (n, n), uniformly without replacement.

        One `rng.random((n, n))` block of keys: row i keeps the brighter fireflies with its `sample` smallest
        keys, all of them when it has no more than `sample`. Returns a new mask.
        """
        n = len(brighter)
        keys = rng.random((n, n))
        crowded = np.flatnonzero(brighter.sum(axis=1) > sample)
        if not len(crowded):
            return brighter.copy()
        keys = keys[crowded]
        keys[~brighter[crowded]] = np.inf
        keep = brighter.copy()
        keep[crowded] = False
        chosen = np.argpartition(keys, sample - 1, axis=1)[:, :sample]
        keep[crowded[:, None], chosen] = True
        return keep


@functools.lru_cache(maxsize=16)
def _ranked_pairs(n: int) -> tuple[IntArray, IntArray, IntArray, IntArray]:
    """The pairs of a swarm ranked with strictly increasing values, as (i, j, i * n + j, start of row i).

    (0, 0) first (the brightest firefly's random walk), then (i, j) for every j < i, row-major. Cached: the
    planner builds a swarm of the same size for every step. The arrays are read-only.
    """
    below_i, below_j = np.tril_indices(n, -1)
    i = np.concatenate(([0], below_i))
    j = np.concatenate(([0], below_j))
    rows = np.arange(n)
    start = rows * (rows - 1) // 2 + (rows > 0)
    arrays = (i, j, i * n + j, start)
    for a in arrays:
        a.flags.writeable = False
    return arrays


def _check_swarm_parameters(n_fireflies: int, max_iter: int, patience: int, gamma: float, beta0: float,
                            alpha: float, alpha_damping: float) -> None:
    check_count('n_fireflies', n_fireflies, 1)
    check_count('max_iter', max_iter, 0)
    check_count('patience', patience, 1)
    check_number('gamma', gamma)
    check_number('beta0', beta0)
    check_number('alpha', alpha)
    check_number('alpha_damping', alpha_damping)
