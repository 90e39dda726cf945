"""Panel preview images (preview.py): geometry of the sphere view, colours, encoding."""

from math import pi, sqrt

import numpy as np
import pytest

from sh_lighting.core.irradiance import irradiance
from sh_lighting.core.preview import (
    NEGATIVE_COLOUR,
    basis_sphere_images,
    fit_exposure,
    irradiance_equirect_image,
    irradiance_sphere_image,
    linear_to_srgb,
    sphere_normals,
)
from sh_lighting.core.sh import sh_basis

EXACT = 1e-6  # float32 images


def delta(s, rgb=(1.0, 1.0, 1.0)):
    s = np.asarray(s, float) / np.linalg.norm(s)
    return sh_basis(s)[:, None] * np.asarray(rgb)[None, :]


def constant(c):
    coeffs = np.zeros((9, 3))
    coeffs[0] = 2.0 * sqrt(pi) * np.asarray(c)
    return coeffs


def test_sphere_view_geometry():
    normals, alpha = sphere_normals(129)  # odd: a true centre pixel
    assert np.abs(normals[64, 64] - [0.0, -1.0, 0.0]).max() < 1e-15  # faces the viewer (−Y)
    assert normals[0, 64] @ [0, 0, 1] > 0.99  # top: +Z
    assert normals[64, 128] @ [1, 0, 0] > 0.99  # right: +X
    assert normals[128, 64] @ [0, 0, -1] > 0.99  # bottom: −Z
    assert np.abs(np.linalg.norm(normals, axis=-1) - 1.0).max() < 1e-12
    assert np.all(normals[..., 1] <= 0.0)  # only the visible hemisphere
    normals, alpha = sphere_normals(128)
    assert alpha[64, 64] == 1.0 and alpha[0, 0] == 0.0 and alpha[127, 127] == 0.0
    assert alpha.sum() == pytest.approx(pi / 4 * 128**2, rel=2e-3)  # the disc's area
    assert np.all((alpha >= 0.0) & (alpha <= 1.0))
    assert sphere_normals(128)[0] is normals  # cached
    with pytest.raises(ValueError):
        normals[0, 0, 0] = 1.0  # the cache is read-only


def test_basis_images_colours_and_layout():
    images = basis_sphere_images(65)
    assert images.shape == (9, 65, 65, 4) and images.dtype == np.float32
    top, centre, bottom, right, left = (0, 32), (32, 32), (64, 32), (32, 64), (32, 0)
    g, b = 1, 2
    # Y00: uniform green, Â0 Y00 / (Â1 Y1) = 0.886 / 1.023 of full brightness
    assert np.allclose(images[0][32, 32, :3], [0, (pi * 0.2820948) / (2 * pi / 3 * 0.4886025), 0])
    # Y10 ∝ z: green on top, blue at the bottom, black in the middle
    assert images[2][top][g] > 0.95 and images[2][top][b] == 0.0
    assert images[2][bottom][b] > 0.95 and images[2][bottom][g] == 0.0
    assert images[2][centre][:3].max() < EXACT
    # Y11 ∝ x: green on the right; Y1-1 ∝ y: the visible side (y < 0) is blue
    assert images[3][right][g] > 0.95 and images[3][left][b] > 0.95
    assert images[1][centre][b] > 0.99 and images[1][centre][g] == 0.0
    # Y20 ∝ 3z² − 1: blue at the centre (z = 0): Â2 Y20 / (Â1 Y1) = 0.2477 / 1.0233
    assert images[6][centre][b] == pytest.approx(0.247708 / 1.023327, rel=1e-5)
    # the l = 2 row is dimmer than the l = 1 row
    assert images[4:, ..., :3].max() < 0.5 < images[1:4, ..., :3].max()
    # transparent background, opaque disc, no red anywhere
    assert np.all(images[:, 0, 0, 3] == 0.0) and np.all(images[:, 32, 32, 3] == 1.0)
    assert np.all(images[..., 0] == 0.0)


def test_srgb_encoding():
    assert linear_to_srgb(0.0) == 0.0 and linear_to_srgb(1.0) == pytest.approx(1.0)
    assert linear_to_srgb(0.5) == pytest.approx(0.735357, abs=1e-6)
    assert linear_to_srgb(0.002) == pytest.approx(12.92 * 0.002)
    assert linear_to_srgb(-1.0) == 0.0 and 1.0 - 1e-15 <= linear_to_srgb(7.0) <= 1.0


