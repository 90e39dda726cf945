"""Prefiltering: L_lm = ∫ L(ω) Y_lm(ω) dω of an equirectangular map (eq. 10).

The map is taken as piecewise constant over its texels and every Y_lm is integrated exactly
over every texel's area, not sampled at its centre. Each real SH separates as

    Y_lm(θ, φ) = K_lm P_l^|m|(cos θ) · {1, cos mφ, sin |m|φ},

so the integral over texel (i, j) is a row weight times a column weight:

* row weight   w_l|m|[i] = ∫ K_lm P_l^|m|(cos θ) sin θ dθ over row i. The integrand is a
  trigonometric polynomial of degree l + 1 in θ, integrated to rounding by a Gauss-Legendre
  rule of far higher degree (checked against its closed-form antiderivative);
* column weight ∫ cos mφ dφ = (2 sin(m h) / m) cos(m φ_j) with h = π/W (sin likewise).

The sum over texels is done in two steps: blocks of rows against the row weights (one float64
matrix product per block, whatever the input dtype), then the resulting (T, W) sums against
the column weights. A constant map therefore gives exactly L00 = 2√π c and zeros elsewhere (to
rounding), and replicating texels does not change the result.
"""

from math import pi

import numpy as np

from .equirect import check_pixels, column_centres, describe_nonfinite, row_centres
from .sh import legendre_q, normalisation, num_coefficients, sh_index

# Rows cast to float64 and multiplied at a time: 64 rows of a 4096-wide RGBA map are 8 MB.
ROWS_PER_BLOCK = 64


def _theta_functions(max_order):
    """The (l, m >= 0) pairs whose θ parts the row weights integrate, in a fixed order."""
    return [(l, m) for l in range(max_order + 1) for m in range(l + 1)]


def _theta_integrands(theta, max_order):
    """f_t(θ) = K_lm Q_l^m(cos θ) sin^m θ · sin θ for each θ function t = (l, m >= 0)."""
    q = legendre_q(max_order, np.cos(theta))
    sin_t = np.sin(theta)
    return [
        normalisation(l, m) * q[l, m] * sin_t ** (m + 1) for l, m in _theta_functions(max_order)
    ]


def row_weights(height, max_order=2):
    """w[i, t] = ∫ K_lm P_l^m(cos θ) sin θ dθ over row i for each θ function t = (l, m >= 0).

    The integrand is a trigonometric polynomial of degree l + 1 in θ (entire), so a
    Gauss-Legendre rule of ``2 max_order + 16`` nodes per row integrates it to rounding on
    any row, even the whole [0, π] of a one-row map (error bound below 1e-17 of the integrand's
    size). Unlike the difference of an antiderivative (``row_weights_closed_form``), nothing
    cancels, so the tiny weights of the pole rows of tall maps keep full relative accuracy.
    Returns shape (H, number of θ functions).
    """
    nodes, node_weights = np.polynomial.legendre.leggauss(2 * max_order + 16)
    half = 0.5 * pi / height
    theta = row_centres(height)[:, None] + half * nodes[None, :]
    return np.stack([f @ node_weights for f in _theta_integrands(theta, max_order)], axis=-1) * half


def row_weights_closed_form(height, max_order=2):
    """The same weights from the exact antiderivative (the slow reference for the tests).

    f(θ) is a trigonometric polynomial of degree l + 1, so N > 2(l + 1) equispaced samples
    give its Fourier series a_k, b_k exactly, and ∫ over [θ_c - Δ/2, θ_c + Δ/2] is
    a_0 Δ + Σ_k (2 sin(kΔ/2)/k)(a_k cos kθ_c + b_k sin kθ_c). Exact in exact arithmetic,
    but the terms cancel in the pole rows, losing about eps·H of relative accuracy there.
    """
    n = 4 * (max_order + 2)
    samples = np.stack(_theta_integrands(2.0 * pi * np.arange(n) / n, max_order))
    spectrum = np.fft.rfft(samples, axis=1) / n
    k = np.arange(1, max_order + 3)
    a0 = spectrum[:, 0].real
    a, b = 2.0 * spectrum[:, k].real, -2.0 * spectrum[:, k].imag
    delta = pi / height
    theta_c = row_centres(height)[:, None]
    shrink = 2.0 * np.sin(k * delta / 2.0) / k
    return (
        a0[None, :] * delta
        + (np.cos(k * theta_c) * shrink) @ a.T
        + (np.sin(k * theta_c) * shrink) @ b.T
    )


