"""Irradiance from lighting coefficients (eq. 5-13) and its brute-force ground truth (eq. 1).

* ``irradiance_coefficients``: E_lm = Â_l L_lm (eq. 7, Â_l from eq. 8);
* ``irradiance``: E(n) by the paper's quadratic polynomial (eq. 13) for 9 coefficients, by the
  general sum Σ Â_l L_lm Y_lm(n) (eq. 6) for any other order;
* ``irradiance_matrices``: the 4×4 M of eq. 12 per colour channel, E(n) = nᵀ M n, n = (x, y, z, 1);
* ``reference_irradiance``: eq. 1 summed over every texel of an equirectangular map, each
  texel's ∫ max(n·ω, 0) dω exact (``texel_cosine``): the ground truth the paper's error
  claims are measured against, exact for the piecewise-constant map the projection sees.

All coefficients are raw radiance L_lm (not pre-convolved), shape ((order+1)², 3), Blender axes.
"""

from math import pi, sqrt

import numpy as np

from .coefficients import check_coefficients as checked_coefficients
from .downsample import block_downsample, whole_factor
from .equirect import check_finite_pixels, check_pixels, column_centres
from .projection import thread_count, thread_pool
from .sh import band_of_each_coefficient, lambert_band_factors, order_of, sh_basis, spread_normals
from .texel_cosine import clamped_cosine_integral, texel_moments

# Eq. 13's constants, in closed form (the paper prints them rounded to 6 digits).
A0, A1, A2 = lambert_band_factors(2)
C1 = A2 * 0.25 * sqrt(15.0 / pi)  # 0.429043
C2 = 0.5 * A1 * sqrt(3.0 / (4.0 * pi))  # 0.511664
C3 = 3.0 * A2 * 0.25 * sqrt(5.0 / pi)  # 0.743125
C4 = A0 * 0.5 * sqrt(1.0 / pi)  # 0.886227
C5 = A2 * 0.25 * sqrt(5.0 / pi)  # 0.247708

# Largest |constant × polynomial| over the unit sphere of each term of eq. 13 (c4; 2 c2 for
# y, z, x; c1 for 2xy, 2yz, 2xz and x² − y²; c3 − c5 = 2 c5 for c3 z² − c5):
# TERM_PEAKS[i] · |L_i| is the most term i adds to or removes from E(n) anywhere.
TERM_PEAKS = np.array(
    [C4, 2.0 * C2, 2.0 * C2, 2.0 * C2, C1, C1, max(abs(-C5), abs(C3 - C5)), C1, C1]
)

# Running sums along rows and arc sums per normal are handled in blocks of about this many values.
CHUNK_VALUES = 1 << 22
# Texel-normal pairs given to the exact kernel at a time (its temporaries: ~100 MB).
KERNEL_PAIRS = 1 << 17
# Threads for the reference: from this many texel-normal pairs, at least this many normals each.
THREADED_PAIRS = 1 << 24
NORMALS_PER_THREAD = 32
# error_estimate's reference: maps wider than this are box-downsampled to about this width.
ESTIMATE_WIDTH = 512


def check_coefficients(coeffs):
    """Validate an ((order+1)², 3) coefficient array; returns (float64 array, order).

    The project's one coefficient check (``coefficients.check_coefficients``) for any order.
    """
    c = checked_coefficients(coeffs, count=None)
    return c, order_of(c.shape[0])


def irradiance_coefficients(coeffs):
    """E_lm = Â_l L_lm (eq. 7), same shape as ``coeffs``."""
    c, order = check_coefficients(coeffs)
    return c * lambert_band_factors(order)[band_of_each_coefficient(order)][:, None]


def _check_normals(normals):
    n = np.asarray(normals, dtype=np.float64)
    if n.ndim < 1 or n.shape[-1] != 3:
        raise ValueError(f"normals must have shape (..., 3), got {np.shape(normals)}")
    return n


