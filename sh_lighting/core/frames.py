"""Exact changes of axes for lighting coefficients: the paper's frame, Blender's, glTF's.

Coefficients in this project are stored in Blender world axes (z up, docs/reference.md §3). Other
sources and targets use y-up frames; changing frames is a proper rotation of the directions,
so the coefficients change by a real SH rotation, band by band (``rotation.sh_rotation_matrix``).
It is not a relabelling: the l = 2 coefficients mix (L20 and L22 in particular).

A frame change is given as the 3×3 matrix F that maps a direction's Blender coordinates to its
coordinates in the other frame (or the reverse, as named). The lighting function itself does
not move: L_other(F ω) = L_blender(ω), i.e. the coefficients are those of the lighting rotated
by F, ``rotate_coefficients(coeffs, F)``. Each band's energy Σ_m L_lm² is unchanged.

* **The paper's probes** (Figure 2; docs/reference.md §4): +y is up, so L1-1 is the vertical moment.
  Brought to Blender by (x, y, z)_blender = (x, −z, y)_paper; afterwards L10 (Blender) equals
  L1-1 (paper).
* **glTF, three.js, Filament (gltfio)**: right-handed, +y up. Blender's glTF exporter (with its
  default "+Y Up") maps (x, y, z)_blender → (x, z, −y)_gltf.

Both matrices are proper rotations (orthonormal, determinant +1; checked at import). For
such axis permutations (with signs) every entry of the SH rotation matrix of bands 0-2 is one
of 0, ±½, ±√3/2, ±1; the least-squares solution is snapped to those exact values (after
checking it is within 1e-9 of them), so that e.g. the paper's L1-1 = 0.39 becomes Blender's
L10 = 0.39 exactly, not 0.38999999999999996.

The paper frame chosen in docs/reference.md §4 is the glTF frame, so ``paper_to_blender`` and
``y_up_to_blender`` give the same numbers; they are kept apart because they say different
things about where the data came from.
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
