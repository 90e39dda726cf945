"""Prefiltering: L_lm = ∫ L(ω) Y_lm(ω) dω of an equirectangular map (eq. 10).

The map is piecewise constant over its texels and each Y_lm is integrated exactly over each
texel: Y_lm(θ, φ) = K_lm P_l^|m|(cos θ) · {1, cos mφ, sin |m|φ} separates into a row weight
∫ K_lm P_l^|m|(cos θ) sin θ dθ (Gauss-Legendre, exact for this degree) and a column weight
∫ cos mφ dφ = (2 sin(m h) / m) cos(m φ_j), h = π/W. Rows against the column weights in float64
blocks shared between threads (one band of rows per core), then against the row weights: a
constant map gives exactly L00 = 2√π c.
"""

import os
from concurrent.futures import ThreadPoolExecutor
from functools import lru_cache
from math import pi

import numpy as np

from .equirect import NonFiniteError, check_pixels, column_centres, describe_nonfinite, row_centres
from .sh import legendre_q, normalisation, num_coefficients, sh_index

# Rows cast to float64 at a time by each thread: 64 rows of a 4096-wide RGB map are 6 MB.
ROWS_PER_BLOCK = 64
# OpenBLAS runs a product with m·n·k at most 2^18 on the calling thread alone; keeping every
# product under it lets the threads below use the cores instead of competing with BLAS's own.
SINGLE_CORE_PRODUCT = 1 << 18
MAX_THREADS = 8
# Smaller maps are summed on the calling thread: below this a second thread costs more than it
# saves (256x128: 0.9 ms with two threads started per call, see benchmarks/REPORT.md).
THREADED_TEXELS = 1 << 18


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


@lru_cache(maxsize=16)
def row_weights(height, max_order=2):
    """w[i, t] = ∫ K_lm P_l^m(cos θ) sin θ dθ over row i for each θ function t = (l, m >= 0).

    The integrand is a trigonometric polynomial of degree l + 1 in θ (entire), so a
    Gauss-Legendre rule of ``2 max_order + 16`` nodes per row integrates it to rounding on
    any row, even the whole [0, π] of a one-row map (error bound below 1e-17 of the integrand's
    size). Unlike the difference of an antiderivative (``row_weights_closed_form``), nothing
    cancels, so the tiny weights of the pole rows of tall maps keep full relative accuracy.
    Returns shape (H, number of θ functions), read-only: it is cached per (height, order).
    """
    nodes, node_weights = np.polynomial.legendre.leggauss(2 * max_order + 16)
    half = 0.5 * pi / height
    theta = row_centres(height)[:, None] + half * nodes[None, :]
    integrands = _theta_integrands(theta, max_order)
    weights = np.stack([f @ node_weights for f in integrands], axis=-1) * half
    weights.setflags(write=False)
    return weights


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


def _phi_functions(max_order):
    """Rows of ``column_sums``: (m, 0) for ∫ cos mφ (m = 0..L), then (m, 1) for ∫ sin mφ."""
    return [(m, 0) for m in range(max_order + 1)] + [(m, 1) for m in range(1, max_order + 1)]


