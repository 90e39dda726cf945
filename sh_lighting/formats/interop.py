"""Exporters (and importers) of the 9 lighting coefficients for other tools.

Our coefficients are raw radiance L_lm in the paper's real SH basis (no Condon-Shortley phase),
Blender world axes (z up). Each target differs in up to three ways: its axes, what the numbers
mean (radiance, irradiance, or values pre-scaled for a shader) and the basis signs. A white
Lambertian surface lit by the 9-term lighting shows E(n)/π in every target (E from eq. 13 of
the paper, ``irradiance.irradiance``), which is what the tests check, target by target.

Axes: all three targets use a right-handed y-up frame. Unless said otherwise it is the glTF
frame, into which Blender's glTF exporter maps (x, y, z)_blender → (x, z, −y)_gltf
(``frames.BLENDER_TO_Y_UP``), so lighting exported here lines up with a glTF export of the
same Blender scene.

1. **three.js** ``SphericalHarmonics3`` / ``LightProbe`` (``to_threejs_sh``). 27 floats,
   coefficient-major: [L00 r, L00 g, L00 b, L1-1 r, ...] (``toArray``/``fromArray``; a
   ``LightProbe.toJSON()`` object stores the same array as ``sh``, next to ``intensity``).
   Values are radiance L_lm in the paper's basis, no sign flips, glTF frame (three.js world
   axes are right-handed, y up; its GLTFLoader does not change axes). The file
   (``to_threejs_json``) is a three.js object JSON that ``ObjectLoader().parse`` reads
   (``LightProbe.fromJSON`` is gone since r182). Checked in the three.js source and run in
   node (``tests/interop``): ``getBasisAt`` uses the paper's table (0.282095; 0.488603 y,
   z, x; 1.092548 xy, yz; 0.315392 (3z² − 1); 1.092548 xz; 0.546274 (x² − y²));
   ``getIrradianceAt`` and the shader
   ``shGetIrradianceAt`` evaluate eq. 13 with the paper's rounded constants (0.886227,
   2·0.511664, 2·0.429043, 0.743125, 0.247708) at the world-space normal, and the indirect
   diffuse term is ``irradiance * BRDF_Lambert(diffuseColor)`` = E · albedo/π.

2. **glTF EXT_lights_image_based** ``irradianceCoefficients``
   (``to_gltf_irradiance_coefficients``; the whole environment with its specular cube is
   ``gltf_environment``). A 9×3 array, rows L00, L1-1, L10, L11, L2-2, L2-1, L20, L21, L22
   (the order the Babylon.js loader reads). The extension text says only "spherical harmonic
   coefficients for irradiance up to l=2": no scaling, signs or frame. Its main reader,
   Babylon.js (``EXT_lights_image_based.ts``, ``sphericalPolynomial.ts``, run in node by
   ``tests/interop``), multiplies by the light's ``intensity``, divides by π, and in its
   default shading path (``useSphericalHarmonics = true``) multiplies by its basis constants
   √(1/4π), −√(3/4π), √(3/4π), −√(3/4π), √(15/4π), −√(15/4π), √(5/16π), −√(15/4π), √(15/16π)
   (a Condon-Shortley-signed basis) and sums the plain polynomials at the *lookup vector*:
   the world normal times the light's rotation, with z negated in a right-handed scene
   (``REFLECTIONMAP_OPPOSITEZ``: Babylon's cube textures live in its native left-handed
   axes). So in a right-handed Babylon scene, glTF's own frame, the lookup vector of a glTF
   normal (x, y, z) is (x, y, −z) = (x, z, y)_blender (``BLENDER_TO_BABYLON_LOOKUP``, a
   reflection), and a Lambertian surface shows E(n)/π exactly when the array holds
   irradiance E_lm = Â_l L_lm of the lighting in those lookup axes, with the sign (−1)^|m|
   (L1-1, L11, L2-1, L21 negated). **We write that.** In Babylon's default left-handed scene
   the loader mirrors the geometry (root node: scale z by −1, turn 180° about y) but not the
   environment, so the same file shows the lighting turned 180° about the up axis; setting
   the texture's reflection matrix to a 180° turn about y afterwards makes it exact there too
   (``tests/interop``). Uncertain (read, not run): other readers may assume radiance, no sign
   flips or another frame; Babylon's non-default polynomial path
   (``useSphericalHarmonics = false``) was not checked.

3. **Filament** cmgen ``sh.txt`` (``to_filament_sh_txt``) and
   ``IndirectLight::Builder::irradiance(3, sh)`` (``filament_prescaled``). Nine lines
   ``(r, g, b); // L00, irradiance, pre-scaled base``; the values are "shader-ready", *not*
   L_lm: Â_l · K_lm · L_lm / π with K_lm the paper's constant of each polynomial (0.282095,
   0.488603, ..., 0.546274). Filament's shader
   (``Irradiance_SphericalHarmonics``) evaluates sh[0] + sh[1] y + sh[2] z + sh[3] x +
   sh[4] yx + sh[5] yz + sh[6] (3z² − 1) + sh[7] zx + sh[8] (x² − y²), clamped at 0, which is
   then E(n)/π: the Lambert 1/π is included. Checked in Filament's source (libs/ibl
   CubemapSH.cpp: ``computeSH`` with irradiance, then ``preprocessSHForShader``; its basis has
   the Condon-Shortley sign and so do its pre-scale factors, so the signs cancel; tools/cmgen:
   the output format). We write the shortest decimal that reads back to the same float
   (cmgen writes 15 fixed decimals) and **no windowing**, i.e. cmgen's ``--sh-window=no``.
   cmgen windows by default (``--sh-window=auto``, CubemapSH::windowSH): per colour channel
   it searches (by bisection) the largest cutoff w whose window (sin(πl/w)/(πl/w))⁴ on band l
   makes the reconstruction non-negative (Sloan, "Deringing Spherical Harmonics"), so its
   sh.txt of an HDRI with a strong sun has weaker l = 1, 2 bands than ours.
   Filament's reader of a sh.txt (``libs/filamentapp`` IBL.cpp) reads each line with
   ``sscanf(line, "(%f,%f,%f)")``. Two frames:

   - ``frame="cmgen"`` (default): the frame of what ``cmgen`` itself writes, by default
     (mirrored), for the same equirectangular image: (x, y, z)_cmgen = (y, z, x)_blender, so
     our sh.txt lines up with cmgen's specular KTX of that image. Derived from cmgen's
     source: it reads an equirect texel at u ∝ atan2(s.x, s.z), v from asin(s.y) (image
     centre toward +z, top +y), then mirrors x (``mirrorCubemap`` samples (−x, y, z)) unless
     ``--no-mirror``. Without the mirror the frame would be a reflection of Blender's, which
     no rotation reaches; with it, it is a proper rotation, 90° about the up axis from the
     glTF frame. cmgen's sub-texel resampling is ignored.
   - ``frame="gltf"``: the glTF frame, matching a glTF export of the Blender scene
     (Filament's world axes are right-handed with y up, like glTF's).

   ``IndirectLight::Builder::radiance()`` (Condon-Shortley-signed radiance) is not offered.

The ``from_*`` functions invert the exporters exactly (to rounding), for round trips.
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