def column_weights(width, max_order=2):
    """c[j, m], s[j, m]: ∫ cos mφ dφ and ∫ sin mφ dφ over column j, for m = 0..max_order."""
    m = np.arange(max_order + 1)
    half = pi / width
    shrink = np.where(m == 0, 2.0 * half, 2.0 * np.sin(m * half) / np.maximum(m, 1))
    phi = column_centres(width)[:, None] * m[None, :]
    return np.cos(phi) * shrink, np.sin(phi) * shrink


def row_sums(pixels, weights, zero_nonfinite=False):
    """B[t, j, c] = Σ_i w[i, t] pixels[i, j, c] in float64, shape (T, W, 3).

    Blocks of rows are cast to float64 (from any input dtype and strides) and multiplied by
    their row weights in one matrix product each; only a block and B are ever held.
    """
    height, width, channels = pixels.shape
    total = np.zeros((weights.shape[1], width * channels))
    product = np.empty_like(total)
    block = np.empty((ROWS_PER_BLOCK, width * channels))
    for r0 in range(0, height, ROWS_PER_BLOCK):
        r1 = min(height, r0 + ROWS_PER_BLOCK)
        x = block[: r1 - r0]
        x.reshape(r1 - r0, width, channels)[...] = pixels[r0:r1]
        if zero_nonfinite:
            x[~np.isfinite(x)] = 0.0
        np.dot(weights[r0:r1].T, x, out=product)
        total += product
    return total.reshape(-1, width, channels)[..., :3]


def project_equirect(pixels, max_order=2, nonfinite="raise"):
    """L_lm (eq. 10) of an equirectangular map, shape ((max_order+1)², 3), float64, Blender axes.

    ``pixels``: (H, W, 3 or 4) float radiance in Blender's equirectangular convention, rows top
    to bottom (see ``equirect``). Alpha is ignored; negative texels are kept (they are data).
    Exact for the piecewise-constant image. ``nonfinite``: "raise" (default) raises a
    ValueError saying how many NaN/Inf texels there are and where; "zero" treats them as 0.
    """
    a = check_pixels(pixels)
    if nonfinite not in ("raise", "zero"):
        raise ValueError(f'nonfinite must be "raise" or "zero", got {nonfinite!r}')
    height = a.shape[0]
    weights = row_weights(height, max_order)
    with np.errstate(over="ignore", invalid="ignore"):  # checked below, with a clear message
        return _combine(a, weights, max_order, nonfinite)


def _combine(a, weights, max_order, nonfinite):
    """Row sums, the non-finite policy, then the column weights: ((max_order+1)², 3)."""
    sums = row_sums(a, weights)
    if not np.isfinite(sums).all():
        count, message = describe_nonfinite(a)
        if count and nonfinite == "raise":
            raise ValueError(
                f"pixels contain {message}: repair the image, or pass nonfinite='zero' "
                "to treat those texels as black"
            )
        sums = row_sums(a, weights, zero_nonfinite=True)
    cos_w, sin_w = column_weights(a.shape[1], max_order)
    coeffs = np.zeros((num_coefficients(max_order), 3))
    for t, (l, m) in enumerate(_theta_functions(max_order)):
        coeffs[sh_index(l, m)] = cos_w[:, m] @ sums[t]
        if m > 0:
            coeffs[sh_index(l, -m)] = sin_w[:, m] @ sums[t]
    if not (np.isfinite(sums).all() and np.isfinite(coeffs).all()):
        raise ValueError(
            "the image's values are too large: its integrals overflow float64 "
            f"(largest texel {np.nanmax(np.abs(a[..., :3])):.3g}); scale the image down"
        )
    return coeffs
