"""IES LM-63 photometric files (1986, 1991, 1995, 2002, 2019) to a :class:`CandelaTable`.

Layout after the keyword lines: ``TILT=NONE`` or ``TILT=INCLUDE`` (then the lamp-to-luminaire
geometry, the number of tilt angles n, n angles and n factors), then ten numbers (lamps,
lumens per lamp, candela multiplier, #vertical, #horizontal, photometric type, units,
width, length, height), three (ballast factor, ballast-lamp factor or "future use",
input watts), the vertical angles, the horizontal angles and the candela values, one
horizontal angle after another. Numbers are separated by blanks or commas, across lines.
Candela = value × multiplier × ballast factor × ballast-lamp factor (as Blender's reader).
Type C is read as is; type B (polar axis horizontal) is resampled onto a type C grid.
"""

import re

import numpy as np

from .photometry import PhotometryError, full_table, mirror_to_circle

_NUMBER = re.compile(r"[^\s,]+")
_FEET = 0.3048


class _Numbers:
    """The numbers after the TILT line, each with its line number, read in order."""

    def __init__(self, name, lines, first_line):
        self.name = name
        self.items = []
        for number, line in enumerate(lines, start=first_line):
            self.items.extend((token, number) for token in _NUMBER.findall(line))
        self.pos = 0
        self.last_line = first_line + max(len(lines) - 1, 0)

    def error(self, message, line=None):
        where = self.last_line if line is None else line
        return PhotometryError(f"{self.name} line {where}: {message}")

    def take(self, what, count=1, integer=False):
        if self.pos + count > len(self.items):
            found = len(self.items) - self.pos
            raise self.error(f"the file ends after {found} of {count} {what} "
                             "(truncated or a count is wrong)")
        out = []
        for token, line in self.items[self.pos:self.pos + count]:
            try:
                value = float(token)
            except ValueError:
                raise self.error(f"{what}: {token!r} is not a number", line) from None
            if not np.isfinite(value):
                raise self.error(f"{what}: {token!r} is not a finite number", line)
            if integer and value != int(value):
                raise self.error(f"{what}: {token!r} is not a whole number", line)
            out.append(value)
        self.pos += count
        return np.array(out)

    def line(self):
        """Line number of the next number (or of the end of the file)."""
        return self.items[self.pos][1] if self.pos < len(self.items) else self.last_line


def parse_ies(text, name="file.ies"):
    """The candela table of LM-63 ``text``; raises :class:`PhotometryError` (one line) if bad."""
    lines = text.replace("\r\n", "\n").replace("\r", "\n").rstrip().split("\n")
    if not text.strip():
        raise PhotometryError(f"{name} line 1: the file is empty")
    tilt_at = next((i for i, line in enumerate(lines) if line.strip().upper().startswith("TILT")),
                   None)
    if tilt_at is None:
        raise PhotometryError(f"{name} line {len(lines)}: no TILT= line (not an IES LM-63 file)")
    tilt = lines[tilt_at].split("=", 1)[-1].strip().upper()
    numbers = _Numbers(name, lines[tilt_at + 1:], tilt_at + 2)
    if tilt == "INCLUDE":
        numbers.take("lamp-to-luminaire geometry")
        at = numbers.line()
        n_tilt = numbers.take("number of tilt angles", integer=True)[0]
        if n_tilt < 0:
            raise numbers.error(f"number of tilt angles is {n_tilt:g} (negative)", at)
        numbers.take("tilt angles", int(n_tilt))
        numbers.take("tilt factors", int(n_tilt))
    elif tilt != "NONE":
        raise PhotometryError(f"{name} line {tilt_at + 1}: TILT={tilt.lower()} names another "
                              "file; only TILT=NONE and TILT=INCLUDE are read")

    at = numbers.line()
    head = numbers.take("the ten photometric numbers", 10)
    lamps, lumens, multiplier, n_v, n_h, kind, units, width, length, height = head
    for count, what in ((n_v, "vertical angles"), (n_h, "horizontal angles")):
        if count != int(count) or count < 1:
            raise numbers.error(f"number of {what} is {count:g} (must be a whole number >= 1)",
                                at)
    if kind not in (1, 2):
        label = "A (automotive)" if kind == 3 else f"{kind:g}"
        raise numbers.error(f"photometric type {label}: only types C (1) and B (2) are read", at)
    if units not in (1, 2):
        raise numbers.error(f"units type {units:g}: expected 1 (feet) or 2 (metres)", at)
    factors = numbers.take("ballast factor, ballast-lamp factor and input watts", 3)
    scale = multiplier * factors[0] * factors[1]
    n_v, n_h = int(n_v), int(n_h)
    at_v = numbers.line()
    vertical = numbers.take("vertical angles", n_v)
    at_h = numbers.line()
    horizontal = numbers.take("horizontal angles", n_h)
    at_c = numbers.line()
    values = numbers.take("candela values", n_v * n_h).reshape(n_h, n_v)
    if numbers.pos < len(numbers.items):
        token, line = numbers.items[numbers.pos]
        raise numbers.error(f"{len(numbers.items) - numbers.pos} numbers left over after the "
                            f"{n_v * n_h} candela values (from {token!r}): a count is wrong", line)
    _increasing(numbers, vertical, "vertical angles", at_v)
    _increasing(numbers, horizontal, "horizontal angles", at_h)
    if (values < 0).any():
        bad = float(values[values < 0][0])
        raise numbers.error(f"candela value {bad:g} is negative", at_c)
    if scale <= 0:
        raise numbers.error(f"candela multiplier x ballast factors is {scale:g} (must be > 0)", at)

    unit = _FEET if units == 1 else 1.0
    opening = (length * unit, width * unit, height * unit)
    rated = lamps * lumens if lumens > 0 and lamps > 0 else 0.0
    candela = values * scale
    try:
        if kind == 1:
            _range(numbers, vertical, 0.0, 180.0, "vertical angles (type C)", at_v)
            phi, cd = mirror_to_circle(horizontal, candela)
            return full_table(vertical, phi, cd, rated, opening, name)
        return _type_b(numbers, vertical, horizontal, candela, rated, opening, at_v, at_h)
    except ValueError as error:
        if isinstance(error, PhotometryError):
            raise
        raise numbers.error(f"horizontal angles: {error}", at_h) from None


