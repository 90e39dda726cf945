"""An imitation of EEVEE's world sun extraction, the baseline the tests compare Extract Lights
with (docs/accuracy.md): it lives with the tests, the add-on never uses it."""

import numpy as np

from sh_lighting.core.equirect import check_pixels, texel_directions, texel_solid_angles
from sh_lighting.core.projection import project_equirect

EEVEE_SUN_THRESHOLD = 10.0  # Blender's default World.sun_threshold


def eevee_style_split(pixels, threshold=EEVEE_SUN_THRESHOLD):
    """An imitation of EEVEE's world sun extraction: (sun irradiance (3,), direction, coeffs).

    Each texel is clamped so that its largest channel is at most ``threshold`` (keeping its
    hue); what is clamped off goes into one sun whose irradiance is Σ (L − L_clamped) dΩ and
    whose direction is the mean texel direction weighted by |L − L_clamped| dΩ (the Euclidean
    length of the RGB excess); the clamped map becomes order-1 SH (l ≤ 1, 4 coefficients),
    which is what EEVEE keeps for world diffuse light. Returns (zeros, None, coeffs) when no
    texel exceeds the threshold.
    """
    a = check_pixels(pixels)
    height, width, _ = a.shape
    rgb = a[..., :3].astype(np.float64)
    peak = np.abs(rgb).max(axis=-1)
    scale = np.minimum(1.0, threshold / np.maximum(peak, 1e-300))
    clamped = rgb * scale[..., None]
    excess = (rgb - clamped) * texel_solid_angles(height, width)[:, None, None]
    coeffs = project_equirect(clamped, max_order=1)
    if not excess.any():
        return np.zeros(3), None, coeffs
    direction = np.linalg.norm(excess, axis=-1).ravel() @ texel_directions(height, width).reshape(
        -1, 3
    )
    return excess.sum(axis=(0, 1)), direction / np.linalg.norm(direction), coeffs
