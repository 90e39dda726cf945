"""Independent numerical integration used as a reference by the core tests.

Gauss-Legendre in z = cos θ times the trapezoid rule in φ integrates polynomials in
(x, y, z) exactly, so sphere integrals of products of SH are exact to rounding.
"""

import numpy as np


def sphere_rule(n_z=24, n_phi=48):
    """Directions (N, 3) and weights (N,) that integrate low-degree polynomials exactly."""
    z, wz = np.polynomial.legendre.leggauss(n_z)
    phi = 2.0 * np.pi * np.arange(n_phi) / n_phi
    zz, pp = np.meshgrid(z, phi, indexing="ij")
    r = np.sqrt(1.0 - zz * zz)
    dirs = np.stack([r * np.cos(pp), r * np.sin(pp), zz], axis=-1).reshape(-1, 3)
    weights = (wz[:, None] * np.full(n_phi, 2.0 * np.pi / n_phi)[None, :]).reshape(-1)
    return dirs, weights


def texel_integral(pixels, function, nodes=10):
    """∫ pixels(ω) f(ω) dω over an equirect map, each texel by a tensor Gauss-Legendre rule.

    ``function`` maps directions (..., 3) to values (..., K). Returns (K, C). Independent of the
    core's closed-form row/column weights; accurate to ~1e-15 for smooth f.
    """
    h, w, c = pixels.shape
    g, gw = np.polynomial.legendre.leggauss(nodes)
    theta = ((np.arange(h)[:, None] + 0.5 + 0.5 * g[None, :]) * np.pi / h).ravel()
    phi = (np.pi - (np.arange(w)[:, None] + 0.5 + 0.5 * g[None, :]) * 2.0 * np.pi / w).ravel()
    wt = (np.tile(gw, h) * 0.5 * np.pi / h) * np.sin(theta)
    wp = np.tile(gw, w) * 0.5 * 2.0 * np.pi / w
    tt, pp = np.meshgrid(theta, phi, indexing="ij")
    dirs = np.stack([np.sin(tt) * np.cos(pp), np.sin(tt) * np.sin(pp), np.cos(tt)], axis=-1)
    f = function(dirs)  # (h*nodes, w*nodes, K)
    weighted = f * (wt[:, None] * wp[None, :])[..., None]
    per_texel = weighted.reshape(h, nodes, w, nodes, -1).sum(axis=(1, 3))  # (h, w, K)
    return np.einsum("hwk,hwc->kc", per_texel, pixels[..., :3].astype(np.float64))


def random_directions(count, seed=0):
    rng = np.random.default_rng(seed)
    d = rng.normal(size=(count, 3))
    return d / np.linalg.norm(d, axis=1, keepdims=True)
