"""A minimal 8-bit PNG encoder (RGB or RGBA, no interlacing), standard library only.

PNG (ISO/IEC 15948): signature, IHDR (width, height, bit depth 8, colour type 2 = RGB or
6 = RGBA), one zlib-compressed IDAT of scanlines each prefixed by filter byte 0, IEND; every
chunk is length, type, data, CRC-32 of type + data. Rows are written top to bottom.
"""

import struct
import zlib

import numpy as np

_COLOUR_TYPES = {3: 2, 4: 6}


def _chunk(kind, payload):
    body = kind + payload
    return struct.pack(">I", len(payload)) + body + struct.pack(">I", zlib.crc32(body))


def png_bytes(data, level=9):
    """The PNG file of ``data``: (H, W, 3 or 4) uint8, rows top to bottom."""
    a = np.ascontiguousarray(data)
    if a.dtype != np.uint8 or a.ndim != 3 or a.shape[2] not in _COLOUR_TYPES:
        raise ValueError(f"png_bytes needs (H, W, 3 or 4) uint8 data, got {a.dtype} {a.shape}")
    h, w, channels = a.shape
    raw = np.concatenate([np.zeros((h, 1), np.uint8), a.reshape(h, w * channels)], axis=1)
    header = struct.pack(">IIBBBBB", w, h, 8, _COLOUR_TYPES[channels], 0, 0, 0)
    return b"".join([
        b"\x89PNG\r\n\x1a\n",
        _chunk(b"IHDR", header),
        _chunk(b"IDAT", zlib.compress(raw.tobytes(), level)),
        _chunk(b"IEND", b""),
    ])
