"""Continuous ant colony optimisation, ACO_R (Socha & Dorigo 2008): the optimizer of the ACO-Kinematic baseline.

Why ACO_R: the paper compares FAStep-Kinematic with ACO-Kinematic, whose text was not available; a fair
stand-in plans each step with the standard continuous ACO on the same fitness, so only the optimizer differs.

The "pheromone" is an archive of the k best solutions, the one of rank l weighted
w_l = exp(-(l - 1)^2 / (2 q^2 k^2)) (small q favours the best). Each iteration every one of the m ants picks a
kernel l with probability w_l / sum(w) and samples each coordinate from a normal centred on s_l with
sigma_l^i = xi * sum_e |s_e^i - s_l^i| / (k - 1), so the search narrows as the archive converges. Samples are
clipped into the box, all ants are evaluated in one call, and archive and ants are merged, sorted (stably,
archive first on ties) and cut to k: the best value never increases.

Random draws, in order, from the one Generator: the initial archive (k x d uniforms), then per iteration m
uniforms choosing the kernels followed by m x d standard normals.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from fastep_core.optimize.result import (
    Objective,
    OptimizeResult,
    RngLike,
    VectorisedFunction,
    check_count,
    check_number,
    check_problem,
    initial_population,
)

__all__ = ['aco_r']


def aco_r(fun: VectorisedFunction, bounds: ArrayLike, *, archive_size: int = 10, n_ants: int = 40,
          q: float = 0.5, xi: float = 1.0, max_iter: int = 30, patience: int = 5, tol: float = 0.0, rng: RngLike = None,
          x0: ArrayLike | None = None) -> OptimizeResult:
    """Minimise a vectorised function over a box with ACO_R.

    Parameters
    ----------
    fun : callable
        Maps an (m, d) float array of candidates to an (m,) array of objective values (minimised). Called
        once for the initial archive and once per iteration.
    bounds : array_like, shape (d, 2)
        [low, high] per dimension. Every evaluated candidate lies inside.
    archive_size, n_ants, q, xi
        k, m, locality q and spread xi of ACO_R (defaults: k = 10, m = 40, q = 0.5, xi = 1).
    max_iter, patience
        Stop after max_iter iterations, or after patience consecutive iterations without improvement.
    tol
        An iteration counts as an improvement only if the best value drops by more than tol (>= 0).
    rng : numpy.random.Generator, int or None
        Source of every random draw; an int or None seeds `numpy.random.default_rng`.
    x0 : array_like, shape (k0, d) or (d,), optional
        Initial solutions replacing the first k0 archive members (clipped into the box); k0 <= archive_size.
    """
    check_count('archive_size', archive_size, 2)
    check_count('n_ants', n_ants, 1)
    check_count('max_iter', max_iter, 0)
    check_count('patience', patience, 1)
    check_number('tol', tol)
    check_number('q', q, 1e-12)
    check_number('xi', xi)
    low, high, gen, x0 = check_problem(bounds, rng, x0, archive_size)
    objective = Objective(fun)
    k, d = archive_size, low.size

    rank = np.arange(k, dtype=np.float64)
    weight = np.exp(-rank**2 / (2.0 * q**2 * k**2))
    cdf = np.cumsum(weight / weight.sum())

    S = initial_population(k, low, high, gen, x0)
    fS = objective(S)
    order = np.argsort(fS, kind='stable')
    S, fS = S[order], fS[order]

    history: list[float] = []
    stall = 0
    for _ in range(max_iter):
        sigma = np.abs(S - S[:, None, :]).sum(axis=1)   # sum_e |s_e - s_l| per kernel l, shape (k, d)
        sigma *= xi / (k - 1)
        kernel = np.minimum(np.searchsorted(cdf, gen.random(n_ants) * cdf[-1], side='right'), k - 1)
        A = gen.standard_normal((n_ants, d))
        A *= sigma[kernel]
        A += S[kernel]
        np.maximum(A, low, out=A)
        np.minimum(A, high, out=A)
        fA = objective(A)

        previous = fS[0]
        merged_f = np.concatenate((fS, fA))
        keep = np.argsort(merged_f, kind='stable')[:k]
        S, fS = np.concatenate((S, A))[keep], merged_f[keep]

        stall = 0 if fS[0] < previous and previous - fS[0] > tol else stall + 1
        history.append(float(fS[0]))
        if stall >= patience:
            break
    return OptimizeResult(x=S[0].copy(), fun=float(fS[0]), nit=len(history), nfev=objective.nfev,
                          history=np.asarray(history, dtype=np.float64))
