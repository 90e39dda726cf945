"""The edited world of World Edit, numerically: what clamping at zero takes away.

World Edit renders L'(ω) = max(0, k L_world(ω) + Σ (L_lm − L⁰_lm) Y_lm(ω)) (k = 1 for a world
with coefficients of its own L⁰, else 0 with L⁰ = 0). Without the clamp its nine terms are
exactly the designed L_lm (the projection is linear and L⁰ is the world's own); where the sum
goes below zero the clamp adds light back. ``clamped_edit`` measures that on the world's map:
the share of the world's light the clamp changes and the nine terms of the clamped world,
projected texel by texel (eq. 10) in world axes.
"""

from dataclasses import dataclass

import numpy as np

from .edits import LUMINANCE
from .equirect import texel_directions, texel_solid_angles
from .sh import sh_basis
from .world_map import mapping_rotation


@dataclass(frozen=True)
class Clamping:
    """share: luminance the clamp adds (Σ max(0, −x) dΩ) as a fraction of the edited world's
    luminance power before the clamp (Σ x dΩ; of |Σ x| when that is not positive); texels:
    fraction of the sphere clamped; projected: (9, 3) L_lm of the clamped world; difference:
    largest |projected − designed| over the 27 numbers, as a fraction of the designed L00's
    luminance (of the largest |L_lm| when that is not positive)."""

    share: float
    texels: float
    projected: np.ndarray
    difference: float


def edited_world(pixels, strength, euler, delta, keep):
    """(values (H, W, 3) of x = k s L_image + Σ Δ_lm Y_lm(ω), solid angles (H, 1), Y (H, W, 9))
    on the equirect image's texels, ω = Rᵀ d the world direction of image direction d
    (``world_map``): the edited world before the clamp."""
    rgb = np.asarray(pixels, dtype=np.float64)[..., :3]
    height, width = rgb.shape[:2]
    directions = texel_directions(height, width) @ mapping_rotation(euler).T  # rows: Rᵀ d
    basis = sh_basis(directions)
    x = (float(keep) * float(strength)) * rgb + basis @ np.asarray(delta, dtype=np.float64)
    return x, texel_solid_angles(height, width)[:, None], basis


def clamped_edit(pixels, strength, euler, delta, keep, designed, luminance=LUMINANCE):
    """``Clamping`` of the edited world (module docstring). ``pixels``: the world's equirect
    map (H, W, 3 or 4) as the image stores it, ``strength`` and ``euler`` (the Mapping
    rotation or None) as the world applies them; ``delta``: (9, 3) L − L⁰; ``keep``: k;
    ``designed``: (9, 3) the designed L_lm."""
    x, solid, basis = edited_world(pixels, strength, euler, delta, keep)
    clamped = np.maximum(x, 0.0)
    weights = np.asarray(luminance, dtype=np.float64)
    power = float(np.sum((x @ weights) * solid))
    added = float(np.sum(((clamped - x) @ weights) * solid))
    below = np.any(x < 0.0, axis=-1)
    texels = float(np.sum(below * solid) / (4.0 * np.pi))
    projected = np.einsum("hwk,hwc,h->kc", basis, clamped, solid[:, 0])
    designed = np.asarray(designed, dtype=np.float64)
    scale = float(designed[0] @ weights)
    if not scale > 0.0:
        scale = float(np.max(np.abs(designed))) or 1.0
    difference = float(np.max(np.abs(projected - designed))) / scale
    share = added / (power if power > 0.0 else max(abs(power), 1e-30))
    return Clamping(share, texels, projected, difference)
