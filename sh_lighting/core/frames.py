"""Exact changes of axes for lighting coefficients: the paper's frame, Blender's, glTF's.

A frame change F (3×3, Blender coordinates to the other frame's) is a proper rotation, so the
coefficients change by a real SH rotation band by band: L_other(F ω) = L_blender(ω),
``rotate_coefficients(coeffs, F)`` (the l = 2 terms mix). The paper's probes (+y up):
(x, y, z)_blender = (x, −z, y)_paper; glTF, three.js, Filament: (x, y, z)_blender →
(x, z, −y)_gltf. For these signed permutations every rotation entry is 0, ±½, ±√3/2 or ±1, and
the matrices are snapped to those exact values (the paper's L1-1 = 0.39 is Blender's L10 =
0.39 exactly). Details: docs/modules.md.
"""

from functools import lru_cache
from math import sqrt

import numpy as np

from .irradiance import check_coefficients
from .rotation import check_rotation, sh_rotation_matrix

# Blender coordinates of a direction given in the paper's coordinates: b = PAPER_TO_BLENDER @ p,
# i.e. (x, y, z)_blender = (x, -z, y)_paper (the paper's +y becomes Blender's +z).
PAPER_TO_BLENDER = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])

# y-up (glTF) coordinates of a direction given in Blender's: g = BLENDER_TO_Y_UP @ b,
# i.e. (x, y, z)_gltf = (x, z, -y)_blender (Blender's +z becomes glTF's +y, -y becomes +z).
BLENDER_TO_Y_UP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])

for _matrix in (PAPER_TO_BLENDER, BLENDER_TO_Y_UP):
    check_rotation(_matrix)  # orthonormal with det +1, or an import-time error


# |D_ij| of bands 0-2 for a rotation that permutes the axes (with signs): the octahedral group
# acts on band 2 by signed permutations of (xy, yz, xz) and by 120° turns of (3z² - 1, x² - y²).
_EXACT_MAGNITUDES = np.array([0.0, 0.5, sqrt(3.0) / 2.0, 1.0])
SNAP_TOLERANCE = 1e-9


def _is_signed_permutation(r):
    return bool(np.isin(r, (-1.0, 0.0, 1.0)).all())


def frame_sh_matrix(frame_matrix, max_order=2):
    """SH matrix D of a frame change F (coefficients in the new frame = D @ coefficients).

    For an axis permutation with signs and max_order <= 2, D's entries are snapped to exact
    values (0, ±½, ±√3/2, ±1); otherwise D is ``rotation.sh_rotation_matrix`` as computed.
    """
    r = check_rotation(frame_matrix)
    d = sh_rotation_matrix(r, max_order)
    if max_order > 2 or not _is_signed_permutation(r):
        return d
    magnitude = np.abs(d)
    nearest = _EXACT_MAGNITUDES[
        np.argmin(np.abs(magnitude[..., None] - _EXACT_MAGNITUDES), axis=-1)
    ]
    if np.abs(magnitude - nearest).max() > SNAP_TOLERANCE:
        return d  # not expected for these rotations; keep the least-squares values
    return np.where(nearest == 0.0, 0.0, np.copysign(nearest, d))


@lru_cache(maxsize=None)
def _sh_matrix(name, order):
    """The SH matrix of a named frame change, computed once per order (read-only)."""
    frames = {
        "paper_to_blender": PAPER_TO_BLENDER,
        "blender_to_y_up": BLENDER_TO_Y_UP,
        "y_up_to_blender": BLENDER_TO_Y_UP.T,
    }
    d = frame_sh_matrix(frames[name], order)
    d.setflags(write=False)
    return d


def change_frame(coeffs, frame_matrix):
    """Coefficients of the same lighting in axes where a direction ω has coordinates F ω.

    ``frame_matrix`` F must be a proper rotation (a reflection such as a mirrored axis is
    refused: it is not a change between right-handed frames). Shape ((order+1)², 3) kept.
    """
    c, order = check_coefficients(coeffs)
    return frame_sh_matrix(frame_matrix, order) @ c


def _apply(name, coeffs):
    c, order = check_coefficients(coeffs)
    return _sh_matrix(name, order) @ c


def paper_to_blender(coeffs):
    """The paper's y-up probe coefficients (e.g. Figure 2) in Blender world axes (z up).

    (x, y, z)_blender = (x, −z, y)_paper: L10 (Blender) = L1-1 (paper), L1-1 (Blender) =
    −L10 (paper), L11 unchanged; the l = 2 band is rotated, not relabelled.
    """
    return _apply("paper_to_blender", coeffs)


def blender_to_y_up(coeffs):
    """Blender-axes coefficients in the glTF / three.js / Filament frame: (x, z, −y)_blender."""
    return _apply("blender_to_y_up", coeffs)


def y_up_to_blender(coeffs):
    """Inverse of :func:`blender_to_y_up`: glTF-frame coefficients in Blender world axes."""
    return _apply("y_up_to_blender", coeffs)