def _increasing(numbers, angles, what, line):
    if len(angles) > 1 and (np.diff(angles) <= 0).any():
        i = int(np.argmax(np.diff(angles) <= 0))
        raise numbers.error(f"{what} must increase: {angles[i]:g} then {angles[i + 1]:g}", line)


def _range(numbers, angles, low, high, what, line):
    if angles[0] < low or angles[-1] > high:
        raise numbers.error(f"{what} run from {angles[0]:g} to {angles[-1]:g}, outside "
                            f"{low:g}..{high:g}", line)


def _type_b(numbers, vertical, horizontal, candela, rated, opening, at_v, at_h):
    """Type B (polar axis along the luminaire's width, −X here) resampled to a type C grid.

    A type B direction at horizontal angle H (about the polar axis) and vertical angle V
    (from the plane H sweeps) is d = (−sin V, −cos V sin H, −cos V cos H) in the light's axes
    (nadir at H = V = 0; +H toward −Y, +V toward −X, so C90 = V90 as for type C). Angles given
    on 0..90 only are mirrored (the standard's symmetric forms); then the table is sampled at
    the type C grid's directions, bilinear in (H, V).
    """
    _range(numbers, vertical, -90.0, 90.0, "vertical angles (type B)", at_v)
    _range(numbers, horizontal, -90.0, 90.0, "horizontal angles (type B)", at_h)
    h, v, cd = horizontal, vertical, candela  # cd[h, v]
    if h[0] == 0.0 and len(h) > 1:
        h = np.concatenate([-h[::-1][:-1], h])
        cd = np.concatenate([cd[::-1][:-1], cd], axis=0)
    if v[0] == 0.0 and len(v) > 1:
        v = np.concatenate([-v[::-1][:-1], v])
        cd = np.concatenate([cd[:, ::-1][:, :-1], cd], axis=1)
    theta = np.linspace(0.0, 180.0, 181)
    phi = np.linspace(0.0, 360.0, 361)
    t, p = np.meshgrid(np.radians(theta), np.radians(phi))
    d = np.stack([-np.sin(t) * np.sin(p), -np.sin(t) * np.cos(p), -np.cos(t)], axis=-1)
    v_dir = np.degrees(np.arcsin(np.clip(-d[..., 0], -1.0, 1.0)))
    h_dir = np.degrees(np.arctan2(-d[..., 1], -d[..., 2]))
    out = _bilinear(h, v, cd, h_dir, v_dir)
    return full_table(theta, phi, out, rated, opening, numbers.name)


def _bilinear(xs, ys, table, x, y):
    """table[i, j] at (xs[i], ys[j]) interpolated at (x, y); 0 outside the covered ranges."""
    inside = (x >= xs[0]) & (x <= xs[-1]) & (y >= ys[0]) & (y <= ys[-1])
    if len(xs) == 1:
        xs, table = np.array([xs[0] - 1e-9, xs[0] + 1e-9]), np.concatenate([table, table])
        inside &= np.isclose(x, xs[0], atol=1e-6)
    if len(ys) == 1:
        ys, table = np.array([ys[0] - 1e-9, ys[0] + 1e-9]), np.concatenate([table, table], 1)
        inside &= np.isclose(y, ys[0], atol=1e-6)
    i = np.clip(np.searchsorted(xs, x, side="right") - 1, 0, len(xs) - 2)
    j = np.clip(np.searchsorted(ys, y, side="right") - 1, 0, len(ys) - 2)
    wx = np.clip((x - xs[i]) / (xs[i + 1] - xs[i]), 0, 1)
    wy = np.clip((y - ys[j]) / (ys[j + 1] - ys[j]), 0, 1)
    value = (table[i, j] * (1 - wx) * (1 - wy) + table[i + 1, j] * wx * (1 - wy)
             + table[i, j + 1] * (1 - wx) * wy + table[i + 1, j + 1] * wx * wy)
    return np.where(inside, value, 0.0)


def blender_reads_as_is(text):
    """Whether Blender's IES node reads ``text`` with the same axes as :func:`parse_ies`.

    Type C files whose planes are not 90..270 (Blender turns those by 90°); others are
    converted (:func:`sh_lighting.formats.photometry.to_ies_text`).
    """
    lines = text.replace("\r\n", "\n").replace("\r", "\n").split("\n")
    tilt_at = next(i for i, line in enumerate(lines) if line.strip().upper().startswith("TILT"))
    numbers = _Numbers("", lines[tilt_at + 1:], tilt_at + 2)
    if lines[tilt_at].split("=", 1)[-1].strip().upper() == "INCLUDE":
        numbers.take("", 1)
        n_tilt = int(numbers.take("", 1)[0])
        numbers.take("", 2 * n_tilt)
    head = numbers.take("", 13)
    if head[5] != 1:
        return False
    numbers.take("", int(head[3]))
    horizontal = numbers.take("", int(head[4]))
    return not (len(horizontal) > 1 and horizontal[0] == 90.0)
