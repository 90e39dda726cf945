"""Numerical stability of the core on stiff and extreme inputs.

Covers what tests/core/test_projection.py does not: huge dynamic range in float32/float16
input, single texels at the poles, the seam and the equator of tiny and huge maps, values near
the float32 maximum, long chains of SH rotations, the float32 arithmetic of the node group
(simulated here: every node op rounds to float32), and hypothesis properties over random
non-negative maps with a wide exponent range.

Tolerances are stated where they are used, relative to a named scale. eps is float64's
machine epsilon (2.2e-16), u = 2^-24 is float32's unit roundoff.
"""

from functools import partial
from math import pi, sqrt
import re
import tracemalloc
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from quadrature import random_directions, texel_integral

from sh_lighting.core.equirect import texel_directions
from sh_lighting.core.irradiance import C1, C2, C3, C4, C5, irradiance, reference_irradiance
from sh_lighting.core.projection import project_equirect
from sh_lighting.core.rotation import rotate_coefficients, sh_rotation_matrix
from sh_lighting.core.sh import sh_basis

EPS = np.finfo(np.float64).eps
U32 = 2.0**-24  # float32 unit roundoff
ROUNDING = 1e-12  # relative to the largest |L_lm|: exact up to float64 rounding

# Reproducible property tests: the same examples on every run and in CI, no deadline (the
# machine is shared), few enough examples to keep the whole module well under a minute.
PROPERTIES = settings(
    max_examples=40,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.too_slow],
)


def rel_to_max(a, b):
    """max |a − b| / max |b|: the error relative to the largest reference coefficient."""
    return np.abs(a - b).max() / np.abs(b).max()


def one_hot(shape, row, col, value=1.0, dtype=np.float64):
    pixels = np.zeros(shape + (3,), dtype=dtype)
    pixels[row, col] = value
    return pixels


def one_texel_integral(height, width, row, col, max_order=2, nodes=16):
    """∫ Y_lm over one texel by Gauss-Legendre in θ and φ (for maps too big for texel_integral).

    Integrating in θ (not z = cos θ) keeps the pole texels free of cancellation: the integrand
    Y sin θ is evaluated directly, so the result is accurate to ~eps relative to itself.
    """
    g, gw = np.polynomial.legendre.leggauss(nodes)
    d_theta, d_phi = pi / height, 2.0 * pi / width
    theta = (row + 0.5 + 0.5 * g) * d_theta
    phi = pi - (col + 0.5 + 0.5 * g) * d_phi
    t, p = np.meshgrid(theta, phi, indexing="ij")
    dirs = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1)
    w_theta = gw * 0.5 * d_theta * np.sin(theta)
    w_phi = gw * 0.5 * d_phi
    return np.einsum("abk,a,b->k", sh_basis(dirs, max_order), w_theta, w_phi)


def random_rotation(rng):
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q *= np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


# --------------------------------------------------------------------------------------------
# 1. Dynamic range
# --------------------------------------------------------------------------------------------


def sun_and_sky(dtype, sun_value, shape=(64, 128)):
    """A sun of a few texels straddling the seam near the zenith, over a dim textured sky.

    The sun texels replace the sky (zero sky there), so sun + sky is exact in ``dtype`` and
    the two parts can be projected separately: projection is linear.
    """
    rng = np.random.default_rng(11)
    sky = (1e-3 * (0.5 + rng.random(shape + (3,)))).astype(dtype)
    sun = np.zeros_like(sky)
    rows, cols = slice(3, 5), [shape[1] - 1, 0, 1]
    sky[rows, cols] = 0.0
    sun[rows, cols] = sun_value
    return sun, sky


@pytest.mark.parametrize(
    "dtype, sun_value",
    [(np.float32, 1e6), (np.float16, 65504.0)],  # float16 cannot hold 1e6: 65504 is its max
)
def test_sun_over_dim_sky_is_exact_in_float64(dtype, sun_value):
    """1e6 (float16: 65504) over a 1e-3 sky: 9 (float16: 7.8) decades in one image.

    Reference 1: the same texels integrated independently of the core (``texel_integral``:
    Gauss-Legendre over each texel, in float64). (Projecting the float64 upcast would compare
    the projection with itself: it upcasts its input first.)
    Reference 2: sun and sky projected separately in float64 and added (linearity).
    Both must agree to ROUNDING relative to the largest |L_lm| (the sun's), i.e. no digit is
    lost to the input dtype; and the sky alone must survive the subtraction
    project(sun + sky) − project(sun) to a few ulps of the sun's coefficients.
    """
    sun, sky = sun_and_sky(dtype, sun_value)
    both = sun + sky
    assert both.dtype == dtype and np.array_equal(both.astype(np.float64) - sun, sky)
    got = project_equirect(both)
    independent = texel_integral(both, lambda d: sh_basis(d, 2), nodes=6)
    sun_only = project_equirect(sun.astype(np.float64))
    sky_only = project_equirect(sky.astype(np.float64))
    assert rel_to_max(got, independent) < ROUNDING
    assert rel_to_max(got, sun_only + sky_only) < ROUNDING

    # The sky is 1e-6 (float16: 1e-5) of the sun's largest coefficient. Each float64 sum is
    # correct to a few ulps of its largest partial sums (~max|L_sun|), and the subtraction of
    # two such sums adds at most one more ulp: 64 ulps of max|L_sun| is a safe bound.
    recovered = got - project_equirect(sun)
    tolerance = 64 * EPS * np.abs(sun_only).max()
    assert np.abs(recovered - sky_only).max() < tolerance
    # ... which is a small relative error on the sky's own L00 (≈ 3.5e-3)
    assert tolerance / sky_only[0].min() < 1e-8


