"""Write 8-bit RGB PNG pictures (dev tools only: demo and benchmark pictures)."""

import numpy as np

from sh_lighting.formats.png import png_bytes


def write_png(path, rgb):
    """Write an (H, W, 3) array of sRGB-encoded values in [0, 1], rows top to bottom.

    Encode linear values first with ``sh_lighting.core.preview.linear_to_srgb``.
    """
    data = (np.clip(rgb, 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8)
    with open(path, "wb") as f:
        f.write(png_bytes(data))
