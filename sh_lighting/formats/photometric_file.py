"""A photometric file on disk (IES LM-63 or EULUMDAT) read into a candela table."""

from pathlib import Path

from .eulumdat import parse_ldt
from .ies import parse_ies
from .photometry import PhotometryError


def read_photometry(path):
    """Read an IES (LM-63) or EULUMDAT file, telling them apart by content and extension."""
    path = Path(path)
    try:
        raw = path.read_bytes()
    except OSError as error:
        raise PhotometryError(f"{path.name}: cannot read the file ({error.strerror})") from None
    text = decode(raw)
    head = text.lstrip()[:64].upper()
    if head.startswith("IES") or "TILT=" in text.upper() or path.suffix.lower() == ".ies":
        return parse_ies(text, path.name)
    return parse_ldt(text, path.name)


def decode(raw):
    """File bytes to text: UTF-8 (without a BOM) where valid, else Latin-1 (older files)."""
    if raw[:3] == b"\xef\xbb\xbf":
        raw = raw[3:]
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError:
        return raw.decode("latin-1")
