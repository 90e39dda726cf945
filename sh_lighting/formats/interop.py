"""Exporters (and importers) of the 9 lighting coefficients for three.js, glTF
EXT_lights_image_based (Babylon.js) and Filament.

Ours are raw radiance L_lm (paper's real basis, no Condon-Shortley phase, Blender axes, z up);
a target differs in axes (glTF's y-up frame: (x, y, z)_blender -> (x, z, -y)), in meaning
(radiance L_lm, irradiance E_lm = Â_l L_lm, or Filament's pre-scaled Â_l K_lm L_lm / π) and in
basis signs ((-1)^|m| for Babylon). In every target a white Lambertian surface shows E(n)/π
(eq. 13): the tests check that, target by target. The ``from_*`` functions invert the
exporters. Each client's conventions, as read in its source and run: docs/interop.md.
"""

import hashlib
import re
from math import pi

import numpy as np

from ..core.frames import BLENDER_TO_Y_UP, change_frame
from ..core.irradiance import check_coefficients
from ..core.sh import (
    COEFFICIENT_NAMES,
    Y00,
    Y1,
    Y2_XY,
    Y20,
    Y22,
    band_of_each_coefficient,
    lambert_band_factors,
)

# K of each Y_lm written as K · polynomial (the paper's table): Y00, Y1-1 = K y, ..., Y22.
POLYNOMIAL_CONSTANTS = np.array([Y00, Y1, Y1, Y1, Y2_XY, Y2_XY, Y20, Y2_XY, Y22])

# (−1)^|m|: the Condon-Shortley sign of each coefficient (Filament's and Babylon's basis).
CONDON_SHORTLEY_SIGNS = np.array([1.0, -1.0, 1.0, -1.0, 1.0, -1.0, 1.0, -1.0, 1.0])

# Â_l of each of the 9 coefficients (π, 2π/3 ×3, π/4 ×5).
LAMBERT_FACTORS = lambert_band_factors(2)[band_of_each_coefficient(2)]

# (x, y, z)_cmgen = (y, z, x)_blender: cmgen's default (mirrored) frame for an equirect input.
BLENDER_TO_CMGEN = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])

FILAMENT_FRAMES = {"gltf": BLENDER_TO_Y_UP, "cmgen": BLENDER_TO_CMGEN}

# Babylon.js lookup axes of a right-handed scene (glTF's frame with z negated, see 2. above):
# (x, y, z)_lookup = (x, z, y)_blender. A reflection (det −1): applied to coefficients as the
# rotation into the glTF frame followed by the sign of each coefficient under z → −z.
BLENDER_TO_BABYLON_LOOKUP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]])
# Parity of each y-up coefficient under z → −z: L10 (z), L2-1 (yz), L21 (xz) change sign.
Z_MIRROR_SIGNS = np.array([1.0, 1.0, -1.0, 1.0, 1.0, -1.0, 1.0, -1.0, 1.0])


def _check_nine(coeffs):
    c, order = check_coefficients(coeffs)
    if order != 2:
        raise ValueError(
            f"other tools take exactly 9 RGB coefficients (order 2), got {c.shape[0]}: "
            "pass the L00 ... L22 rows only"
        )
    return c


