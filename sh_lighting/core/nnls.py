"""Non-negative least squares: min ||A x − b||₂ subject to x ≥ 0 (Lawson and Hanson 1974).

C. L. Lawson and R. J. Hanson, "Solving Least Squares Problems", chapter 23, algorithm NNLS:
an active-set method. P is the set of free (positive) variables, Z the rest at zero; the
gradient w = Aᵀ(b − A x) names the variable whose release lowers the residual most; the
unconstrained least squares on P is taken as far as feasibility allows (the step α), variables
reaching zero return to Z. It ends when no w_j > 0 is left for j in Z (the KKT conditions).
numpy only (scipy is not bundled with Blender).
"""

import numpy as np


def nnls(a, b, max_iterations=None, tolerance=None):
    """x ≥ 0 minimising ||a x − b||₂, and the residual norm. ``a`` (m, n), ``b`` (m,)."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    m, n = a.shape
    if b.shape != (m,):
        raise ValueError(f"b has shape {b.shape}, expected ({m},)")
    if not (np.isfinite(a).all() and np.isfinite(b).all()):
        raise ValueError("a and b must be finite")
    max_iterations = 3 * n if max_iterations is None else max_iterations
    if tolerance is None:
        tolerance = 10 * max(m, n) * np.finfo(float).eps * max(np.abs(a).max(initial=0.0), 1.0)
    x = np.zeros(n)
    free = np.zeros(n, dtype=bool)
    w = a.T @ (b - a @ x)
    for _ in range(max_iterations):
        candidates = np.where(~free & (w > tolerance))[0]
        if candidates.size == 0:
            break
        free[candidates[np.argmax(w[candidates])]] = True
        while True:
            z = np.zeros(n)
            z[free] = np.linalg.lstsq(a[:, free], b, rcond=None)[0]
            if (z[free] > 0).all():
                x = z
                break
            # step toward z only as far as keeps every free variable non-negative
            blocking = free & (z <= 0)
            gap = x[blocking] - z[blocking]
            alpha = np.min(np.where(gap > 0, x[blocking] / np.where(gap > 0, gap, 1.0), 0.0))
            x = x + alpha * (z - x)
            free &= x > tolerance
            x[~free] = 0.0
        w = a.T @ (b - a @ x)
    return x, float(np.linalg.norm(a @ x - b))
