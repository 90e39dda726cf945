"""A luminaire's near field: its luminous opening split into cells, one light source per cell.

A goniometric (far-field) distribution I(ω) is measured from far away: it is the luminaire
seen as a point. Closer than about five times the luminous opening's size a surface sees the
opening's extent (the "five-times rule" of photometry; Granier, Goesele, Heidrich and Seidel
2003, §3, sample the near field over a plane of cells, one shadowed projector per cell).
Here the opening, a rectangle of ``length`` along the light's local Y (the C0–C180 axis,
``formats.photometry``) by ``width`` along its local X, is split into n_y × n_x equal cells,
each the far-field distribution I(ω) / (n_y n_x) at its centre: every side is cut until its
cells are smaller than a fifth of the distance to the lit surface,

    n = clamp(⌈5 side / distance⌉, 1, ``max_per_side``),

so that each cell is in its own far field, up to the cap. Where the whole opening already is
(distance ≥ 5 × its largest side) there is one cell, the luminaire's centre: the far field.
A circular opening (negative sides, the IES convention) is cut as its bounding square. The
approximation is the distribution's own: every point of the opening emits the same I(ω), as a
dense grid of the far-field source does (what the benchmark integrates as its reference).
"""

import math
from dataclasses import dataclass

import numpy as np

NEAR_FIELD_FACTOR = 5.0  # closer than 5 × the opening's size: the near field
MAX_CELLS_PER_SIDE = 4  # 16 cells at most: each cell repeats every EEVEE lamp
MAX_HALF_SIZE = 0.25  # metres: the largest soft shadow radius a cell's lamps get


@dataclass(frozen=True)
class Cells:
    """The opening's cells: ``counts`` (n_y along the length, n_x along the width), their
    ``centres`` (n, 3) in the light's local axes (z = 0) and ``half_size`` (metres: a lamp's
    soft shadow radius, half the cell's larger side, at most ``MAX_HALF_SIZE``)."""

    counts: tuple
    centres: np.ndarray
    half_size: float

    @property
    def count(self):
        return len(self.centres)

    @property
    def near(self):
        return self.count > 1


def is_near(opening_m, distance, factor=NEAR_FIELD_FACTOR):
    """Whether a surface at ``distance`` metres is in the opening's near field."""
    return distance is not None and distance > 0 and distance < factor * _size(opening_m)


def near_field_cells(opening_m, distance, factor=NEAR_FIELD_FACTOR,
                     max_per_side=MAX_CELLS_PER_SIDE):
    """The cells for lit surfaces ``distance`` metres away (0 or None: the far field, one
    cell); ``opening_m`` is (length, width, height) as ``CandelaTable.opening_m``."""
    length, width = _sides(opening_m)
    if is_near(opening_m, distance, factor):
        n_y = _count(length, distance, factor, max_per_side)
        n_x = _count(width, distance, factor, max_per_side)
    else:
        n_y = n_x = 1
    y = (np.arange(n_y) + 0.5) / n_y * length - 0.5 * length
    x = (np.arange(n_x) + 0.5) / n_x * width - 0.5 * width
    yy, xx = np.meshgrid(y, x, indexing="ij")
    centres = np.stack([xx.ravel(), yy.ravel(), np.zeros(n_y * n_x)], axis=-1)
    half = 0.5 * max(length / n_y, width / n_x)
    return Cells((n_y, n_x), centres, float(min(half, MAX_HALF_SIZE)))


def _sides(opening_m):
    length, width = (abs(float(v)) for v in opening_m[:2])
    if opening_m[0] < 0 or opening_m[1] < 0:  # a circle of that diameter: its square
        length = width = max(length, width)
    return length, width


def _size(opening_m):
    return max(_sides(opening_m))


def _count(side, distance, factor, max_per_side):
    if side <= 0:
        return 1
    return int(min(max(math.ceil(factor * side / distance - 1e-9), 1), max_per_side))
