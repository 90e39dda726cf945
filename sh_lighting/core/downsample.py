"""Box downsampling of an equirectangular map by whole factors, in one float32 pass over it.

Output texel (I, J) of factor k is the union of the k × k texels with i // k = I, j // k = J
and holds their solid-angle-weighted mean L̄_B = Σ Ω_t L_t / Σ Ω_t (the power ∫ L dω kept).
For a 1-Lipschitz kernel f (max(n·ω, 0), eq. 1) the change of ∫ L f dω is
Σ_t Ω_t (L_t − L̄_B)(k_t − k̄_B), so at most Σ_B d_B Σ_(t in B) Ω_t |L_t − L̄_B| with d_B the
block's angular diameter (``variation_bound``, returned by ``block_downsample`` beside the
map; ``irradiance.error_estimate``).
"""

from math import gcd, pi

import numpy as np

from .equirect import texel_solid_angles
from .projection import THREADED_TEXELS, thread_count, thread_pool

CACHE_VALUES = 1 << 20  # input values handled at a time (4 MB of float32; 64K: 2x slower at 8K,
#                          from numpy call overhead)


def whole_factor(height, width, target_width):
    """The smallest k dividing both ``height`` and ``width`` with width / k ≤ ``target_width``,
    or the largest common divisor if none is that large (1: the map is kept as it is)."""
    common = gcd(height, width)
    wanted = -(-width // max(1, target_width))
    for k in range(max(1, wanted), common + 1):
        if common % k == 0:
            return k
    return common


def block_downsample(pixels, factor, with_bound=False):
    """(map, bound): ``pixels`` (H, W, C ≥ 3; any strides) box-averaged by ``factor`` (dividing
    H and W) with solid-angle weights, as float64 (H/k, W/k, 3); ``bound`` the (3,)
    ``variation_bound`` of the module docstring (None unless ``with_bound``).

    Works one block row (k input rows) at a time in float32, so it adds no copy of the image;
    the block rows are shared out between threads in bands (``projection.thread_pool``), and
    each block row's share of the bound is kept apart and summed in order at the end, so the
    result does not depend on the number of threads.
    """
    height, width = pixels.shape[:2]
    k = int(factor)
    if k < 1 or height % k or width % k:
        raise ValueError(f"a downsample factor must divide {height}x{width}, got {factor!r}")
    if pixels.strides[0] < 0:  # a flipped view (Blender's readback): the same rows upwards;
        out, bound = block_downsample(pixels[::-1], k, with_bound)  # Ω_i and d_B are symmetric
        return out[::-1], bound
    out_h = height // k
    out = np.empty((out_h, width // k, 3))
    shares = np.zeros((out_h, 3)) if with_bound else None
    threads = thread_count(out_h, 1) if height * width >= THREADED_TEXELS else 1
    bands = np.linspace(0, out_h, threads + 1).astype(int)
    work = [(pixels, k, out, shares, i0, i1) for i0, i1 in zip(bands, bands[1:])]
    if len(work) == 1:
        _downsample_band(*work[0])
    else:
        pool = thread_pool(len(work))
        for done in [pool.submit(_downsample_band, *w) for w in work]:
            done.result()
    return out, (shares.sum(axis=0) if with_bound else None)


def _downsample_band(pixels, k, out, shares, i0, i1):
    """Fill out[i0:i1] (and shares[i0:i1], the bound's share of each block row, if not None)."""
    height, width, channels = pixels.shape
    out_h = height // k
    solid = texel_solid_angles(height, width)
    # angular diameter of a block row's blocks: Δθ + (widest sin θ) · min(Δφ, π)
    edges = np.linspace(0.0, pi, out_h + 1)
    widest = np.maximum(np.sin(edges[:-1]), np.sin(edges[1:]))
    widest = np.where((edges[:-1] <= 0.5 * pi) & (edges[1:] >= 0.5 * pi), 1.0, widest)
    diameter = np.minimum(pi, pi / out_h + widest * min(2.0 * pi * k / width, pi))
    # blocks of columns small enough for the core's cache: CACHE_VALUES floats of k rows.
    # In-place arithmetic, and einsum rather than matrix products: a k-vector times k rows is
    # a matrix-vector product, which OpenBLAS shares out between its own threads from about
    # 9K values, competing with this band's threads for the cores (8192x4096 by 16 with its
    # bound: 0.15-0.40 s with np.matmul, 0.10-0.13 s with einsum, benchmarks/REPORT.md).
    step = max(1, CACHE_VALUES // (k * k * channels)) * k * channels
    dtype = np.result_type(pixels.dtype, np.float32)
    acc, tmp = (np.empty(min(step, width * channels), dtype=dtype) for _ in range(2))
    dev = np.empty((k, min(step, width * channels)), dtype=dtype) if shares is not None else None
    for i in range(i0, i1):
        r0 = i * k
        w = solid[r0 : r0 + k].astype(dtype)
        area = float(solid[r0 : r0 + k].sum(dtype=np.float64)) * k
        rows = pixels[r0 : r0 + k].reshape(k, width * channels)
        for c0 in range(0, width * channels, step):
            flat = rows[:, c0 : c0 + step]
            n = flat.shape[1]
            blocks, b0 = n // (k * channels), c0 // (k * channels)
            a, t = acc[:n], tmp[:n]
            if k >= 8:  # measured: a sum of products is faster for tall blocks, the loop
                np.einsum("i,ij->j", w, flat, out=a)  # for short (einsum: no BLAS, below)
            else:
                np.multiply(flat[0], w[0], out=a)
                for r in range(1, k):
                    np.multiply(flat[r], w[r], out=t)
                    a += t
            columns = a.reshape(blocks, k, channels)
            mean = columns[:, 0].astype(np.float64)
            for j in range(1, k):
                mean += columns[:, j]
            mean /= area
            out[i, b0 : b0 + blocks] = mean[:, :3]
            if shares is not None:
                # Σ_t Ω_t |L_t − L̄_B| of each block: the block means repeated over their columns
                repeated = np.repeat(mean.astype(dtype), k, axis=0).reshape(-1)
                spread = dev[:, :n]
                np.subtract(flat, repeated, out=spread)
                np.abs(spread, out=spread)
                # Ω-weighted over the k rows (float32), then per channel in float64
                total = np.einsum("i,ij->j", w, spread).astype(np.float64).reshape(
                    -1, channels).sum(axis=0)
                shares[i] += diameter[i] * total[:3]