def test_irradiance_sphere_of_constant_light_shows_its_radiance():
    """A white diffuse sphere under a constant sky of radiance c shows exactly c everywhere."""
    image = irradiance_sphere_image(constant([0.5, 0.25, 0.125]), size=32)
    inside = image[..., 3] > 0
    expected = linear_to_srgb(np.array([0.5, 0.25, 0.125]))
    assert np.abs(image[inside][:, :3] - expected).max() < EXACT
    brighter = irradiance_sphere_image(constant([0.5, 0.25, 0.125]), size=32, exposure=1.0)
    assert np.abs(brighter[16, 16, :3] - linear_to_srgb(np.array([1.0, 0.5, 0.25]))).max() < EXACT


def test_irradiance_sphere_values_at_known_pixels():
    coeffs = delta([0, 0, 1], rgb=(2.0, 1.0, 0.5))
    size = 129
    image = irradiance_sphere_image(coeffs, size=size)
    normals, _ = sphere_normals(size)
    for pixel in [(0, 64), (64, 64), (128, 64), (30, 90)]:
        e = irradiance(coeffs, normals[pixel]) / pi
        assert np.abs(image[pixel][:3] - linear_to_srgb(e)).max() < EXACT
    # centre faces −Y: u = 0, E9 = 3/32 per unit power
    assert image[64, 64, 0] == pytest.approx(linear_to_srgb(2.0 * 3 / 32 / pi), abs=EXACT)
    assert image[0, 64, 0] > image[64, 64, 0] > image[128, 64, 0]  # lit from above


def test_fit_exposure_puts_the_brightest_pixel_at_white():
    """The sphere is exposed to its own range. A constant sky of radiance c
    shows c everywhere, so the fit is −log₂ of its largest channel; a light from above
    4× brighter is shown 2 stops lower with the same picture."""
    sky = constant([4.0, 2.0, 1.0])
    assert fit_exposure(sky, 32) == pytest.approx(-2.0, abs=1e-12)
    image = irradiance_sphere_image(sky, 32, exposure=fit_exposure(sky, 32))
    inside = image[..., 3] > 0
    assert np.abs(image[inside][:, :3] - linear_to_srgb(np.array([1.0, 0.5, 0.25]))).max() < EXACT
    above = delta([0.2, -0.5, 1.0], rgb=(3.0, 2.0, 1.0))
    first = irradiance_sphere_image(above, 64, exposure=fit_exposure(above, 64))
    again = irradiance_sphere_image(4 * above, 64, exposure=fit_exposure(4 * above, 64))
    assert fit_exposure(4 * above, 64) == pytest.approx(fit_exposure(above, 64) - 2.0, abs=1e-12)
    assert np.abs(first - again).max() < EXACT
    assert first[..., :3].max() == pytest.approx(1.0, abs=EXACT)
    assert (first[..., :3] >= 1.0 - EXACT).any(axis=-1).sum() <= 3  # only the peak is white


def test_fit_exposure_of_unlit_coefficients_is_zero():
    assert fit_exposure(np.zeros((9, 3)), 16) == 0.0
    assert fit_exposure(-constant([1.0, 1.0, 1.0]), 16) == 0.0  # negative everywhere
    with pytest.raises(ValueError, match="order 2"):
        fit_exposure(np.zeros((4, 3)), 16)


def test_negative_irradiance_is_flagged_on_request():
    coeffs = delta([0, 0, 1])  # E9 < 0 on the cone u < −1/3 or so, below
    plain = irradiance_sphere_image(coeffs, size=65)
    flagged = irradiance_sphere_image(coeffs, size=65, show_negative=True)
    normals, _ = sphere_normals(65)
    u = normals[..., 2]
    e9 = 0.25 + u / 2 + (15 * u * u - 5) / 32
    negative = e9 < -1e-9
    assert negative.any()
    assert np.all(flagged[negative][:, :3] == NEGATIVE_COLOUR)
    assert np.all(plain[negative][:, :3] == 0.0)
    assert np.all(flagged[e9 > 1e-9] == plain[e9 > 1e-9])


def test_irradiance_equirect_image():
    image = irradiance_equirect_image(delta([1, 0, 0]), width=64, height=32)
    assert image.shape == (32, 64, 4) and image.dtype == np.float32
    assert np.all(image[..., 3] == 1.0)
    # the centre column faces +X: the brightest; column 0 faces −X
    row = image[16, :, 0]
    assert np.argmax(row) in (31, 32) and row[0] < row[32]
    top = irradiance_equirect_image(delta([0, 0, 1]), width=64, height=32)
    assert top[0, 0, 0] > top[16, 0, 0] > top[31, 0, 0]
    assert np.all(top[0] == top[0, 0])  # symmetric about z: rows are uniform
    flat = irradiance_equirect_image(constant([0.5, 0.5, 0.5]), 16, 8)
    assert np.abs(flat[..., :3] - linear_to_srgb(0.5)).max() < EXACT