def irradiance(coeffs, normals):
    """E(n) at unit ``normals`` (..., 3) → (..., 3) RGB: eq. 13 for 9 coefficients, else eq. 6."""
    c, order = check_coefficients(coeffs)
    n = _check_normals(normals)
    if order != 2:
        return sh_basis(n, order) @ irradiance_coefficients(c)
    x, y, z = (n[..., i, None] for i in range(3))
    L00, L1m1, L10, L11, L2m2, L2m1, L20, L21, L22 = c
    return (
        C1 * L22 * (x * x - y * y)
        + C3 * L20 * z * z
        + C4 * L00
        - C5 * L20
        + 2.0 * C1 * (L2m2 * x * y + L21 * x * z + L2m1 * y * z)
        + 2.0 * C2 * (L11 * x + L1m1 * y + L10 * z)
    )


def irradiance_matrices(coeffs):
    """M of eq. 12 for each channel, shape (3, 4, 4): E(n) = nᵀ M n with n = (x, y, z, 1)."""
    c, order = check_coefficients(coeffs)
    if order != 2:
        raise ValueError(f"the matrix form needs the 9 coefficients of order 2, got order {order}")
    L00, L1m1, L10, L11, L2m2, L2m1, L20, L21, L22 = c
    m = np.empty((3, 4, 4))
    m[:, 0] = np.stack([C1 * L22, C1 * L2m2, C1 * L21, C2 * L11], axis=-1)
    m[:, 1] = np.stack([C1 * L2m2, -C1 * L22, C1 * L2m1, C2 * L1m1], axis=-1)
    m[:, 2] = np.stack([C1 * L21, C1 * L2m1, C3 * L20, C2 * L10], axis=-1)
    m[:, 3] = np.stack([C2 * L11, C2 * L1m1, C2 * L10, C4 * L00 - C5 * L20], axis=-1)
    return m


