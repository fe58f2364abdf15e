"""FAStep with plain Python loops: the reference `fastep_core.optimize.fastep` is checked and timed against.

This is how the algorithm reads in the authors' MATLAB template, translated line by line: loops over fireflies
and over pairs, one objective call per point (`fun` is still the vectorised objective, called on a (1, d)
array). It exists so that a test can check that the vectorised version makes the same moves
(tests/fastep_core/optimize/test_optimize_fastep.py) and a benchmark can report its speed-up
(benchmarks/step_latency.py); the product never calls it.

It makes exactly the same moves as `fastep` (ranking, eq. 3 attraction, eq. 4 stepping ahead, the preference
rule, elitism, damping and stopping; see `fastep_core/optimize/fastep.py` for the why) and takes the same
random draws from the Generator in the same order: the initial population, then per iteration one
`rng.random((d, m))` block for the m attraction pairs and one `rng.random((d, k))` block for the k
stepping-ahead fireflies. The floating-point operations are also the same, in the same order, so for the same
seed it returns the same result as `fastep`, bit for bit (up to the objective itself: an objective whose value
for a point depends on the memory layout of the batch could differ in the last bits).
"""

from __future__ import annotations

from typing import Callable

import numpy as np
from numpy.typing import ArrayLike

from fastep_core.optimize import OptimizeResult
from fastep_core.optimize.fastep import PREFERENCE_TOLERANCE

__all__ = ['fastep_loop']


def fastep_loop(fun: Callable[[np.ndarray], ArrayLike], bounds: ArrayLike, *, n_fireflies: int = 50,
                max_iter: int = 30, patience: int = 5, gamma: float = 1.0, beta0: float = 2.0,
                alpha: float = 0.2, alpha_damping: float = 0.8, tol: float = 0.0,
                rng: np.random.Generator | int | None = None, x0: ArrayLike | None = None,
                merged_moves: bool = False) -> OptimizeResult:
    """FAStep with loops over fireflies and pairs; same API and result as `fastep` (no input validation).

    merged_moves: `fastep`'s departure of that name, with its draws (one block per iteration, the pairs' columns
    then every firefly's step ahead of the brightest at the iteration's start)."""
    rng = np.random.default_rng(rng)
    b = np.asarray(bounds, dtype=np.float64)
    low, high = b[:, 0].copy(), b[:, 1].copy()
    n, d = n_fireflies, low.size
    span = high - low
    diag2 = float(np.sum(span ** 2))
    absorption = -gamma / diag2 if diag2 > 0.0 else 0.0
    nfev = 0

    def evaluate(x: np.ndarray) -> float:
        nonlocal nfev
        nfev += 1
        value = float(np.asarray(fun(x.reshape(1, d)), dtype=np.float64)[0])
        return np.inf if value != value else value          # NaN counts as +inf

    def move(origin: np.ndarray, towards: np.ndarray, u: np.ndarray, scale: np.ndarray) -> np.ndarray:
        """origin + beta0 exp(-gamma r^2) (towards - origin) + (u - 0.5) scale, clipped into the box."""
        diff = towards - origin
        r2 = 0.0
        for k in range(d):
            r2 += diff[k] * diff[k]
        beta = np.exp(r2 * absorption) * beta0
        return np.clip(diff * beta + origin + (u - 0.5) * scale, low, high)

    X = rng.uniform(low, high, size=(n, d))
    if x0 is not None:
        x0 = np.atleast_2d(np.asarray(x0, dtype=np.float64))
        X[:x0.shape[0]] = np.clip(x0, low, high)
    F = [evaluate(X[i]) for i in range(n)]
    best = min(range(n), key=F.__getitem__)
    best_x, best_f = X[best].copy(), F[best]

    history: list[float] = []
    alpha_t, stall = float(alpha), 0
    for _ in range(max_iter):
        scale = alpha_t * span
        order = sorted(range(n), key=F.__getitem__)          # rank brightest first (stable)
        X = X[order]
        F = [F[i] for i in order]

        # 1. Attraction (eq. 3): every pair (i, j) with j brighter; (i, i) when nobody is brighter.
        pairs = []
        for i in range(n):
            brighter = [j for j in range(n) if F[j] < F[i]]
            for j in brighter or [i]:
                pairs.append((i, j))
        u = rng.random((d, len(pairs) + (n if merged_moves else 0)))
        best_c: list[np.ndarray | None] = [None] * n
        best_fc = [np.inf] * n
        for p, (i, j) in enumerate(pairs):
            c = move(X[i], X[j], u[:, p], scale)
            fc = evaluate(c)
            if best_c[i] is None or fc < best_fc[i]:
                best_c[i], best_fc[i] = c, fc
        if merged_moves:   # every firefly's step ahead of the brightest at the start, evaluated before any move
            steps = []
            for i in range(n):
                s = move(X[0], X[i], u[:, len(pairs) + i], scale)
                steps.append((i, s, evaluate(s)))
        moved = [False] * n
        for i in range(n):
            if best_fc[i] < F[i]:
                X[i], F[i], moved[i] = best_c[i], best_fc[i], True

        # 2. Stepping ahead (eq. 4) of the brightest firefly, for those that did not move.
        stuck = [i for i in range(n) if not moved[i]]
        if merged_moves:
            b = 0
            steps = [step for step in steps if not moved[step[0]]]
        elif stuck:
            b = min(range(n), key=F.__getitem__)
            xb = X[b].copy()
            u = rng.random((d, len(stuck)))
            steps = []
            for q, i in enumerate(stuck):
                s = move(xb, X[i], u[:, q], scale)
                steps.append((i, s, evaluate(s)))
        if stuck:
            # 3. Preference rule.
            for i, s, fs in steps:
                f = F[i]
                if i == b:
                    take = fs < f
                else:
                    take = fs <= f + PREFERENCE_TOLERANCE * min(abs(f), 1e300)
                if take:
                    X[i], F[i] = s, fs

        # 4. Elitism and damping.
        i = min(range(n), key=F.__getitem__)
        if F[i] < best_f:
            stall = 0 if best_f - F[i] > tol else stall + 1
            best_x, best_f = X[i].copy(), F[i]
        else:
            stall += 1
        history.append(best_f)
        alpha_t *= alpha_damping
        if stall >= patience:
            break
    return OptimizeResult(x=best_x, fun=float(best_f), nit=len(history), nfev=nfev,
                          history=np.asarray(history, dtype=np.float64))