# --------------------------------------------------------------------------------------------
# 2. Extremes of size and place
# --------------------------------------------------------------------------------------------

H, W = 32, 64


@pytest.mark.parametrize(
    "shape, row, col",
    [
        ((H, W), 0, 5),  # top pole row
        ((H, W), H - 1, 17),  # bottom pole row
        ((H, W), 9, 0),  # seam, first column (u = 0, facing -X)
        ((H, W), 9, W - 1),  # seam, last column
        ((H, W), 0, W - 1),  # pole and seam at once
        ((H, W), H // 2 - 1, 20),  # just above the equator
        ((H, W), H // 2, 20),  # just below
        ((H + 1, W), H // 2, 33),  # odd height: the middle row straddles the equator
    ],
)
def test_single_texel_equals_its_exact_integral(shape, row, col):
    """One bright texel: L_lm = ∫ Y_lm over that texel, to ROUNDING of its own largest L_lm.

    Relative to the texel's own coefficients, not to a whole map's: the pole texels are
    ~50× smaller than the equator's, so this is stricter than the random-map test.
    """
    pixels = one_hot(shape, row, col, value=1.0)
    expected = texel_integral(pixels, lambda d: sh_basis(d, 4))
    assert rel_to_max(project_equirect(pixels, 4), expected) < ROUNDING


@pytest.mark.parametrize("shape", [(1, 1), (1, 2), (2, 1), (2, 4), (3, 2)])
def test_tiny_maps_texel_by_texel(shape):
    """Every texel of a 1×1 … 3×2 map (texels up to a hemisphere) integrates exactly."""
    for row in range(shape[0]):
        for col in range(shape[1]):
            pixels = one_hot(shape, row, col, value=2.5)
            # texels up to a whole sphere: 40 Gauss nodes per side resolve cos 4φ over 2π
            expected = texel_integral(pixels, lambda d: sh_basis(d, 4), nodes=40)
            assert rel_to_max(project_equirect(pixels, 4), expected) < ROUNDING, (row, col)


@pytest.mark.parametrize("height", [8192, 65536])
@pytest.mark.parametrize("row", [0, -1])
def test_pole_texels_of_tall_maps_to_rounding(height, row):
    """Pole-row texels of tall maps keep full relative accuracy (1e-12 of their own L_lm).

    Their weights are tiny (the integrand vanishes like sin θ); the difference of an
    antiderivative loses about eps·H there (2.4e-12 at H = 8192, 1.9e-11 at 65536, measured
    when the core used it), the per-row Gauss-Legendre rule does not.
    """
    w = 8
    r = row % height
    pixels = one_hot((height, w), r, 3, value=1.0, dtype=np.float32)
    expected = one_texel_integral(height, w, r, 3)
    assert rel_to_max(project_equirect(pixels)[:, 0], expected) < ROUNDING


@pytest.mark.slow
def test_one_hot_texels_on_a_16k_map():
    """16384×8192 float32 RGB, three single texels (one per channel): top pole at column 0,
    bottom pole at column W−1, equator at column W−1. Zero pages are not committed by
    np.zeros, so this costs a few seconds and little RAM; the projection's peak is checked."""
    h, w = 8192, 16384
    pixels = np.zeros((h, w, 3), dtype=np.float32)
    places = [(0, 0), (h - 1, w - 1), (h // 2, w - 1)]
    for channel, (r, c) in enumerate(places):
        pixels[r, c, channel] = 1.0
    tracemalloc.start()
    try:
        coeffs = project_equirect(pixels)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    # measured 50 MiB on 2 cores: a 25 MiB block of float64 rows per thread
    assert peak < 1 << 28, f"peak extra memory {peak / 2**20:.0f} MiB"
    for channel, (r, c) in enumerate(places):
        expected = one_texel_integral(h, w, r, c)
        assert rel_to_max(coeffs[:, channel], expected) < ROUNDING, (r, c)


@pytest.mark.parametrize("dtype", [np.float16, np.float32, np.float64])
@pytest.mark.parametrize("shape", [(1, 1), (7, 3, 4), (64, 128)])
@pytest.mark.parametrize("order", [2, 4])
def test_all_zero_map_gives_exactly_zero(dtype, shape, order):
    shape = shape if len(shape) == 3 else shape + (3,)
    pixels = np.zeros(shape, dtype=dtype)
    pixels[..., 0] = -0.0
    coeffs = project_equirect(pixels, order)
    assert coeffs.shape == ((order + 1) ** 2, 3)
    assert not coeffs.any()


def test_values_near_float32_max_stay_finite_and_exact():
    """Texels up to 3.4e38: float64 accumulation cannot overflow (4π · 3.4e38 ≈ 4e39).

    Scaling by 2^127 is exact in binary floating point, so the projection of m · 2^127 must
    equal 2^127 × the projection of m bit for bit (m in [1, 2), a small-valued map).
    """
    rng = np.random.default_rng(12)
    m = (1.0 + rng.random((16, 32, 3))).astype(np.float32)
    m[5, 7] = np.nextafter(np.float32(2.0), np.float32(0.0))  # × 2^127 = float32 max
    scale = np.float32(2.0**127)
    huge = m * scale
    assert np.isfinite(huge).all() and huge.max() == np.finfo(np.float32).max
    coeffs = project_equirect(huge)
    assert np.isfinite(coeffs).all()
    assert np.array_equal(coeffs, 2.0**127 * project_equirect(m))

    everywhere = np.full((8, 16, 3), np.finfo(np.float32).max, dtype=np.float32)
    c = project_equirect(everywhere)
    assert np.isfinite(c).all()
    assert c[0] == pytest.approx(2.0 * sqrt(pi) * float(np.finfo(np.float32).max), rel=ROUNDING)


@pytest.mark.parametrize("shape", [(4, 8, 3), (256, 512, 3)])  # one thread, then several
def test_coefficients_that_overflow_float64_are_an_error(shape):
    """1e308 everywhere (finite) has L00 = 2√π·1e308 > float64 max: a ValueError, and no
    RuntimeWarning on the way, from the caller's thread or from a worker thread."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ValueError, match="too large|overflow"):
            project_equirect(np.full(shape, 1e308))


# --------------------------------------------------------------------------------------------
# 3. Non-finite and negative texels (the project_equirect docstring's policy)
# --------------------------------------------------------------------------------------------


def test_many_non_finite_texels_are_counted_and_the_first_five_located():
    pixels = np.ones((16, 32, 3), dtype=np.float32)
    bad = [(0, 0, np.nan), (0, 31, -np.inf), (3, 4, np.inf), (7, 0, np.nan), (8, 8, np.nan),
           (15, 31, -np.inf), (15, 0, np.nan)]
    for r, c, v in bad:
        pixels[r, c, 1] = v  # one channel is enough to make the texel non-finite
    with pytest.raises(ValueError) as info:
        project_equirect(pixels)
    message = str(info.value)
    assert "7 non-finite" in message and "and 2 more" in message
    located = "".join(f".*row {r}, column {c}" for r, c, _ in bad[:5])
    assert re.search(located, message)
    assert "(row 15" not in message


def test_non_finite_in_late_row_blocks_zeroed_under_huge_dynamic_range():
    """NaN/Inf in the second row block and the last row of a float32 map with a 1e6 sun:
    nonfinite='zero' gives bit for bit the map with those texels zeroed."""
    sun, sky = sun_and_sky(np.float32, 1e6, shape=(100, 200))
    pixels = sun + sky
    pixels[33, 150, 2] = np.inf
    pixels[99, 199, 0] = np.nan
    with pytest.raises(ValueError, match=r"2 non-finite .*row 33, column 150.*row 99, column 199"):
        project_equirect(pixels)
    cleaned = pixels.copy()
    cleaned[~np.isfinite(cleaned)] = 0.0
    zeroed = project_equirect(pixels, nonfinite="zero")
    assert np.isfinite(zeroed).all()
    assert np.array_equal(zeroed, project_equirect(cleaned))


def test_float16_overflow_is_reported_as_inf():
    """A half-float image whose sun saturated to inf (1e5 > 65504) is non-finite input."""
    pixels = np.full((8, 16, 3), 0.5, dtype=np.float16)
    with np.errstate(over="ignore"):
        pixels[2, 5] = np.float32(1e5)
    assert np.isinf(pixels[2, 5]).all()
    with pytest.raises(ValueError, match=r"1 non-finite .*row 2, column 5"):
        project_equirect(pixels)
    expected = project_equirect(np.where(np.isfinite(pixels), pixels, 0))
    assert np.array_equal(project_equirect(pixels, nonfinite="zero"), expected)


def test_unknown_nonfinite_policy_is_rejected():
    with pytest.raises(ValueError, match="nonfinite"):
        project_equirect(np.ones((2, 4, 3)), nonfinite="clamp")


def test_small_negative_texels_are_kept_not_clamped():
    """Like the bundled HDRIs (a 3e4 sun, small negative texels): the negatives contribute."""
    rng = np.random.default_rng(13)
    pixels = (0.2 + rng.random((32, 64, 3))).astype(np.float32)
    pixels[10, 10] = 3e4
    negative = rng.random((32, 64)) < 0.05
    pixels[negative] = -1e-3 * rng.random((negative.sum(), 3)).astype(np.float32)
    got = project_equirect(pixels)
    positive_part = project_equirect(np.maximum(pixels, 0))
    negative_part = project_equirect(np.minimum(pixels, 0))
    assert np.abs(got - (positive_part + negative_part)).max() < 64 * EPS * np.abs(got).max()
    # clamping would be visible: the negative part is far above that rounding level
    assert np.abs(got - positive_part).max() > 1e6 * 64 * EPS * np.abs(got).max()
    one = one_hot((32, 64), 31, 63, value=-7.0, dtype=np.float32)
    assert np.array_equal(project_equirect(one), -project_equirect(-one))


# --------------------------------------------------------------------------------------------
# 4. Long rotation chains
# --------------------------------------------------------------------------------------------


def test_thousand_rotations_composed_then_inverted():
    """D(R1000)…D(R1), then D of the inverse composite rotation: back to the start.

    Each D is orthogonal to ~1e-15 and rounding errors add like a random walk, so 1000
    steps stay far below 1e-10 relative to max |L| (measured ~3e-13 at order 4).
    """
    rng = np.random.default_rng(14)
    rotations = [random_rotation(rng) for _ in range(1000)]
    order, n = 4, 25
    composite_d, composite_r = np.eye(n), np.eye(3)
    for r in rotations:
        composite_d = sh_rotation_matrix(r, order) @ composite_d
        composite_r = r @ composite_r
    coeffs = rng.normal(size=(n, 3))
    back = sh_rotation_matrix(composite_r.T, order) @ (composite_d @ coeffs)
    assert rel_to_max(back, coeffs) < 1e-10
    # the product of 1000 D's is still the D of the product, and still orthogonal
    assert np.abs(composite_d - sh_rotation_matrix(composite_r, order)).max() < 1e-10
    assert np.abs(composite_d @ composite_d.T - np.eye(n)).max() < 1e-10


def test_thousand_rotations_applied_one_by_one_and_undone_in_reverse():
    rng = np.random.default_rng(15)
    rotations = [random_rotation(rng) for _ in range(1000)]
    start = rng.normal(size=(9, 3)) * np.array([1e-3, 1.0, 1e3])  # channels of unequal scale
    coeffs = start
    for r in rotations:
        coeffs = rotate_coefficients(coeffs, r)
    for l in range(3):  # band energy kept along the way
        band = slice(l * l, (l + 1) ** 2)
        energy = (start[band] ** 2).sum(axis=0)
        assert np.abs((coeffs[band] ** 2).sum(axis=0) / energy - 1.0).max() < 1e-10
    for r in reversed(rotations):
        coeffs = rotate_coefficients(coeffs, r.T)
    for channel in range(3):  # relative to each channel's own scale
        assert rel_to_max(coeffs[:, channel], start[:, channel]) < 1e-10


# --------------------------------------------------------------------------------------------
# 5. The node group's float32 arithmetic: evaluation orders of eq. 13
# --------------------------------------------------------------------------------------------
# Each evaluator takes float32 coefficients L (9,) of one channel and float32 normals (N, 3)
# and does every operation in float32 (numpy rounds each float32 op to float32, like each node
# of a shader tree). The reference is eq. 13 in float64 at the same float32 inputs, so only
# the evaluation error is measured.

F32 = np.float32
c1, c2, c3, c4, c5 = (F32(c) for c in (C1, C2, C3, C4, C5))
TWO = F32(2.0)


def folded_coefficients(coeffs):
    """Eq. 13 as a polynomial in the monomials 1, x, y, z, xy, yz, xz, x²−y², z² (float64)."""
    L00, L1m1, L10, L11, L2m2, L2m1, L20, L21, L22 = np.asarray(coeffs, dtype=np.float64)
    return np.array(
        [C4 * L00 - C5 * L20, 2 * C2 * L11, 2 * C2 * L1m1, 2 * C2 * L10,
         2 * C1 * L2m2, 2 * C1 * L2m1, 2 * C1 * L21, C1 * L22, C3 * L20]
    )


def monomials(normals):
    """The 9 monomials in float64, and their absolute versions (x²+y² for x²−y²)."""
    x, y, z = np.asarray(normals, dtype=np.float64).T
    one = np.ones_like(x)
    values = np.stack([one, x, y, z, x * y, y * z, x * z, x * x - y * y, z * z])
    absolute = np.stack([one, abs(x), abs(y), abs(z), abs(x * y), abs(y * z), abs(x * z),
                         x * x + y * y, z * z])
    return values, absolute


def eval_eq13(L, n):
    """(a) eq. 13 as printed, left to right, products and constants in float32."""
    L00, L1m1, L10, L11, L2m2, L2m1, L20, L21, L22 = L
    x, y, z = n.T
    e = (c1 * L22) * (x * x - y * y)
    e = e + (c3 * L20) * (z * z)
    e = e + c4 * L00
    e = e - c5 * L20
    e = e + (TWO * c1) * ((L2m2 * x) * y + (L21 * x) * z + (L2m1 * y) * z)
    return e + (TWO * c2) * (L11 * x + L1m1 * y + L10 * z)


def eval_horner(L, n):
    """(b) nested: k0 + x(a1 + c1L22 x + …) + y(…) + z(a3 + c3L20 z), all in float32."""
    L00, L1m1, L10, L11, L2m2, L2m1, L20, L21, L22 = L
    x, y, z = n.T
    a11 = c1 * L22
    ex = (TWO * c2) * L11 + x * a11 + y * ((TWO * c1) * L2m2) + z * ((TWO * c1) * L21)
    ey = (TWO * c2) * L1m1 - y * a11 + z * ((TWO * c1) * L2m1)
    ez = (TWO * c2) * L10 + z * (c3 * L20)
    return (c4 * L00 - c5 * L20) + x * ex + y * ey + z * ez


def _matrix_form(M, n):
    v = [n[:, 0], n[:, 1], n[:, 2], np.ones(len(n), F32)]
    e = np.zeros(len(n), F32)
    for r in range(4):
        row = M[r, 0] * v[0]
        for c in range(1, 4):
            row = row + M[r, c] * v[c]
        e = e + v[r] * row
    return e


def eval_matrix_f32(L, n):
    """(c) nᵀMn, n = (x, y, z, 1), with M (eq. 12) built in float32 too."""
    L00, L1m1, L10, L11, L2m2, L2m1, L20, L21, L22 = L
    M = np.array([[c1 * L22, c1 * L2m2, c1 * L21, c2 * L11],
                  [c1 * L2m2, -c1 * L22, c1 * L2m1, c2 * L1m1],
                  [c1 * L21, c1 * L2m1, c3 * L20, c2 * L10],
                  [c2 * L11, c2 * L1m1, c2 * L10, c4 * L00 - c5 * L20]], dtype=F32)
    return _matrix_form(M, n)


def eval_matrix_f64(L, n):
    """(c') nᵀMn with M precomputed in float64 on the CPU and uploaded as float32."""
    L00, L1m1, L10, L11, L2m2, L2m1, L20, L21, L22 = np.asarray(L, dtype=np.float64)
    M = np.array([[C1 * L22, C1 * L2m2, C1 * L21, C2 * L11],
                  [C1 * L2m2, -C1 * L22, C1 * L2m1, C2 * L1m1],
                  [C1 * L21, C1 * L2m1, C3 * L20, C2 * L10],
                  [C2 * L11, C2 * L1m1, C2 * L10, C4 * L00 - C5 * L20]]).astype(F32)
    return _matrix_form(M, n)


def eval_basis_sum(L, n):
    """(d) Σ_i Â_l L_i Y_i(n) in index order: the SH basis and Â_l L_i in float32."""
    x, y, z = n.T
    y00, y1, yxy, y20, y22 = (F32(v) for v in (0.5 * sqrt(1 / pi), sqrt(3 / (4 * pi)),
                                               0.5 * sqrt(15 / pi), 0.25 * sqrt(5 / pi),
                                               0.25 * sqrt(15 / pi)))
    basis = [np.full_like(x, y00), y1 * y, y1 * z, y1 * x, yxy * (x * y), yxy * (y * z),
             y20 * (F32(3) * (z * z) - F32(1)), yxy * (x * z), y22 * (x * x - y * y)]
    a = [F32(pi)] + [F32(2 * pi / 3)] * 3 + [F32(pi / 4)] * 5
    e = (a[0] * L[0]) * basis[0]
    for i in range(1, 9):
        e = e + (a[i] * L[i]) * basis[i]
    return e


# The node group (sh_lighting/blender/shading/nodes.py) computes each factor from n = (x, y, z) as below
# and sums the terms L_lm × factor in a chain of Multiply Add nodes whose order it chooses;
# tests/blender/shading/test_node_precision.py checks, node by node, that this is what it builds.
NODE_ORDERS = {
    "L00 first, index order": (0, 1, 2, 3, 4, 5, 6, 7, 8),
    "L00, L20, then index": (0, 6, 1, 2, 3, 4, 5, 7, 8),
    "band 2 first, L00 last": (8, 7, 6, 5, 4, 3, 2, 1, 0),
    "band 2, L00, band 1": (8, 7, 6, 5, 4, 0, 3, 2, 1),
}
NODE_GROUP_ORDER = "band 2 first, L00 last"


def node_factors(n):
    """{term index: float32 factor}, as nodes.py forms them: SCALE by 2c2 (band 1), n ⊙ (y, z,
    x) then SCALE by 2c1, and Dot Products of (x², y², z²) with (−c5, −c5, c3 − c5) (the L20
    factor c3 z² − c5 on the unit sphere) and (c1, −c1, 0); c4 for L00."""
    x, y, z = n.T
    xx, yy, zz = x * x, y * y, z * z

    def dot(w):
        return (xx * F32(w[0]) + yy * F32(w[1])) + zz * F32(w[2])

    linear, cross = F32(2.0 * C2), F32(2.0 * C1)
    return {0: c4, 1: y * linear, 2: z * linear, 3: x * linear, 4: (x * y) * cross,
            5: (y * z) * cross, 6: dot((-C5, -C5, C3 - C5)), 7: (z * x) * cross,
            8: dot((C1, -C1, 0.0))}


def multiply_add(a, b, c, fused=False):
    """a·b + c with two roundings (Cycles' SVM), or one when ``fused`` (a GPU's fma)."""
    if not fused:
        return a * b + c
    return (np.float64(a) * np.asarray(b, np.float64) + np.asarray(c, np.float64)).astype(F32)


def eval_node_chain(L, n, order, fused=False):
    """Σ L_lm × factor summed in ``order``: the first term a Multiply, then Multiply Adds."""
    factors = node_factors(n)
    total = None
    for index in order:
        if total is None:
            total = np.broadcast_to(L[index] * factors[index], n.shape[:1]).astype(F32)
        else:
            total = multiply_add(L[index], factors[index], total, fused)
    return total


def eval_folded(L, n):
    """(e1) fold every constant into the coefficients in float64 — including the constant
    term c4 L00 − c5 L20 — round the 9 to float32, then a float32 dot product with the
    monomials (1, x, y, z, xy, yz, xz, x²−y², z²)."""
    K = folded_coefficients(L).astype(F32)
    x, y, z = n.T
    e = np.full_like(x, K[0])
    for k, m in zip(K[1:], [x, y, z, x * y, y * z, x * z, x * x - y * y, z * z]):
        e = e + k * m
    return e


def eval_grouped(L, n):
    """(e2) c4L00 + c3L20 (z² − 1/3) + …: coefficients folded in float64, z² − 1/3 in float32."""
    L64 = np.asarray(L, dtype=np.float64)
    K = folded_coefficients(L).astype(F32)
    x, y, z = n.T
    e = F32(C4 * L64[0]) + F32(C3 * L64[6]) * (z * z - F32(1 / 3))
    for k, m in zip(K[1:8], [x, y, z, x * y, y * z, x * z, x * x - y * y]):
        e = e + k * m
    return e


EVALUATORS = {
    "a eq.13 as printed": eval_eq13,
    "b Horner": eval_horner,
    "c nMn, M in f32": eval_matrix_f32,
    "c' nMn, M f64->f32": eval_matrix_f64,
    "d sum A_l L_i Y_i": eval_basis_sum,
    "e1 fold f64, f32 dot": eval_folded,
    "e2 c3L20(z^2-1/3)+c4L00": eval_grouped,
}
for _name, _order in NODE_ORDERS.items():
    EVALUATORS[f"nodes: {_name}"] = partial(eval_node_chain, order=_order)
    EVALUATORS[f"nodes: {_name}, fma"] = partial(eval_node_chain, order=_order, fused=True)
RECOMMENDED = "e1 fold f64, f32 dot"


def gamma(k):
    """Higham's γ_k = k u / (1 − k u): the bound on k compounded float32 roundings."""
    return k * U32 / (1.0 - k * U32)


def evaluation_normals():
    """4000 random normals, the axes, and rings at the equator and at z² = 1/3 (where the
    L20 term of eq. 13 cancels internally), as float32 unit vectors."""
    t = np.linspace(0.0, 2.0 * pi, 256, endpoint=False)
    parts = [random_directions(4000, seed=21), np.eye(3), -np.eye(3)]
    for z in (0.0, sqrt(1 / 3), -sqrt(1 / 3)):
        r = sqrt(1.0 - z * z)
        parts.append(np.stack([r * np.cos(t), r * np.sin(t), np.full_like(t, z)], axis=-1))
    n = np.concatenate(parts)
    return (n / np.linalg.norm(n, axis=1, keepdims=True)).astype(F32)


def coefficient_sets():
    """Coefficient magnitudes 1e-6 … 1e6 in three families (one channel each):

    * generic: random signs, all 9 of the same scale;
    * physical: L_lm of non-negative lighting (5 deltas of random power + a constant sky);
    * near-cancel: c4 L00 ≈ c5 L20 (constant term −c4 L00 δ, δ = 1e-2, 1e-4, 1e-7), the
      other 7 coefficients 0, 1e-3 or 1 times L00. Not physical: for non-negative lighting
      c4 L00 − c5 L20 ≥ (3/8) c4 L00 (see the property test below).
    """
    rng = np.random.default_rng(22)
    families = {"generic": [], "physical": [], "near-cancel": []}
    for k in range(-6, 7):
        s = 10.0**k
        for _ in range(3):
            families["generic"].append(s * rng.normal(size=9))
            dirs = random_directions(5, seed=int(rng.integers(1 << 30)))
            sky = np.zeros(9)
            sky[0] = 2.0 * sqrt(pi) * rng.random()
            families["physical"].append(s * (rng.random(5) @ sh_basis(dirs) + sky))
        for delta in (1e-2, 1e-4, 1e-7):
            for rest in (0.0, 1e-3, 1.0):
                L = s * rest * rng.normal(size=9)
                L[0] = s
                L[6] = s * (C4 / C5) * (1.0 + delta * rng.choice([-1.0, 1.0]))
                families["near-cancel"].append(L)
    return families


def measure_evaluation_errors():
    """Worst error of each evaluator in each family, relative to three scales:

    * S  = Σ |folded coefficient × monomial| (the polynomial's own condition scale: what a
      backward-stable float32 evaluation of E can reach, whatever the order of terms);
    * S13 = the same with c4 L00 and c5 L20 counted apart (eq. 13's terms as printed);
    * |E| where E is not tiny: |E| ≥ 0.1 max_n |E| (the visible part of the shading).
    """
    n = evaluation_normals()
    values, absolute = monomials(n)
    results = {}
    for family, sets in coefficient_sets().items():
        for name, evaluate in EVALUATORS.items():
            worst = np.zeros(3)
            for L in sets:
                L32 = L.astype(F32)
                K = folded_coefficients(L32)
                reference = K @ values
                scale = np.abs(K) @ absolute
                L00, L20 = np.float64(L32[0]), np.float64(L32[6])
                scale13 = scale - abs(K[0]) + abs(C4 * L00) + abs(C5 * L20)
                got = evaluate(L32, n)
                assert got.dtype == F32
                err = np.abs(got.astype(np.float64) - reference)
                visible = np.abs(reference) >= 0.1 * np.abs(reference).max()
                worst = np.maximum(worst, [
                    (err / scale).max(),
                    (err / scale13).max(),
                    (err[visible] / np.abs(reference[visible])).max(),
                ])
            results[family, name] = worst
    return results


FAMILIES = ("generic", "physical", "near-cancel")


def evaluation_table(results):
    """The measured errors as a text table (``make bench`` prints it:
    benchmarks/bench_eq13_orders.py)."""
    lines = ["float32 eq. 13, worst error in units of u = 2^-24, relative to S | S13 | |E|",
             f"{'form':38s}" + "".join(f"{f:>30s}" for f in FAMILIES)]
    for name in EVALUATORS:
        cells = ("{:>8.3g} {:>8.3g} {:>10.3g}".format(*(results[f, name] / U32))
                 for f in FAMILIES)
        lines.append(f"{name:38s}" + "".join(f"{c:>30s}" for c in cells))
    return "\n".join(lines)


def test_float32_evaluation_orders_of_eq13():
    results = measure_evaluation_errors()
    families = FAMILIES

    # The recommended order (e1): 1 rounding per folded coefficient, ≤ 2 per monomial, 1 per
    # product and 8 additions: ≤ γ_12 · S in every family (measured ≤ 5.5 u). The matrix form
    # with M folded in float64 (c') is as good (≤ 10 roundings per term; measured ≤ 4.8 u).
    for family in families:
        assert results[family, RECOMMENDED][0] <= gamma(12), family
        assert results[family, "c' nMn, M f64->f32"][0] <= gamma(12), family
    # Every order a node chain can take is backward stable in eq. 13's own terms: c4·L00
    # (1 rounding), factors ≤ 4 (constant, square, product, sum), 2 per Multiply Add × 8:
    # ≤ γ_14 · S13 always, and since S13 ≤ (13/3) S for non-negative lighting (c5 |L20| ≤
    # (5/8) c4 L00 and c4 L00 − c5 L20 ≥ (3/8) c4 L00), ≤ (13/3) γ_14 · S on physical lighting.
    chains = [name for name in EVALUATORS if name.startswith("nodes: ")]
    for name in chains:
        for family in families:
            assert results[family, name][1] <= gamma(14), (family, name)
        assert results["physical", name][0] <= 13 / 3 * gamma(14), name
    # The order nodes.py builds is the one that rounds least on physical lighting, with and
    # without fma (measured 3.05 u and 2.17 u against 5.77 u for L00 first in index order).
    for suffix in ("", ", fma"):
        chosen = results["physical", f"nodes: {NODE_GROUP_ORDER}{suffix}"][0]
        others = [results["physical", f"nodes: {o}{suffix}"][0] for o in NODE_ORDERS]
        assert chosen <= min(others) * (1.0 + 1e-9)
        assert chosen < 0.75 * results["physical", f"nodes: L00 first, index order{suffix}"][0]
    # Only near-cancelling (non-physical) coefficients separate the orders: every form that
    # forms c4 L00 − c5 L20 in float32 loses ≥ 1000× more than folding it in float64 first.
    for name in ("a eq.13 as printed", "b Horner", "c nMn, M in f32", "e2 c3L20(z^2-1/3)+c4L00",
                 *chains):
        assert results["near-cancel", name][0] > 1000 * results["near-cancel", RECOMMENDED][0]


# --------------------------------------------------------------------------------------------
# 6. Properties over random non-negative maps with a wide exponent range
# --------------------------------------------------------------------------------------------


@st.composite
def radiance_maps(draw, shape=None):
    """Non-negative H×W×3 maps (H ≤ 16, W ≤ 32), values spread over up to 12 decades
    (10^±6), some texels zero, maybe a 1e6 sun texel. Built by numpy from a drawn seed:
    hypothesis shrinks the size, the dynamic range, the share of zeros and the sun."""
    h = shape[0] if shape else draw(st.integers(1, 16))
    w = shape[1] if shape else draw(st.integers(1, 32))
    decades = draw(st.integers(0, 12))
    zeros = draw(st.sampled_from([0.0, 0.3, 0.9]))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    x = rng.random((h, w, 3)) * 10.0 ** rng.uniform(-decades / 2, decades / 2, (h, w, 3))
    x[rng.random((h, w)) < zeros] = 0.0
    if draw(st.booleans()):  # a sun: one texel holding nearly all the light (the stiff case)
        x[draw(st.integers(0, h - 1)), draw(st.integers(0, w - 1))] = 1e6 * (1.0 + rng.random(3))
    return x


def absolute_power(pixels):
    """A(X) = ∫ |X| dω per channel (= 2√π L00 of |X|); every |L_lm| ≤ A for l ≤ 2 since
    max |Y_lm| = √(5/4π) < 1."""
    return 2.0 * sqrt(pi) * project_equirect(np.abs(pixels))[0]


scalars = st.one_of(st.floats(1e-3, 1e3), st.floats(-1e3, -1e-3))


@PROPERTIES
@given(data=st.data(), a=scalars, b=scalars)
def test_projection_is_linear(data, a, b):
    x = data.draw(radiance_maps())
    y = data.draw(radiance_maps(shape=x.shape[:2]))
    got = project_equirect(a * x + b * y)
    expected = a * project_equirect(x) + b * project_equirect(y)
    magnitude = abs(a) * absolute_power(x) + abs(b) * absolute_power(y)
    assert (np.abs(got - expected) <= 1e-12 * magnitude + 1e-300).all()


def e9_test_normals(pixels):
    """48 random normals and the axes, plus the two worst cases for the brightest texel s:
    its horizon (u = 0, where E9 − E = 3/32 P for a delta) and u = −8/15 (E9's minimum)."""
    dirs = texel_directions(*pixels.shape[:2])
    s = dirs.reshape(-1, 3)[np.argmax(pixels.sum(axis=-1))]
    p = np.cross(s, [0.3, 0.5, 0.8])
    p /= np.linalg.norm(p)
    q = -8 / 15 * s + sqrt(1 - 64 / 225) * p
    return np.concatenate([random_directions(48, seed=23), np.eye(3), -np.eye(3), [p, q]])


@PROPERTIES
@given(pixels=radiance_maps())
def test_nine_term_irradiance_error_bounds(pixels):
    """docs/reference.md §2 for any non-negative lighting of power P: |E9 − E| ≤ (3/32) P and
    E9 ≥ −(19/480) P (= −0.03958 P, E9's minimum at u = −8/15).

    E is the exact irradiance of the piecewise-constant map: reference_irradiance integrates
    the clamped cosine over each texel exactly, so the bounds hold to rounding, 1×1 maps
    included.
    """
    h, w, _ = pixels.shape
    power = 2.0 * sqrt(pi) * project_equirect(pixels)[0]
    if not (power > 0).all():
        pixels = pixels + 1e-3  # a channel with no light has nothing to bound
        power = 2.0 * sqrt(pi) * project_equirect(pixels)[0]
    coeffs = project_equirect(pixels)
    n = e9_test_normals(pixels)
    e9 = irradiance(coeffs, n)
    e_ref = reference_irradiance(pixels, n)
    assert (np.abs(e9 - e_ref) <= (3 / 32 + 1e-12) * power).all()
    assert (e9 >= -(19 / 480 + 1e-12) * power).all()
    # the constant term of eq. 13 cannot nearly cancel for non-negative lighting:
    # max Y20 = √5 Y00, so L20 ≤ √5 L00 and c5 L20 ≤ (√5/8)·√5 c4 L00 = (5/8) c4 L00
    assert (C4 * coeffs[0] - C5 * coeffs[6] >= (3 / 8 - 1e-12) * C4 * coeffs[0]).all()


@PROPERTIES
@given(data=st.data())
def test_rolling_columns_rotates_coefficients_about_z(data):
    """np.roll by k columns is the lighting rotated by α = −2πk/W about z, exactly: each pair
    (L_l,m, L_l,−m) turns by mα (checked independently of rotation.py, and against it)."""
    pixels = data.draw(radiance_maps())
    w = pixels.shape[1]
    shift = data.draw(st.integers(0, w - 1))
    before = project_equirect(pixels)
    after = project_equirect(np.roll(pixels, shift, axis=1))
    alpha = -2.0 * pi * shift / w
    expected = before.copy()
    for l in range(1, 3):
        for m in range(1, l + 1):
            cos_part, sin_part = before[l * (l + 1) + m], before[l * (l + 1) - m]
            ca, sa = np.cos(m * alpha), np.sin(m * alpha)
            expected[l * (l + 1) + m] = ca * cos_part - sa * sin_part
            expected[l * (l + 1) - m] = sa * cos_part + ca * sin_part
    scale = absolute_power(pixels)
    assert (np.abs(after - expected) <= 1e-12 * scale + 1e-300).all()
    rz = np.array([[np.cos(alpha), -np.sin(alpha), 0.0], [np.sin(alpha), np.cos(alpha), 0.0],
                   [0.0, 0.0, 1.0]])
    assert (np.abs(after - rotate_coefficients(before, rz)) <= 1e-12 * scale + 1e-300).all()
