"""EULUMDAT (.ldt) photometric files to a :class:`CandelaTable`.

Lines 1–12 identify the luminaire (line 3: symmetry indicator Isym 0–4, 4: Mc C-planes, 5: their
spacing, 6: Ng γ angles), 13–21 give its size in mm (16–17: luminous area length and width,
width 0 for a circle; 18–21: its heights at C0, C90, C180, C270), 22–25 factors (24: conversion
factor for the intensities), 26 the number of lamp sets, six lines per set (lamps, type, total
flux in lm, colour, CRI, watts), ten direct ratios, then the Mc C angles, the Ng γ angles and
the intensities in cd/klm, one stored C-plane after another. The stored planes follow Isym:
0 all Mc, 1 one (rotational), 2 C0..C180, 3 C270..C90 through C0, 4 C0..C90.
Candela = value × (set 1's flux / 1000) × conversion factor. Decimal commas are accepted.
"""

import re

import numpy as np

from .photometry import PhotometryError, full_table, mirror_to_circle

_TOKEN = re.compile(r"[^\s;]+")


class _Lines:
    def __init__(self, name, text):
        self.name = name
        self.lines = text.replace("\r\n", "\n").replace("\r", "\n").split("\n")
        while self.lines and not self.lines[-1].strip():
            self.lines.pop()
        self.pos = 0

    def error(self, message, line=None):
        return PhotometryError(f"{self.name} line {self.pos if line is None else line}: {message}")

    def text(self, what):
        if self.pos >= len(self.lines):
            raise self.error(f"the file ends before {what} (truncated)", len(self.lines))
        self.pos += 1
        return self.lines[self.pos - 1].strip()

    def number(self, what, integer=False):
        token = self.text(what)
        return _value(self, token, what, self.pos, integer)

    def numbers(self, what, count):
        """``count`` numbers from the following lines (one or more a line)."""
        out = []
        start = self.pos + 1
        while len(out) < count:
            if self.pos >= len(self.lines):
                raise self.error(f"the file ends after {len(out)} of {count} {what} (truncated "
                                 "or a count is wrong)", len(self.lines))
            self.pos += 1
            for token in _TOKEN.findall(self.lines[self.pos - 1]):
                out.append(_value(self, token, what, self.pos))
        if len(out) > count:
            raise self.error(f"{len(out) - count} more numbers than the {count} {what} "
                             "expected on this line")
        return np.array(out), start


def _value(lines, token, what, line, integer=False):
    try:
        value = float(token.replace(",", "."))
    except ValueError:
        raise lines.error(f"{what}: {token!r} is not a number", line) from None
    if not np.isfinite(value):
        raise lines.error(f"{what}: {token!r} is not a finite number", line)
    if integer and value != int(value):
        raise lines.error(f"{what}: {token!r} is not a whole number", line)
    return value


