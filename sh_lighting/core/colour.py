"""Colour: decoding 8-bit texels, the RGB working spaces Blender 4.2–5.0 render in, luminance.

``WORKING_SPACES`` (Linear Rec.709, Linear Rec.2020, ACEScg) by their CIE xy primaries and
white; ``rgb_to_xyz_matrix`` is the normalised primary matrix (SMPTE RP 177),
``luminance_weights`` its Y row adapted to D65 (Rec.709: 0.2126, 0.7152, 0.0722, the project's
one luminance), ``conversion_matrix`` goes through XYZ with Bradford adaptation, as Blender's
OpenColorIO does; converting L_lm equals converting the image (projection is linear).
8-bit texels (``BYTE_SPACES``) decode as Blender renders them: byte / 255, the IEC 61966-2-1
sRGB curve, then the matrix to the working space (``byte_decoding``, ``decode_bytes``).
Details: docs/modules.md.
"""

import numpy as np

#: name -> (red xy, green xy, blue xy, white xy)
WORKING_SPACES = {
    "Linear Rec.709": ((0.64, 0.33), (0.30, 0.60), (0.15, 0.06), (0.3127, 0.3290)),
    "Linear Rec.2020": ((0.708, 0.292), (0.170, 0.797), (0.131, 0.046), (0.3127, 0.3290)),
    "ACEScg": ((0.713, 0.293), (0.165, 0.830), (0.128, 0.044), (0.32168, 0.33767)),
}
REC709 = "Linear Rec.709"
#: 8-bit image colour spaces decoded directly: name -> (transfer curve, primaries' space).
BYTE_SPACES = {
    "sRGB": ("srgb", REC709),
    "Linear Rec.709": (None, REC709),
    "Linear Rec.2020": (None, "Linear Rec.2020"),
    "ACEScg": (None, "ACEScg"),
}
D65 = (0.3127, 0.3290)
# Bradford cone response matrix (Lam 1985), the chromatic adaptation OpenColorIO configs use.
BRADFORD = np.array([
    [0.8951, 0.2664, -0.1614],
    [-0.7502, 1.7135, 0.0367],
    [0.0389, -0.0685, 1.0296],
])


def _space(name):
    try:
        return WORKING_SPACES[name]
    except KeyError:
        raise ValueError(
            f"unknown working colour space {name!r}: use one of {', '.join(WORKING_SPACES)}"
        ) from None


def _xyz(xy):
    """XYZ with Y = 1 of chromaticity (x, y)."""
    x, y = xy
    return np.array([x / y, 1.0, (1.0 - x - y) / y])


def _adaptation(white_from, white_to):
    """Bradford matrix taking XYZ under ``white_from`` to XYZ under ``white_to``."""
    source, target = BRADFORD @ _xyz(white_from), BRADFORD @ _xyz(white_to)
    return np.linalg.solve(BRADFORD, np.diag(target / source) @ BRADFORD)


def rgb_to_xyz_matrix(space, white=D65):
    """3×3 matrix from ``space``'s RGB to CIE XYZ, adapted (Bradford) to ``white`` (xy).

    SMPTE RP 177: P = [X_r X_g X_b] of the primaries (Y = 1), S = P⁻¹ W, matrix = P diag(S),
    so RGB (1, 1, 1) maps to the space's white with Y = 1, then adapted to ``white``.
    """
    red, green, blue, own_white = _space(space)
    primaries = np.stack([_xyz(red), _xyz(green), _xyz(blue)], axis=1)
    scale = np.linalg.solve(primaries, _xyz(own_white))
    return _adaptation(own_white, white) @ primaries @ np.diag(scale)


def luminance_weights(space=REC709):
    """(3,) weights giving the luminance Y (D65-adapted) of RGB in ``space``; they sum to 1."""
    return rgb_to_xyz_matrix(space)[1]


def conversion_matrix(source, target):
    """3×3 matrix taking linear RGB in ``source`` to linear RGB in ``target`` (both names of
    ``WORKING_SPACES``), through D65-adapted XYZ."""
    if source == target:
        _space(source)
        return np.eye(3)
    return np.linalg.solve(rgb_to_xyz_matrix(target), rgb_to_xyz_matrix(source))


def convert_coefficients(coeffs, source, target=REC709):
    """``coeffs`` (..., 3) RGB (e.g. (9, 3) L_lm) from working space ``source`` to ``target``,
    float64; a copy even when the spaces are the same."""
    c = np.array(coeffs, dtype=np.float64)
    if c.shape[-1:] != (3,):
        raise ValueError(f"colour conversion needs RGB values (..., 3), got shape {c.shape}")
    return c @ conversion_matrix(source, target).T


def byte_decoding(space, working):
    """How 8-bit texels of an image in ``space`` (a ``BYTE_SPACES`` name) become linear RGB of
    ``working``: (curve, matrix) for ``decode_bytes``. curve (256,) float32: each byte's
    linear value; matrix (3, 3) float32 from the image's primaries to ``working``, or None
    when they are the same."""
    try:
        curve, primaries = BYTE_SPACES[space]
    except KeyError:
        raise ValueError(
            f"8-bit colour space {space!r} is not decoded here: use one of {', '.join(BYTE_SPACES)}"
        ) from None
    values = np.arange(256) / 255.0
    if curve == "srgb":
        values = srgb_to_linear(values)
    matrix = None if primaries == working else conversion_matrix(primaries, working)
    return values.astype(np.float32), None if matrix is None else matrix.astype(np.float32)


def decode_bytes(codes, curve, matrix=None):
    """Linear RGB (H, W, 3) float32 of 8-bit texels ``codes`` (H, W, 3) uint8:
    ``matrix`` · curve[codes] per texel (``byte_decoding``; no matrix: curve[codes])."""
    linear = np.asarray(curve, dtype=np.float32)[codes]
    if matrix is None:
        return linear
    return linear @ np.asarray(matrix, dtype=np.float32).T


def srgb_to_linear(values):
    """The IEC 61966-2-1 sRGB decoding of ``values`` (any shape), as float64.

    v / 12.92 for v <= 0.04045, ((v + 0.055) / 1.055) ** 2.4 above; negative values are
    mirrored (odd extension) so the function is monotonic on the whole real line.
    """
    v = np.asarray(values, dtype=np.float64)
    a = np.abs(v)
    out = np.where(a <= 0.04045, a / 12.92, ((a + 0.055) / 1.055) ** 2.4)
    return np.copysign(out, v)