def _numbers(values, shape, what):
    try:
        a = np.array(values, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise ValueError(f"{what} must be numbers: {error}") from None
    if a.size != int(np.prod(shape)):
        raise ValueError(f"{what} must hold {int(np.prod(shape))} numbers, got {a.size}")
    a = a.reshape(shape)
    if not np.isfinite(a).all():
        raise ValueError(f"{what} contain NaN or Inf")
    return a


def _to_blender(y_up, frame_matrix):
    return change_frame(y_up, np.asarray(frame_matrix).T)


# --- three.js -----------------------------------------------------------------------------


def to_threejs_sh(coeffs):
    """three.js ``SphericalHarmonics3.toArray()``: 27 floats, radiance L_lm, y-up glTF frame."""
    y_up = change_frame(_check_nine(coeffs), BLENDER_TO_Y_UP)
    return [float(v) for v in y_up.reshape(-1)]


def to_threejs_json(coeffs, name="", user_data=None):
    """A three.js object JSON (``ObjectLoader`` format 4) holding one ``LightProbe``.

    ``new ObjectLoader().parse(json)`` gives the LightProbe; so does
    ``new LightProbe(new SphericalHarmonics3().fromArray(json.object.sh),
    json.object.intensity)``. The uuid is derived from the coefficients (same lighting, same
    file).
    """
    sh = to_threejs_sh(coeffs)
    digest = hashlib.sha256(np.asarray(sh).tobytes()).hexdigest()
    uuid = f"{digest[:8]}-{digest[8:12]}-4{digest[13:16]}-8{digest[17:20]}-{digest[20:32]}"
    return {
        "metadata": {"version": 4.6, "type": "Object", "generator": "sh_lighting"},
        "object": {
            "uuid": uuid,
            "type": "LightProbe",
            "name": name,
            "layers": 1,
            "matrix": [float(v) for v in np.eye(4).reshape(-1)],
            "up": [0.0, 1.0, 0.0],
            "intensity": 1.0,
            "sh": sh,
            "userData": dict(user_data or {}),
        },
    }


def from_threejs_sh(values):
    """Inverse of :func:`to_threejs_sh`: 27 floats (coefficient-major RGB) → (9, 3) Blender."""
    return _to_blender(_numbers(values, (9, 3), "three.js SH values"), BLENDER_TO_Y_UP)


# --- glTF EXT_lights_image_based ----------------------------------------------------------


def to_babylon_lookup(coeffs):
    """(9, 3) L_lm of the lighting in Babylon's lookup axes (x, z, y)_blender (see 2. above)."""
    return change_frame(_check_nine(coeffs), BLENDER_TO_Y_UP) * Z_MIRROR_SIGNS[:, None]


_GLTF_FACTORS = LAMBERT_FACTORS * CONDON_SHORTLEY_SIGNS


def to_gltf_irradiance_coefficients(coeffs):
    """EXT_lights_image_based ``irradianceCoefficients``: 9×3 list, (−1)^|m| Â_l L_lm in
    Babylon's lookup axes, so that its right-handed scene shows E(n)/π (module docstring)."""
    e = to_babylon_lookup(coeffs) * _GLTF_FACTORS[:, None]
    return [[float(v) for v in row] for row in e]


def from_gltf_irradiance_coefficients(values):
    """Inverse of :func:`to_gltf_irradiance_coefficients` → (9, 3) radiance L_lm, Blender."""
    e = _numbers(values, (9, 3), "irradianceCoefficients")
    y_up = e / _GLTF_FACTORS[:, None] * Z_MIRROR_SIGNS[:, None]
    return _to_blender(y_up, BLENDER_TO_Y_UP)


# --- Filament -----------------------------------------------------------------------------


def _filament_frame(frame):
    try:
        return FILAMENT_FRAMES[frame]
    except KeyError:
        raise ValueError(
            f"unknown Filament frame {frame!r}: use 'gltf' (matches a glTF export) or 'cmgen' "
            "(matches cmgen's own output for the same equirect image)"
        ) from None


def filament_prescaled(coeffs, frame="cmgen"):
    """Shader-ready values (9, 3): Â_l K_lm L_lm / π in the chosen y-up frame. Not L_lm."""
    y_up = change_frame(_check_nine(coeffs), _filament_frame(frame))
    return y_up * (LAMBERT_FACTORS * POLYNOMIAL_CONSTANTS / pi)[:, None]


def coefficients_from_filament_prescaled(values, frame="cmgen"):
    """Inverse of :func:`filament_prescaled` → (9, 3) radiance L_lm in Blender axes."""
    p = _numbers(values, (9, 3), "Filament SH values")
    y_up = p / (LAMBERT_FACTORS * POLYNOMIAL_CONSTANTS / pi)[:, None]
    return _to_blender(y_up, _filament_frame(frame))


def to_filament_sh_txt(coeffs, frame="cmgen"):
    """The text of a cmgen ``sh.txt`` (9 lines, pre-scaled irradiance, no windowing)."""
    lines = [
        f"({float(r)!r}, {float(g)!r}, {float(b)!r}); // {name}, irradiance, pre-scaled base"
        for name, (r, g, b) in zip(COEFFICIENT_NAMES, filament_prescaled(coeffs, frame))
    ]
    return "\n".join(lines) + "\n"


_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
_SH_LINE = re.compile(
    rf"^\s*\(\s*({_NUMBER})\s*,\s*({_NUMBER})\s*,\s*({_NUMBER})\s*\)\s*;?\s*(?://.*)?$"
)


def from_filament_sh_txt(text, frame="cmgen"):
    """(9, 3) radiance L_lm in Blender axes from cmgen ``sh.txt`` text (3 bands, pre-scaled).

    Blank lines are skipped; anything else must be ``(r, g, b);`` with an optional ``//``
    comment. ValueError naming the line otherwise. Assumes the file was written with
    ``--sh-shader`` (pre-scaled irradiance), as ``cmgen --deploy`` does.
    """
    rows = []
    for number, line in enumerate(text.splitlines(), start=1):
        if not line.strip():
            continue
        match = _SH_LINE.match(line)
        if match is None:
            raise ValueError(
                f"sh.txt line {number} is not '(r, g, b); // comment': {line.strip()[:60]!r}"
            )
        rows.append([float(v) for v in match.groups()])
    if len(rows) != 9:
        raise ValueError(
            f"sh.txt holds {len(rows)} coefficient lines, expected 9 (3 bands): write it with "
            "cmgen --sh-shader (or --deploy), which uses 3 bands"
        )
    return coefficients_from_filament_prescaled(rows, frame)
