"""∫ max(n·ω, 0) dω over one latitude-longitude texel in closed form: the kernel of the exact
irradiance E(n) = Σ_t L_t ∫_t max(n·ω, 0) dω of a piecewise-constant map (eq. 1).

Texel z = cos θ ∈ [z_lo, z_hi], φ ∈ [φ_0, φ_1]; with n = (r cos α, r sin α, n_z),
n·ω = a + b cos ψ, a = n_z z, b = r √(1 − z²), ψ = φ − α. The z range is cut where the horizon
touches a latitude circle (z = ±r) or crosses a meridian; the φ integral of each piece is
F(ψ) = a ψ + b sin ψ between meridians or ψ = ±arccos(−a/b), and its z integral is in closed
form (∫ √(r² − z²) dz, and ∫ n_z z c dz by parts). Exact to rounding for any texel and normal
(π for every n on a 1×1 map). Derivation: docs/modules.md.
"""

from math import pi

import numpy as np

TWO_PI = 2.0 * pi


def texel_moments(z_lo, z_hi, phi0, phi1):
    """∫ ω dω over texels z ∈ [z_lo, z_hi], φ ∈ [φ_0, φ_1] (arrays broadcast): (..., 3).

    x, y: ∫ √(1 − z²) dz · (sin φ_1 − sin φ_0, cos φ_0 − cos φ_1); z: (φ_1 − φ_0)(z_hi² − z_lo²)/2.
    """
    s = _sqrt_integral(z_lo, z_hi)
    return np.stack(
        [s * (np.sin(phi1) - np.sin(phi0)), s * (np.cos(phi0) - np.cos(phi1)),
         0.5 * (phi1 - phi0) * (z_hi - z_lo) * (z_hi + z_lo)], axis=-1)


def _sqrt_integral(z_lo, z_hi):
    """∫ √(1 − z²) dz over [z_lo, z_hi] = [θ/2 − sin 2θ / 4] over θ = arccos z."""
    t_lo, t_hi = np.arccos(np.clip(z_hi, -1, 1)), np.arccos(np.clip(z_lo, -1, 1))
    return 0.5 * (t_hi - t_lo) - 0.25 * (np.sin(2 * t_hi) - np.sin(2 * t_lo))


def _moving_bound(z, r, nz):
    """Antiderivative in z of a c(z) + √(r² − z²) (F at ψ = c), for |z| ≤ r, r > 0."""
    root = np.sqrt(np.maximum((r - z) * (r + z), 0.0))
    c = np.arctan2(root, -nz * z)  # arccos(−a/b) without arccos's loss near ±1
    arc = np.arcsin(np.clip(z / r, -1.0, 1.0))
    anz = np.abs(nz)
    by_parts = 0.5 * nz * z * z * c + 0.5 * nz * nz * arc - 0.5 * anz * np.arctan2(anz * z, root)
    return by_parts + 0.5 * (z * root + r * r * arc)


def _band_integral(za, zb, nz, r, u0, u1):
    """∫ over z ∈ [za, zb] (a piece inside the band) of ∫ max(a + b cos ψ, 0) dψ, ψ ∈ [u0, u1]."""
    mid = 0.5 * (za + zb)
    c_mid = np.arctan2(np.sqrt(np.maximum((r - mid) * (r + mid), 0.0)), -nz * mid)
    shift = TWO_PI * np.floor((u0 + pi) / TWO_PI)
    u0, u1 = u0 - shift, u1 - shift  # u0 in [−π, π): only the parts k = 0, 1 can overlap
    half_z2 = 0.5 * (zb - za) * (zb + za)  # ∫ z dz
    sqrt_part = _sqrt_integral(za, zb)  # ∫ √(1 − z²) dz
    moving = _moving_bound(zb, r, nz) - _moving_bound(za, r, nz)
    total = np.zeros(np.broadcast(za, u0).shape)
    for k in (0, 1):
        centre = TWO_PI * k
        lo_fixed = u0 > centre - c_mid  # the part starts at the meridian u0
        hi_fixed = u1 < centre + c_mid
        nonempty = np.minimum(u1, centre + c_mid) > np.maximum(u0, centre - c_mid)
        hi = np.where(hi_fixed, nz * u1 * half_z2 + r * np.sin(u1) * sqrt_part,
                      centre * nz * half_z2 + moving)
        lo = np.where(lo_fixed, nz * u0 * half_z2 + r * np.sin(u0) * sqrt_part,
                      centre * nz * half_z2 - moving)
        total += np.where(nonempty, hi - lo, 0.0)
    return total


def clamped_cosine_integral(normals, z_lo, z_hi, phi0, phi1):
    """∫ max(n·ω, 0) dω over each texel, for pairs of unit ``normals`` (P, 3) and texels
    (z_lo, z_hi, phi0, phi1: (P,) each, z_lo < z_hi, 0 < φ_1 − φ_0 ≤ 2π): shape (P,)."""
    n = np.asarray(normals, dtype=np.float64)
    nx, ny, nz = n[:, 0], n[:, 1], n[:, 2]
    r = np.hypot(nx, ny)
    alpha = np.arctan2(ny, nx)
    u0, u1 = phi0 - alpha, phi1 - alpha
    # Breakpoints in z: the tangent points ±r and the horizon's crossing of each meridian.
    points = [z_lo, z_hi, -r, r]
    for u in (u0, u1):
        p = r * np.cos(u)
        d = np.hypot(nz, p)
        crossing = -p * np.where(nz < 0, -1.0, 1.0) / np.where(d > 0, d, 1.0)
        points.append(np.where(d > 0, crossing, z_lo))
    z = np.sort(np.clip(np.stack(points, axis=-1), z_lo[:, None], z_hi[:, None]), axis=-1)
    pair, piece = np.nonzero(z[:, 1:] > z[:, :-1])  # the non-empty pieces, one row each
    za, zb = z[pair, piece], z[pair, piece + 1]
    mid = 0.5 * (za + zb)
    inside = np.abs(mid) < r[pair]
    total = np.zeros(len(n))
    # Outside the band, n·ω has the sign of n_z z on the whole piece.
    out = np.nonzero(~inside & (nz[pair] * mid > 0))[0]
    moments = texel_moments(za[out], zb[out], phi0[pair[out]], phi1[pair[out]])
    np.add.at(total, pair[out], (moments * n[pair[out]]).sum(-1))
    band = np.nonzero(inside)[0]
    p = pair[band]
    values = _band_integral(za[band], zb[band], nz[p], r[p], u0[p], u1[p])
    np.add.at(total, p, values)
    return total
