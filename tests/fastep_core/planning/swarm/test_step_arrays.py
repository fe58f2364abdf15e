"""The step fitness's row sums of mostly-zero arrays are numpy's own, bit for bit (the swarm compares the floats)."""

import numpy as np
import pytest

from fastep_core.planning.swarm.step_arrays import DENSE_FROM, near_row_sum, sparse_row_sum


@pytest.mark.parametrize('n', [1, 2, 5, 7, 8, 9, 15, 16, 17, 39, 64, 100, 128, 129, 200, 300])
@pytest.mark.parametrize('m', [1, 2, 3, 50, 1226])
def test_sparse_row_sum_is_numpys_row_sum(n, m):
    rng = np.random.default_rng(n * 10_000 + m)
    for k in {1, 2, 3, n // 3 + 1, n}:
        keep = np.sort(rng.choice(n, size=min(k, n), replace=False))
        A = np.zeros((m, n))
        A[:, keep] = rng.random((m, len(keep))) * rng.choice([1e-3, 1.0, 1e3], (m, len(keep)))
        A[rng.random((m, n)) < 0.2] = 0.0                      # zeros inside the columns too
        total = sparse_row_sum({int(j): A[:, j].copy() for j in keep}, n)
        assert np.array_equal(total, A.sum(axis=1))
    assert sparse_row_sum({}, n) is None


@pytest.mark.parametrize('n', [1, 3, 5, 15, 39, 129])
@pytest.mark.parametrize('m', [1, 50, 1226])
def test_near_row_sum_is_numpys_row_sum_with_few_and_many_columns(n, m):
    """Below DENSE_FROM columns it adds them alone (sparse_row_sum), from it on it builds the array: both give
    numpy's sum of the whole array, bit for bit."""
    rng = np.random.default_rng(n * 7_000 + m)
    for k in sorted({1, DENSE_FROM - 1, DENSE_FROM, n // 2 + 1, n}):
        if k > n:
            continue
        near = np.sort(rng.choice(n, size=k, replace=False))
        A = np.zeros((m, n))
        A[:, near] = rng.random((m, k)) * rng.choice([1e-3, 1.0, 1e3], (m, k))
        assert np.array_equal(near_row_sum(near, A[:, near].T.copy(), n), A.sum(axis=1))
    assert near_row_sum(np.zeros(0, dtype=np.intp), np.zeros((0, m)), n) is None