def reference_irradiance(pixels, normals):
    """Ground-truth E(n) (eq. 1) of an equirectangular map at ``normals`` (..., 3) → (..., 3).

    Σ over every texel of L · ∫_texel max(n·ω, 0) dω with each texel's integral exact, as the
    projection integrates each texel exactly: the map is taken as piecewise constant, so a
    constant map of any size (1×1 included) gives π L to rounding and its 9-term error is 0.

    A texel wholly above n's horizon contributes L n · V, V = ∫_texel ω dω
    (``texel_cosine.texel_moments``); one wholly below, nothing; the few the horizon may cross
    (n · V̂ within sin(reach) of 0, reach: how far the texel extends from its mean direction
    V̂) take the exact kernel ``clamped_cosine_integral``. Texel (i, j) has V = (A_i cos φ_j,
    A_i sin φ_j, B_i), so in each row the texels above the horizon are one arc of columns and
    their sum is A_i (n_x Σ L cos φ + n_y Σ L sin φ) + B_i n_z Σ L, from running sums along
    the row: O(texels + rows × normals + crossing texels), float64, in blocks of rows, the
    normals shared out between threads (``projection.thread_pool``).
    """
    a = check_pixels(pixels)
    n = _check_normals(normals)
    check_finite_pixels(a)
    height, width, _ = a.shape
    flat_n = n.reshape(-1, 3)
    lengths = np.linalg.norm(flat_n, axis=-1)
    flat_n = flat_n / np.where(lengths > 0.0, lengths, 1.0)[:, None]  # E is linear in |n|
    rows = max(1, CHUNK_VALUES // (9 * max(width + 1, flat_n.shape[0])))
    # the normals are shared out between threads (each normal's E is its own sum)
    count = flat_n.shape[0]
    threads = (thread_count(count, NORMALS_PER_THREAD)
               if height * width * count >= THREADED_PAIRS else 1)
    bands = np.linspace(0, count, threads + 1).astype(int)
    work = [(a, flat_n[n0:n1], rows) for n0, n1 in zip(bands, bands[1:])]
    if len(work) == 1:
        result = _reference_sums(*work[0])
    else:
        pool = thread_pool(len(work))
        result = np.concatenate([done.result() for done in
                                 [pool.submit(_reference_sums, *w) for w in work]])
    return (result * lengths[:, None]).reshape(n.shape[:-1] + (3,))


def _reference_sums(a, flat_n, rows):
    """``reference_irradiance`` of unit normals ``flat_n`` (N, 3), ``rows`` rows at a time."""
    height, width, _ = a.shape
    theta = np.linspace(0.0, pi, height + 1)
    z_edges = np.cos(theta)
    phi_edges = pi - (2.0 * pi / width) * np.arange(width + 1)  # column j: [phi_edges[j+1], [j]]
    first_column = texel_moments(z_edges[1:], z_edges[:-1], phi_edges[1], phi_edges[0])
    edge = _horizon_margin(theta, width, first_column)  # (H,): |n · V| ≤ edge may cross
    # the boundary test (_boundary_range) holds for texels less than a quarter turn across
    small_texels = 2.0 * pi / width + pi / height < 0.5 * pi
    z_roots = np.sin(theta)  # √(1 − z²) at the row edges
    phi_trig = np.cos(phi_edges), np.sin(phi_edges)
    phi = column_centres(width)
    trig = np.stack([np.ones(width), np.cos(phi), np.sin(phi)], axis=-1)  # (W, 3)
    result = np.zeros((flat_n.shape[0], 3))
    x, y, z = (flat_n[:, k, None, None] for k in range(3))
    for r0 in range(0, height, rows):
        r1 = min(height, r0 + rows)
        radiance = a[r0:r1, :, :3].astype(np.float64)
        bounds = _arc_bounds(flat_n, first_column[r0:r1], edge[r0:r1])
        # running sums along each row of L, L cos φ, L sin φ: (h, W + 1, 3 terms, 3 channels)
        sums = np.zeros((r1 - r0, width + 1, 3, 3))
        np.cumsum(radiance[:, :, None, :] * trig[None, :, :, None], axis=1, out=sums[:, 1:])
        first, count = _above_arcs(bounds, width)
        end = first + count
        row = np.arange(r1 - r0)[None, :]
        wrapped = end > width
        arc = sums[row, np.minimum(end, width)] - sums[row, first]
        arc += np.where(wrapped, 1.0, 0.0)[..., None, None] * sums[row, np.where(wrapped,
                                                                                 end - width, 0)]
        big_a = np.hypot(first_column[r0:r1, 0], first_column[r0:r1, 1])[None, :, None]
        big_b = first_column[r0:r1, 2][None, :, None]
        result += (big_a * (x * arc[:, :, 1] + y * arc[:, :, 2])
                   + big_b * z * arc[:, :, 0]).sum(axis=1)
        near = _near_horizon(bounds, width)
        for p0 in range(0, near[0].size, KERNEL_PAIRS):
            pair_n, row, col = (index[p0 : p0 + KERNEL_PAIRS] for index in near)
            texel = (z_edges[row + r0 + 1], z_edges[row + r0], phi_edges[col + 1],
                     phi_edges[col])
            if small_texels:  # a third of the texels near the horizon lie wholly above it
                # (n · V) or below it (0): only those it may cross take the exact kernel
                lo, hi = _boundary_range(flat_n[pair_n], texel[0], texel[1],
                                         z_roots[row + r0 + 1], z_roots[row + r0],
                                         *(t[col + k] for k in (1, 0) for t in phi_trig))
                above = lo > SIGN_MARGIN
                cross = ~above & (hi >= -SIGN_MARGIN)
            else:
                above, cross = np.zeros(pair_n.size, bool), np.ones(pair_n.size, bool)
            kernel = np.zeros(pair_n.size)
            kernel[above] = (texel_moments(*(t[above] for t in texel))
                             * flat_n[pair_n[above]]).sum(axis=-1)
            kernel[cross] = clamped_cosine_integral(flat_n[pair_n[cross]],
                                                    *(t[cross] for t in texel))
            for channel in range(3):
                result[:, channel] += np.bincount(
                    pair_n, kernel * radiance[row, col, channel], minlength=flat_n.shape[0]
                )
    return result


# n·ω within this of 0 somewhere on a texel's boundary: the texel takes the exact kernel.
SIGN_MARGIN = 1e-12


def _boundary_range(normals, z_lo, z_hi, root_lo, root_hi, c0, s0, c1, s1):
    """(lo, hi), (P,) each: the least and largest n·ω on the boundary of each texel (z in
    [z_lo, z_hi], φ in [φ_0, φ_1]) for pairs of unit ``normals`` (P, 3) and texels (P,),
    given √(1 − z²) at z_lo, z_hi and cos, sin of φ_0, φ_1 (the caller's tables).

    With ω = (√(1 − z²) cos φ, √(1 − z²) sin φ, z), n·ω = n_z z + √(1 − z²) g(φ),
    g = n_x cos φ + n_y sin φ. Along a parallel the extremes are at the corners or where
    g' = −n_x sin φ + n_y cos φ changes sign inside (a maximum r = |n_xy| of g where it goes
    from + to −, a minimum −r where from − to +); along a meridian n·ω = n_z cos θ +
    g sin θ likewise, its θ-derivative g cos θ − n_z sin θ changing sign inside at ±|(n_z, g)|
    (each edge shorter than a half turn holds at most one such point). The only critical
    points inside a texel are ±n, and a texel less than a quarter turn across holding n (−n)
    lies wholly above (below) the horizon, which its boundary then says: for such texels
    n·ω > 0 (< 0) on the boundary means on the whole texel (the caller's condition).
    """
    nx, ny, nz = normals[:, 0], normals[:, 1], normals[:, 2]
    r = np.hypot(nx, ny)
    g0, g1 = nx * c0 + ny * s0, nx * c1 + ny * s1  # g at the two meridians
    turns0, turns1 = ny * c0 - nx * s0, ny * c1 - nx * s1  # g' there
    peak, trough = (turns0 > 0.0) & (turns1 < 0.0), (turns0 < 0.0) & (turns1 > 0.0)
    lo, hi = np.full(len(nz), np.inf), np.full(len(nz), -np.inf)
    for z, root in ((z_hi, root_hi), (z_lo, root_lo)):
        base = nz * z
        for g in (g0, g1):
            corner = base + root * g
            lo, hi = np.minimum(lo, corner), np.maximum(hi, corner)
        hi = np.where(peak, np.maximum(hi, base + root * r), hi)
        lo = np.where(trough, np.minimum(lo, base - root * r), lo)
    for g in (g0, g1):
        rise_a = g * z_hi - nz * root_hi  # d(n·ω)/dθ at θ_a (top) and θ_b
        rise_b = g * z_lo - nz * root_lo
        size = np.hypot(nz, g)
        hi = np.where((rise_a > 0.0) & (rise_b < 0.0), np.maximum(hi, size), hi)
        lo = np.where((rise_a < 0.0) & (rise_b > 0.0), np.minimum(lo, -size), lo)
    return lo, hi


def _horizon_margin(theta, width, first_column):
    """Per row, the |n · V| below which the horizon of a unit n may cross a texel of the row.

    Every point of a texel is within reach = (θ distance from the mean direction V̂ to the
    farther row edge) + max sin θ · Δφ/2 (along its parallel) of V̂, so n·ω there is within
    sin(reach) of n · V̂ = n · V / |V|. Rows reaching a quarter turn (or with V = 0, the whole
    sphere of a 1×1 map) always go to the exact kernel.
    """
    norm = np.linalg.norm(first_column, axis=-1)
    theta_v = np.arctan2(np.hypot(first_column[:, 0], first_column[:, 1]), first_column[:, 2])
    widest = np.maximum(np.sin(theta[:-1]), np.sin(theta[1:]))
    widest = np.where((theta[:-1] <= 0.5 * pi) & (theta[1:] >= 0.5 * pi), 1.0, widest)
    reach = np.maximum(theta_v - theta[:-1], theta[1:] - theta_v) + widest * (pi / width)
    return np.where((reach < 0.5 * pi) & (norm > 0.0),
                    np.sin(np.minimum(reach, 0.5 * pi)) * norm, np.inf)


def _arc_bounds(normals, first_column, edge):
    """(α, lo, hi), each (N, h): n · V of texel (i, j) is A_i r cos(φ_j − α) + B_i n_z, so
    n · V > edge where cos(φ − α) > hi, n · V < −edge where cos(φ − α) < lo, and the horizon
    may cross where lo ≤ cos(φ − α) ≤ hi. A row whose n · V does not vary with φ (r = 0)
    gets ±inf bounds: all above (hi = lo = −inf), all near (lo = −inf, hi = inf) or all below
    (hi = lo = inf)."""
    r = np.hypot(normals[:, 0], normals[:, 1])[:, None]
    alpha = np.arctan2(normals[:, 1], normals[:, 0])[:, None] + np.zeros_like(edge)
    scale = np.hypot(first_column[:, 0], first_column[:, 1])[None, :] * r
    offset = first_column[:, 2][None, :] * normals[:, 2:3]
    level_hi = np.where(offset > edge, -np.inf, np.inf)
    level_lo = np.where(offset >= -edge, -np.inf, np.inf)
    with np.errstate(divide="ignore", invalid="ignore"):
        hi = np.where(scale > 0, (edge - offset) / scale, level_hi)
        lo = np.where(scale > 0, (-edge - offset) / scale, level_lo)
    return alpha, lo, hi


def _above_arcs(bounds, width):
    """(first column, number of columns), (N, h): the texels wholly above each normal's
    horizon in each row, cos(φ_j − α) > hi: one arc, or every column when hi < −1."""
    alpha, _, hi = bounds
    everything = hi < -1.0
    part = (hi >= -1.0) & (hi < 1.0)
    half = np.arccos(np.clip(hi, -1.0, 1.0))
    step = 2.0 * pi / width
    # column j is above for (j + ½) step in (π − α − half, π − α + half), modulo 2π
    first = np.floor((pi - alpha - half) / step - 0.5) + 1.0
    last = np.ceil((pi - alpha + half) / step - 0.5) - 1.0
    count = np.where(everything, width, np.where(part, np.clip(last - first + 1.0, 0, width), 0))
    first = np.where(everything, 0.0, first)
    return np.mod(first, width).astype(np.intp), count.astype(np.intp)


def _near_horizon(bounds, width):
    """(normal, row, column) index arrays of the texels with |n · V| ≤ edge: lo ≤ cos(φ_j − α)
    ≤ hi holds on at most two arcs of φ per normal and row, whose columns are listed directly
    (no scan of every pair)."""
    alpha, lo, hi = bounds
    empty = (lo > 1.0) | (hi < -1.0)
    whole = ~empty & (hi >= 1.0) & (lo <= -1.0)
    one_arc_top = ~empty & ~whole & (hi >= 1.0)  # ψ = φ − α in [−outer, outer]
    one_arc_bottom = ~empty & ~whole & (lo <= -1.0)  # ψ in [inner, 2π − inner]
    inner = np.arccos(np.clip(hi, -1.0, 1.0))
    outer = np.arccos(np.clip(lo, -1.0, 1.0))
    two = ~(empty | whole | one_arc_top | one_arc_bottom)
    arcs = [  # (start ψ, end ψ, where)
        (np.full_like(inner, -pi), np.full_like(inner, pi), whole),
        (-outer, outer, one_arc_top),
        (inner, 2.0 * pi - inner, one_arc_bottom),
        (inner, outer, two),
        (-outer, -inner, two),
    ]
    found = [], [], []
    step = 2.0 * pi / width
    for start, end, where in arcs:
        k, i = np.nonzero(where)
        if not k.size:
            continue
        # Column j's centre is φ_j = π − (j + ½) step; φ in [α + start, α + end].
        first = np.ceil((pi - (alpha[k, i] + end[k, i])) / step - 0.5).astype(np.int64)
        last = np.floor((pi - (alpha[k, i] + start[k, i])) / step - 0.5).astype(np.int64)
        count = np.clip(last - first + 1, 0, width)
        total = int(count.sum())
        if not total:
            continue
        owner = np.repeat(np.arange(k.size), count)
        within = np.arange(total) - np.repeat(np.cumsum(count) - count, count)
        found[0].append(k[owner])
        found[1].append(i[owner])
        found[2].append((first[owner] + within) % width)
    if not found[0]:
        none = np.zeros(0, dtype=np.int64)
        return none, none, none
    return tuple(np.concatenate(part) for part in found)


def total_power(coeffs):
    """P = ∫ L dω of each channel, (3,): L00 / Y00 = 2√π L00."""
    c, _ = check_coefficients(coeffs)
    return 2.0 * sqrt(pi) * c[0]


def error_over_power(estimate, reference, power):
    """|E − E_ref| / P per normal and channel: the paper's error measure.

    Ramamoorthi and Hanrahan (2001) give the 9-term irradiance error as a fraction of the total
    light P = ∫ L dω (``total_power``; docs/reference.md §2: at most 3/32 anywhere and 0.0307 on
    average for non-negative lighting). ``estimate``, ``reference``: (N, 3) irradiance at the
    same normals; ``power``: (3,). A channel with P ≤ 0 is refused (ValueError).
    """
    p = np.asarray(power, dtype=np.float64)
    if np.any(p <= 0.0):
        raise ValueError("a channel has total power ≤ 0 (L00 ≤ 0): relative errors are undefined")
    return np.abs(np.asarray(estimate, dtype=np.float64) - reference) / p


def relative_error(estimate, reference, power):
    """(mean, max) of ``error_over_power``: the worst channel's mean over the normals, and the
    largest value over normals and channels, as floats (the paper's mean and max error).
    """
    err = error_over_power(estimate, reference, power)
    return float(err.mean(axis=0).max()), float(err.max())


def error_estimate(pixels, coeffs, count=256, reference_width=ESTIMATE_WIDTH):
    """{"mean", "max"} of ``bounded_error_estimate`` (the preset metadata's form), or None."""
    estimate = bounded_error_estimate(pixels, coeffs, count, reference_width)
    return None if estimate is None else {"mean": estimate["mean"], "max": estimate["max"]}


def bounded_error_estimate(pixels, coeffs, count=256, reference_width=ESTIMATE_WIDTH):
    """{"mean", "max", "bound", "reference_size", "downsample"}: the 9-term irradiance error / total power
    ∫L dω of an equirect map, or None (a channel without light).

    The paper's measure (``relative_error``): |E9 − E| at ``count`` normals
    (``sh.spread_normals``) against the brute-force ``reference_irradiance`` (eq. 1), divided
    per channel by the channel's power 2√π L00; mean is the worst channel's mean, max the
    largest over normals and channels. The command line's and the preset builder's estimate.

    Maps wider than ``reference_width`` take E from their box downsample by a whole factor
    (``downsample.block_downsample``, about ``reference_width`` wide; the cost of the exact
    reference grows with the width): E changes by at most Σ_B d_B Σ_t Ω_t |L_t − L̄_B| per
    channel (``downsample`` module docstring), so "mean" and "max" are each within "bound" (that
    over the power, the largest channel's; 0 at full resolution) of the full-resolution values.
    "reference_size" is the (height, width) the reference was computed at, "downsample" the
    (map, bound) of that downsample (None at full resolution) for a further reference of the
    same map (``downsampled_reference``).
    """
    power = total_power(coeffs)
    if not (power > 0.0).all():
        return None
    normals = spread_normals(count)
    reference, spread, size, made = downsampled_reference(pixels, normals, reference_width,
                                                          keep=True)
    mean, largest = relative_error(irradiance(coeffs, normals), reference, power)
    return {"mean": mean, "max": largest, "bound": float((spread / power).max()),
            "reference_size": size, "downsample": made}


def downsampled_reference(pixels, normals, reference_width=ESTIMATE_WIDTH, downsample=None,
                          keep=False):
    """(E, bound, size): ``reference_irradiance`` at unit ``normals`` (N, 3) of ``pixels``
    box-downsampled by a whole factor to about ``reference_width`` wide (None: never), the
    (3,) bound on |E − E_full| of every normal (``downsample``; 0 at full resolution) and
    the (height, width) it was computed at.

    ``downsample``: that (map, bound) when already made (``keep`` True appends it to the
    result, None at full resolution), so that a second reference of the same map at other
    normals (``lights.extract_lights``) does not pass over the pixels again."""
    a = check_pixels(pixels)
    height, width = a.shape[:2]
    factor = whole_factor(height, width, reference_width) if reference_width else 1
    if factor == 1:
        found = reference_irradiance(a, normals), np.zeros(3), (height, width)
        return found + (None,) if keep else found
    if downsample is None or downsample[0].shape[:2] != (height // factor, width // factor):
        downsample = block_downsample(a, factor, with_bound=True)
    source, spread = downsample
    if not np.isfinite(source).all():
        check_finite_pixels(a)  # names the texels; else the sums overflowed float64
    found = reference_irradiance(source, normals), spread, source.shape[:2]
    return found + (downsample,) if keep else found
