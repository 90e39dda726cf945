"""The one check of lighting coefficients handed to sh_lighting by users, files and the core.

``check_coefficients`` takes rows of RGB (lists, tuples, numpy, ``mathutils`` vectors) and
returns a float64 (count, 3) copy, or raises a ValueError (or the ``error`` class given)
naming the first bad value by coefficient and channel ("L10 channel G") and what to pass:
not rows of 3, not real numbers (strings, booleans, None), NaN, infinity, or beyond float32
(±3.4e38, where Blender's float32 render would turn the lighting black).
"""

from numbers import Real

import numpy as np

from .sh import COEFFICIENT_NAMES, order_of

# Blender renders in float32: its largest value, and the smallest magnitude that rounds to
# infinity there (float32 max + half an ulp, 2^128 - 2^103); every magnitude below it is kept.
FLOAT32_MAX = float(np.finfo(np.float32).max)
FLOAT32_OVERFLOW = 2.0**128 - 2.0**103
CHANNELS = ("R", "G", "B")
_ORDER_HINT = "one [r, g, b] row per L_lm, in the order L00, L1-1, L10, L11, L2-2, ..."


def coefficient_name(index):
    """"L10" for index 2; "L3-3" and beyond for higher orders (index l(l+1)+m)."""
    if index < len(COEFFICIENT_NAMES):
        return COEFFICIENT_NAMES[index]
    band = int(np.sqrt(index))
    return f"L{band}{index - band * (band + 1)}"


def type_name(value):
    """How a message names the kind of ``value`` ("a string", "a boolean", "null"...)."""
    if value is None:
        return "None (null)"
    if isinstance(value, (bool, np.bool_)):
        return "a boolean"
    if isinstance(value, (str, bytes)):
        return "a string"
    if isinstance(value, dict):
        return "a dict"
    if isinstance(value, (list, tuple)):
        return "a list"
    if isinstance(value, (complex, np.complexfloating)):
        return "a complex number"
    return type(value).__name__


def real_number(value, what, error=ValueError, limit=FLOAT32_OVERFLOW):
    """``value`` as a float, or ``error`` if it is not a finite real number within ``limit``.

    Booleans, strings and complex numbers are refused (numpy's real scalars are accepted).
    """
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, Real):
        shown = type_name(value) if value is None else f"{type_name(value)} ({value!r})"
        raise error(f"{what} is {shown}, not a number: write a number")
    try:
        number = float(value)
    except OverflowError:  # an integer too large for a float
        number = float("inf") if value > 0 else float("-inf")
    if number != number or number in (float("inf"), float("-inf")):
        raise error(
            f"{what} is {number!r}: NaN and infinite values are not allowed; "
            "recompute the lighting or write a finite number"
        )
    if abs(number) >= limit:
        raise error(
            f"{what} is {number:.6g}, beyond the float32 range (±{FLOAT32_MAX:.4g}) in which Blender "
            "renders the lighting (it would render black): scale the lighting down (lower "
            "the exposure or the image's values)"
        )
    return number


def _rows(coeffs, error):
    """``coeffs`` as a list of rows, or ``error`` if it is not a list-like of rows."""
    if isinstance(coeffs, np.ndarray):
        if coeffs.dtype.kind in "iuf":
            return None  # fast path: checked as an array
        coeffs = coeffs.tolist()
    if isinstance(coeffs, (str, bytes, dict, set)) or not hasattr(coeffs, "__len__"):
        raise error(f"coefficients are {type_name(coeffs)}, not a list of rows: pass {_ORDER_HINT}")
    return list(coeffs)


def _check_array(c, error, limit):
    """Finite and within ``limit``: the first bad value named, or ``c``."""
    bad = ~np.isfinite(c) | (np.abs(c) >= limit)
    if bad.any():
        i, j = (int(k) for k in np.argwhere(bad)[0])
        real_number(float(c[i, j]), f"coefficient {coefficient_name(i)} channel {CHANNELS[j]}",
                    error, limit)
    return c


def check_coefficients(coeffs, count=9, error=ValueError, limit=FLOAT32_OVERFLOW):
    """A float64 ``(count, 3)`` copy of ``coeffs``, or ``error`` naming the problem.

    ``count``: the number of rows required (9: L00 ... L22), or None for any (order + 1)²
    (1, 4, 9, 16, ...). ``limit``: magnitudes from it on are refused (default: float32's).
    """
    rows = _rows(coeffs, error)
    if rows is None:
        c = np.array(coeffs, dtype=np.float64)
    else:
        c = np.empty((len(rows), 3))
        for i, row in enumerate(rows):
            name = coefficient_name(i)
            if isinstance(row, (str, bytes, dict, set)) or not hasattr(row, "__len__"):
                raise error(
                    f"coefficient {name} is {type_name(row)} ({row!r}), not [r, g, b]: "
                    f"pass {_ORDER_HINT}"
                )
            if len(row) != 3:
                raise error(
                    f"coefficient {name} has {len(row)} values, not 3: each row is [r, g, b]"
                )
            for j, value in enumerate(row):
                c[i, j] = real_number(value, f"coefficient {name} channel {CHANNELS[j]}",
                                      error, limit)
    if c.ndim != 2 or c.shape[1] != 3:
        raise error(
            f"coefficients must have shape ({count or '(order+1)²'}, 3), got shape {c.shape}: "
            f"pass {_ORDER_HINT}"
        )
    if count is None:
        try:
            order_of(c.shape[0])
        except ValueError as problem:
            raise error(str(problem)) from None
    elif c.shape[0] != count:
        raise error(
            f"SH lighting needs {count} RGB coefficients (shape ({count}, 3)), got shape "
            f"{c.shape}: pass {_ORDER_HINT}"
        )
    return _check_array(c, error, limit)
