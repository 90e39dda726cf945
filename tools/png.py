"""A minimal 8-bit RGB PNG writer (dev tools only: demo and benchmark pictures)."""

import struct
import zlib

import numpy as np


def write_png(path, rgb):
    """Write an (H, W, 3) array of sRGB-encoded values in [0, 1], rows top to bottom.

    Encode linear values first with ``sh_lighting.core.preview.linear_to_srgb``.
    """
    data = (np.clip(rgb, 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8)
    h, w, _ = data.shape
    raw = b"".join(b"\x00" + data[row].tobytes() for row in range(h))

    def chunk(kind, payload):
        body = kind + payload
        return struct.pack(">I", len(payload)) + body + struct.pack(">I", zlib.crc32(body))

    header = struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header))
        f.write(chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))