def column_sums(pixels, max_order=2, zero_nonfinite=False):
    """S[i, k, c] = Σ_j (∫ over column j of φ function k) pixels[i, j, c], float64 (H, 2L+1, 3).

    φ function k runs over ``_phi_functions``. Rows are shared between threads in contiguous
    bands; each casts blocks of its rows to float64 and multiplies them by the weights.
    """
    height, width = pixels.shape[:2]
    weights = _stacked_column_weights(width, max_order)
    sums = np.empty((height, weights.shape[0], 3))
    threads = thread_count(height) if height * width >= THREADED_TEXELS else 1
    if threads == 1:  # a small map: no thread, no bands (their set-up was a tenth of 256x128)
        _band_column_sums(pixels, weights, sums, 0, height, zero_nonfinite)
    else:
        bands = [height * k // threads for k in range(threads + 1)]
        work = [(pixels, weights, sums, r0, r1, zero_nonfinite) for r0, r1 in zip(bands, bands[1:])]
        pool = thread_pool(len(work))
        for done in [pool.submit(_quiet_band_column_sums, *w) for w in work]:
            done.result()
    return sums


@lru_cache(maxsize=16)
def _stacked_column_weights(width, max_order):
    """The (2L+1, W) rows of ``_phi_functions``' column weights, contiguous, read-only: cached
    per width (a small map's projection was mostly this and a thread pool's start)."""
    cos_w, sin_w = column_weights(width, max_order)
    weights = np.ascontiguousarray(np.concatenate([cos_w, sin_w[:, 1:]], axis=1).T)
    weights.setflags(write=False)
    return weights


# Thread pools are the process's workers, started once per size and kept (no lighting data).
_POOLS = {}


def thread_pool(threads):
    """One long-lived pool of ``threads`` workers (starting threads per call cost ~0.5 ms),
    shared by the passes over the pixels (also ``downsample``, ``irradiance``)."""
    if threads not in _POOLS:
        _POOLS[threads] = ThreadPoolExecutor(threads, thread_name_prefix="sh_projection")
    return _POOLS[threads]


def thread_count(height, rows_per_thread=ROWS_PER_BLOCK):
    """One thread per available core, at most MAX_THREADS, and none without
    ``rows_per_thread`` rows (a block of rows)."""
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # not Linux
        cores = os.cpu_count() or 1
    return max(1, min(cores, MAX_THREADS, height // rows_per_thread))


def _quiet_band_column_sums(*args):
    """``_band_column_sums`` in a worker thread, which does not inherit the caller's errstate:
    overflow is checked afterwards (``_combine``), with a clear message."""
    with np.errstate(over="ignore", invalid="ignore"):
        _band_column_sums(*args)


def _band_column_sums(pixels, weights, sums, r0, r1, zero_nonfinite):
    """Fill sums[r0:r1]: float64 blocks of rows (channel-planar) times the column weights."""
    functions, width = weights.shape
    group = max(1, SINGLE_CORE_PRODUCT // (functions * width * 3))  # rows per product
    rows = max(group, ROWS_PER_BLOCK // group * group)
    block = np.empty((rows, 3, width))
    for b0 in range(r0, r1, rows):
        b1 = min(r1, b0 + rows)
        n = b1 - b0
        g = next(d for d in range(min(group, n), 0, -1) if n % d == 0)  # rows per product
        x = block[:n]
        x[...] = pixels[b0:b1, :, :3].transpose(0, 2, 1)
        if zero_nonfinite:
            x[~np.isfinite(x)] = 0.0
        # (n/g, F, 3g): each product is the F×W weights times W×3g texels, on one core.
        products = np.matmul(weights, x.reshape(n // g, 3 * g, width).transpose(0, 2, 1))
        sums[b0:b1] = products.reshape(n // g, functions, g, 3).transpose(0, 2, 1, 3).reshape(
            n, functions, 3
        )


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


def project_texels(values, rows, columns, height, width, max_order=2):
    """L_lm (eq. 10) of an H × W map that is zero except at texels (``rows``, ``columns``)
    (index arrays, (N,)) holding ``values`` (N, 3): Σ over those texels of their exact
    integrals w_l|m|[i] · ∫ {cos mφ, sin |m|φ} over column j (module docstring), in float64.

    What ``project_equirect`` gives for such a map, to rounding, without a pass over the other
    texels: since the projection is linear, the coefficients of a map changed at a few texels
    are the old ones plus those of the change (``lights.extract_lights``). A texel listed twice
    counts twice. Shape ((max_order+1)², 3).
    """
    v = np.asarray(values, dtype=np.float64).reshape(-1, 3)
    rows, columns = np.asarray(rows, dtype=np.intp), np.asarray(columns, dtype=np.intp)
    theta, phi = _function_pairs(max_order)
    row_w = row_weights(height, max_order)[rows][:, theta].T  # (coefficients, N)
    column_w = _stacked_column_weights(width, max_order)[phi][:, columns]  # (coefficients, N)
    return (row_w * column_w) @ v


@lru_cache(maxsize=4)
def _function_pairs(max_order):
    """(θ function, φ function) index arrays, one pair per coefficient in ``sh_index`` order:
    Y_lm's θ part is (l, |m|), its φ part cos mφ for m >= 0 and sin |m|φ for m < 0."""
    theta_index = {pair: t for t, pair in enumerate(_theta_functions(max_order))}
    phi_index = {pair: k for k, pair in enumerate(_phi_functions(max_order))}
    theta = np.empty(num_coefficients(max_order), dtype=np.intp)
    phi = np.empty_like(theta)
    for l in range(max_order + 1):
        for m in range(-l, l + 1):
            theta[sh_index(l, m)] = theta_index[l, abs(m)]
            phi[sh_index(l, m)] = phi_index[abs(m), int(m < 0)]
    theta.setflags(write=False)
    phi.setflags(write=False)
    return theta, phi


def _combine(a, weights, max_order, nonfinite):
    """Column sums, the non-finite policy, then the row weights: ((max_order+1)², 3)."""
    sums = column_sums(a, max_order)
    if not np.isfinite(sums).all():
        count, message = describe_nonfinite(a)
        if count and nonfinite == "raise":
            raise NonFiniteError(
                message, "repair the image, or pass nonfinite='zero' to treat those texels as black"
            )
        if count:  # else every texel is finite and the sums overflowed: reported below
            sums = column_sums(a, max_order, zero_nonfinite=True)
    theta, phi = _function_pairs(max_order)
    # Σ_i w_t[i] S[i, k, c] for every (θ, φ) function pair in one product, then the pairs
    # that are coefficients (eq. 10 separated: L_lm = Σ_i w_l|m|[i] Σ_j ∫φ_m(column j) L_ij).
    coeffs = np.tensordot(weights, sums, axes=(0, 0))[theta, phi]
    if not (np.isfinite(sums).all() and np.isfinite(coeffs).all()):
        raise ValueError(
            "the image's values are too large: its integrals overflow float64 "
            f"(largest texel {np.nanmax(np.abs(a[..., :3])):.3g}); scale the image down"
        )
    return coeffs
