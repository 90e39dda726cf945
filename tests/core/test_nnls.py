"""Lawson–Hanson NNLS against the brute-force optimum over every active set."""

import itertools

import numpy as np
import pytest

from sh_lighting.core.nnls import nnls


def brute_force(a, b):
    """Best non-negative least squares over all 2^n supports (unconstrained on each)."""
    best, best_x = np.inf, None
    n = a.shape[1]
    for size in range(n + 1):
        for support in itertools.combinations(range(n), size):
            x = np.zeros(n)
            if support:
                x[list(support)] = np.linalg.lstsq(a[:, support], b, rcond=None)[0]
            if (x < 0).any():
                continue
            r = np.linalg.norm(a @ x - b)
            if r < best:
                best, best_x = r, x
    return best_x, best


@pytest.mark.parametrize("seed", range(20))
def test_nnls_equals_brute_force(seed):
    rng = np.random.default_rng(seed)
    m, n = rng.integers(3, 12), rng.integers(1, 7)
    a = rng.normal(size=(m, n))
    b = rng.normal(size=m)
    x, r = nnls(a, b)
    want_x, want_r = brute_force(a, b)
    assert (x >= 0).all()
    assert r == pytest.approx(want_r, rel=1e-9, abs=1e-12)
    assert x == pytest.approx(want_x, abs=1e-8)


def test_nnls_exact_and_kkt():
    rng = np.random.default_rng(7)
    a = rng.random((40, 6))
    truth = np.array([0.0, 2.0, 0.0, 1.5, 0.3, 0.0])
    x, r = nnls(a, a @ truth)
    assert x == pytest.approx(truth, abs=1e-10) and r < 1e-10
    b = rng.normal(size=40)
    x, _ = nnls(a, b)
    w = a.T @ (b - a @ x)  # KKT: w <= 0 where x = 0, w = 0 where x > 0
    assert (w[x == 0] <= 1e-10).all() and np.abs(w[x > 0]).max(initial=0) < 1e-9


def test_nnls_refuses_bad_input():
    with pytest.raises(ValueError, match="finite"):
        nnls(np.array([[np.nan]]), np.array([1.0]))
    with pytest.raises(ValueError, match="shape"):
        nnls(np.ones((3, 2)), np.ones(2))
