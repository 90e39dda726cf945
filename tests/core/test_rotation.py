"""Exact SH rotation of lighting coefficients."""

import numpy as np
import pytest
from quadrature import random_directions

from sh_lighting.core.projection import project_equirect
from sh_lighting.core.rotation import euler_xyz_matrix, rotate_coefficients, sh_rotation_matrix
from sh_lighting.core.sh import sh_basis

EXACT = 1e-12


def random_rotation(rng):
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q *= np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


@pytest.mark.parametrize("order", [1, 2, 4])
def test_rotation_matrices_are_orthogonal_and_block_diagonal(order):
    rng = np.random.default_rng(0)
    d = sh_rotation_matrix(random_rotation(rng), order)
    n = (order + 1) ** 2
    assert np.abs(d @ d.T - np.eye(n)).max() < EXACT
    for l in range(order + 1):
        band = slice(l * l, (l + 1) ** 2)
        off = d[band].copy()
        off[:, band] = 0.0
        assert not off.any()


def test_basis_identity_y_of_r_omega():
    rng = np.random.default_rng(1)
    r = random_rotation(rng)
    dirs = random_directions(100)
    assert np.abs(sh_basis(dirs @ r.T, 4) - sh_basis(dirs, 4) @ sh_rotation_matrix(r, 4).T).max() < EXACT


def test_rotations_compose_and_invert():
    rng = np.random.default_rng(2)
    a, b = random_rotation(rng), random_rotation(rng)
    assert np.abs(sh_rotation_matrix(a @ b) - sh_rotation_matrix(a) @ sh_rotation_matrix(b)).max() < EXACT
    coeffs = rng.normal(size=(9, 3))
    assert np.abs(rotate_coefficients(rotate_coefficients(coeffs, a), a.T) - coeffs).max() < EXACT


def test_rotating_coefficients_equals_projecting_the_rotated_map():
    """A quarter turn about z is an exact column roll of an equirect map with W divisible by 4."""
    pixels = np.random.default_rng(3).random((10, 20, 3))
    rz = euler_xyz_matrix([0.0, 0.0, -np.pi / 2])  # rolling W/4 columns: α = -2π(W/4)/W
    rolled = project_equirect(np.roll(pixels, 5, axis=1), 4)
    assert np.abs(rotate_coefficients(project_equirect(pixels, 4), rz) - rolled).max() < EXACT


def test_euler_xyz_follows_blender():
    """Blender's XYZ Euler applies X first, then Y, then Z: (0, 0, 90°) sends +X to +Y."""
    assert np.allclose(euler_xyz_matrix([0, 0, np.pi / 2]) @ [1, 0, 0], [0, 1, 0])
    assert np.allclose(euler_xyz_matrix([np.pi / 2, 0, np.pi / 2]) @ [0, 1, 0], [0, 0, 1])


def test_not_a_rotation_is_refused():
    with pytest.raises(ValueError, match="not a rotation"):
        sh_rotation_matrix(np.diag([1.0, 1.0, -1.0]))


@pytest.mark.parametrize("rows", [0, 8, 10])
def test_a_row_count_that_is_no_order_is_refused(rows):
    """Rows must be (order + 1)²: a clear message, not a failed matrix product."""
    with pytest.raises(ValueError, match=f"{rows} SH coefficients is not"):
        rotate_coefficients(np.ones((rows, 3)), np.eye(3))
