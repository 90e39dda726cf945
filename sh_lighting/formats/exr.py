"""An OpenEXR file's structure checked before Blender reads it (no bpy, no numpy).

bpy 5.0.1's EXR reader crashes (SIGSEGV) on a file whose chunks are cut short. ``check_exr``
reads the header (magic 20000630, version flags 0x200 tiled, 0x800 deep, 0x1000 multi-part,
attributes up to an empty name), the chunk offset table and each chunk's header (scanline: y
and size; tile: 4 coordinates and size), and raises a one-line ValueError when something lies
outside the file. Single-part scanline and one-level tiled files are checked in full; of
multi-part, deep and mip-mapped files only the header.
"""

import os
import struct

MAGIC = b"\x76\x2f\x31\x01"
TILED, DEEP, MULTIPART = 0x200, 0x800, 0x1000
# compression id -> scanlines per chunk (NONE, RLE, ZIPS: 1; ZIP, PXR24: 16; PIZ, B44, B44A,
# DWAA: 32; DWAB: 256)
LINES_PER_CHUNK = {0: 1, 1: 1, 2: 1, 3: 16, 4: 32, 5: 16, 6: 32, 7: 32, 8: 32, 9: 256}


def is_exr(path):
    """Whether the file at ``path`` starts with the OpenEXR magic number."""
    try:
        with open(path, "rb") as stream:
            return stream.read(4) == MAGIC
    except OSError:
        return False


def check_exr(path):
    """Nothing if the EXR file at ``path`` holds every chunk its header announces, else a
    ValueError saying what is wrong and what to do."""
    try:
        _check(path)
    except _Damaged as error:
        raise ValueError(
            f"EXR file '{os.fspath(path)}' is damaged ({error}): it is probably truncated "
            "(an interrupted copy or download); copy it again"
        ) from None


class _Damaged(Exception):
    pass


def _read(stream, size, what):
    data = stream.read(size)
    if len(data) != size:
        raise _Damaged(f"the file ends inside {what}")
    return data


def _text(stream, what):
    out = bytearray()
    while True:
        byte = _read(stream, 1, what)
        if byte == b"\0":
            return out.decode("latin-1")
        out += byte
        if len(out) > 255:
            raise _Damaged(f"{what} is not a name")


def _header(stream, file_size):
    """{attribute name: (type, value bytes)} of one part's header."""
    attributes = {}
    while True:
        name = _text(stream, "the header")
        if not name:
            return attributes
        kind = _text(stream, f"attribute {name}")
        (size,) = struct.unpack("<i", _read(stream, 4, f"attribute {name}"))
        if size < 0 or stream.tell() + size > file_size:
            raise _Damaged(f"attribute {name} runs past the end of the file")
        attributes[name] = (kind, _read(stream, size, f"attribute {name}"))


def _check(path):
    file_size = os.path.getsize(path)
    with open(path, "rb") as stream:
        if _read(stream, 4, "the magic number") != MAGIC:
            raise _Damaged("no OpenEXR magic number")
        (version,) = struct.unpack("<I", _read(stream, 4, "the version"))
        header = _header(stream, file_size)
        if version & (MULTIPART | DEEP):
            return  # only the first header is checked
        for needed in ("dataWindow", "compression", "channels"):
            if needed not in header:
                raise _Damaged(f"the header has no {needed}")
        xmin, ymin, xmax, ymax = struct.unpack("<4i", header["dataWindow"][1][:16])
        width, height = xmax - xmin + 1, ymax - ymin + 1
        if width <= 0 or height <= 0:
            raise _Damaged(f"its data window is {width}x{height}")
        compression = header["compression"][1][0]
        if "chunkCount" in header:
            (chunks,) = struct.unpack("<i", header["chunkCount"][1][:4])
        elif version & TILED:
            tile_x, tile_y, mode = struct.unpack("<IIB", header["tiles"][1][:9])
            if mode & 0x0F or tile_x == 0 or tile_y == 0:
                return  # mip/rip levels: not checked
            chunks = -(-width // tile_x) * -(-height // tile_y)
        elif compression in LINES_PER_CHUNK:
            chunks = -(-height // LINES_PER_CHUNK[compression])
        else:
            return  # a compression this check does not know
        prefix = 20 if version & TILED else 8
        table_end = stream.tell() + 8 * chunks
        if chunks < 0 or table_end > file_size:
            raise _Damaged(f"the file ends inside its table of {chunks} chunk offsets")
        offsets = struct.unpack(f"<{chunks}Q", _read(stream, 8 * chunks, "the offset table"))
        for index, offset in enumerate(offsets):
            if not table_end <= offset <= file_size - prefix:
                raise _Damaged(f"chunk {index + 1} of {chunks} starts past the end of the file")
            stream.seek(offset + prefix - 4)
            (size,) = struct.unpack("<i", _read(stream, 4, f"chunk {index + 1}"))
            if size < 0 or offset + prefix + size > file_size:
                raise _Damaged(f"chunk {index + 1} of {chunks} runs past the end of the file "
                               f"({file_size} bytes)")