def stored_planes(isym, mc):
    """Indices (into the file's Mc C angles) of the planes an Isym file stores, in order."""
    if isym == 0:
        return list(range(mc))
    if isym == 1:
        return [0]
    if isym == 2:
        return list(range(mc // 2 + 1))
    if isym == 3:
        return [(3 * mc // 4 + k) % mc for k in range(mc // 2 + 1)]
    return list(range(mc // 4 + 1))


def parse_ldt(text, name="file.ldt"):
    """The candela table of EULUMDAT ``text``; raises :class:`PhotometryError` (one line)."""
    if not text.strip():
        raise PhotometryError(f"{name} line 1: the file is empty")
    f = _Lines(name, text)
    f.text("the company")
    f.number("the luminaire type Ityp", integer=True)
    isym = f.number("the symmetry indicator Isym", integer=True)
    if isym not in (0, 1, 2, 3, 4):
        raise f.error(f"symmetry indicator Isym is {isym:g}: expected 0 to 4")
    mc = f.number("the number of C-planes Mc", integer=True)
    if mc < 1:
        raise f.error(f"number of C-planes Mc is {mc:g} (must be >= 1)")
    if isym in (3, 4) and mc % 4 or isym == 2 and mc % 2:
        raise f.error(f"Mc = {mc:g} C-planes cannot be split as symmetry {isym:g} needs")
    f.number("the C-plane spacing Dc")
    ng = f.number("the number of gamma angles Ng", integer=True)
    if ng < 1:
        raise f.error(f"number of gamma angles Ng is {ng:g} (must be >= 1)")
    f.number("the gamma spacing Dg")
    for what in ("the report number", "the luminaire name", "the luminaire number",
                 "the file name", "the date / user"):
        f.text(what)
    f.number("the luminaire length")
    f.number("the luminaire width")
    f.number("the luminaire height")
    area_length = f.number("the luminous area's length or diameter")
    area_width = f.number("the luminous area's width")
    heights = [f.number(f"the luminous area's height at C{c}") for c in (0, 90, 180, 270)]
    f.number("the downward flux fraction")
    f.number("the light output ratio")
    conversion = f.number("the intensity conversion factor")
    f.number("the tilt")
    n_sets = f.number("the number of lamp sets", integer=True)
    if n_sets < 1:
        raise f.error(f"number of lamp sets is {n_sets:g} (must be >= 1)")
    fluxes = []
    for k in range(int(n_sets)):
        f.number(f"set {k + 1}'s number of lamps", integer=True)
        f.text(f"set {k + 1}'s lamp type")
        fluxes.append((f.number(f"set {k + 1}'s total flux"), f.pos))
        f.text(f"set {k + 1}'s colour")
        f.text(f"set {k + 1}'s colour rendering")
        f.number(f"set {k + 1}'s wattage")
    flux, flux_line = fluxes[0]
    if flux <= 0 or conversion <= 0:
        bad, line = (flux, flux_line) if flux <= 0 else (conversion, 24)
        raise f.error(f"{'lamp flux' if flux <= 0 else 'conversion factor'} is {bad:g} "
                      "(must be > 0 to turn cd/klm into candela)", line)
    f.numbers("direct ratios", 10)
    mc, ng = int(mc), int(ng)
    c_angles, c_line = f.numbers("C angles", mc)
    gamma, g_line = f.numbers("gamma angles", ng)
    planes = stored_planes(int(isym), mc)
    values, v_line = f.numbers("intensities", len(planes) * ng)
    if f.pos < len(f.lines):
        raise f.error(f"text after the {len(planes) * ng} intensities: "
                      f"{f.lines[f.pos].strip()[:20]!r} (a count is wrong)", f.pos + 1)
    for angles, what, line in ((c_angles, "C angles", c_line), (gamma, "gamma angles", g_line)):
        if len(angles) > 1 and (np.diff(angles) <= 0).any():
            raise f.error(f"{what} must increase", line)
    if gamma[0] < 0 or gamma[-1] > 180:
        raise f.error(f"gamma angles run from {gamma[0]:g} to {gamma[-1]:g}, outside 0..180",
                      g_line)
    if (values < 0).any():
        raise f.error(f"intensity {float(values[values < 0][0]):g} is negative", v_line)

    candela = values.reshape(len(planes), ng) * (flux / 1000.0) * conversion
    phi = c_angles[planes]
    if isym == 3:  # C270..C90 through C0, mirrored to the standard's 90..270 half
        phi = (180.0 - phi) % 360.0
        order = np.argsort(phi)
        phi, candela = phi[order], candela[order]
    try:
        phi, candela = mirror_to_circle(phi, candela)
    except ValueError as error:
        raise f.error(f"C angles: {error}", c_line) from None
    opening = (area_length / 1000.0, area_width / 1000.0, max(heights) / 1000.0)
    if area_width == 0:
        opening = (-area_length / 1000.0, -area_length / 1000.0, opening[2])
    return full_table(gamma, phi, candela, flux, opening, name)
