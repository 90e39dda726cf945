"""A photometric file on disk (IES LM-63 or EULUMDAT) read into a candela table."""

from pathlib import Path

from .eulumdat import parse_ldt
from .ies import blender_reads_as_is, parse_ies
from .photometry import PhotometryError, to_ies_text


def read_photometry(path):
    """The :class:`CandelaTable` of an IES or EULUMDAT file."""
    return read_with_ies_text(path)[0]


def read_with_ies_text(path):
    """(table, IES text Blender's IES node reads with the table's axes) of an IES/LDT file.

    The file's own text where Blender reads it as the standard says (type C, planes not
    90..270), else the table written as LM-63-2002 (:func:`photometry.to_ies_text`).
    """
    path = Path(path)
    try:
        raw = path.read_bytes()
    except OSError as error:
        raise PhotometryError(f"{path.name}: cannot read the file ({error.strerror})") from None
    text = decode(raw)
    head = text.lstrip()[:64].upper()
    if head.startswith("IES") or "TILT=" in text.upper() or path.suffix.lower() == ".ies":
        table = parse_ies(text, path.name)
        return table, text if blender_reads_as_is(text) else to_ies_text(table, path.name)
    table = parse_ldt(text, path.name)
    return table, to_ies_text(table, path.name)


def decode(raw):
    """File bytes to text: UTF-8 (without a BOM) where valid, else Latin-1 (older files)."""
    if raw[:3] == b"\xef\xbb\xbf":
        raw = raw[3:]
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError:
        return raw.decode("latin-1")
