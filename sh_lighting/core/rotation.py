"""Exact rotation of SH lighting coefficients, band by band.

Rotating the lighting by a 3×3 rotation R (L'(ω) = L(Rᵀω)) maps its coefficients linearly,
band by band: L'_l = D_l(R) L_l with D_l orthogonal, because Y_lm(Rω) = Σ_m' D_l,mm' Y_lm'(ω).
D_l is found from that identity itself: evaluated at a fixed, well-spread set of directions it
is an over-determined linear system whose solution is exact up to rounding (there is no
sampling error: both sides are the same degree-l polynomial).
"""

import numpy as np

from .sh import num_coefficients, order_of, sh_basis, spread_normals


def check_rotation(rotation):
    """A 3×3 float64 rotation matrix, or a ValueError if it is not orthonormal with det +1."""
    r = np.asarray(rotation, dtype=np.float64)
    if r.shape != (3, 3):
        raise ValueError(f"a rotation must be a 3×3 matrix, got shape {r.shape}")
    if not np.allclose(r @ r.T, np.eye(3), atol=1e-6) or np.linalg.det(r) < 0:
        raise ValueError("the matrix is not a rotation (orthonormal with determinant +1)")
    return r


def sh_rotation_matrix(rotation, max_order=2):
    """Block-diagonal D ((n, n), n = (max_order+1)²) with L_rotated = D @ L for a rotation R."""
    r = check_rotation(rotation)
    n = num_coefficients(max_order)
    directions = spread_normals(4 * n)
    before = sh_basis(directions, max_order)
    after = sh_basis(directions @ r.T, max_order)
    d = np.zeros((n, n))
    for l in range(max_order + 1):
        band = slice(l * l, (l + 1) * (l + 1))
        solution, *_ = np.linalg.lstsq(before[:, band], after[:, band], rcond=None)
        d[band, band] = solution.T
    return d


def rotate_coefficients(coeffs, rotation):
    """Coefficients of the lighting rotated by R: L'(ω) = L(Rᵀ ω). Shape kept."""
    c = np.asarray(coeffs, dtype=np.float64)
    order = order_of(c.shape[0])
    return sh_rotation_matrix(rotation, order) @ c


def euler_xyz_matrix(angles):
    """Blender's XYZ Euler rotation matrix Rz · Ry · Rx for angles (x, y, z) in radians."""
    ax, ay, az = angles
    cx, sx, cy, sy, cz, sz = np.cos(ax), np.sin(ax), np.cos(ay), np.sin(ay), np.cos(az), np.sin(az)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return rz @ ry @ rx
