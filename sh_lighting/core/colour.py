"""Colour-space decoding the Blender layer needs before projecting 8-bit images.

An 8-bit image in the "sRGB" colour space stores the sRGB-encoded value; ``Image.pixels`` gives
it as byte / 255, and Cycles renders it decoded with the exact piecewise sRGB transfer function
(IEC 61966-2-1), which is what ``srgb_to_linear`` computes (checked against Cycles renders in
tests/blender/test_world.py).
"""

import numpy as np


def srgb_to_linear(values):
    """The IEC 61966-2-1 sRGB decoding of ``values`` (any shape), as float64.

    v / 12.92 for v <= 0.04045, ((v + 0.055) / 1.055) ** 2.4 above; negative values are
    mirrored (odd extension) so the function is monotonic on the whole real line.
    """
    v = np.asarray(values, dtype=np.float64)
    a = np.abs(v)
    out = np.where(a <= 0.04045, a / 12.92, ((a + 0.055) / 1.055) ** 2.4)
    return np.copysign(out, v)
