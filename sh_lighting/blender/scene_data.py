"""Where a scene keeps its SH lighting: plain custom properties, readable without the add-on.

The 9 RGB lighting coefficients L_lm (raw radiance, Blender world axes) live in
``scene["sh_L00"]`` ... ``scene["sh_L22"]``, each a 3-float array. Plain custom properties
(not a registered PropertyGroup) are what an Attribute node of type View Layer can read at
render time in a Blender where this add-on is not installed (REFERENCE.md §3), so a saved
.blend renders the same on a render farm. They are keyframable and undoable like any property.

``scene["sh_computed"]`` keeps the last values computed from the world (27 floats), so that
Reset can return to them.
"""

import numpy as np

from ..core.coefficients import check_coefficients
from ..core.sh import COEFFICIENT_NAMES

# Attribute/custom-property names: "L1-1" -> "sh_L1m1" (no '-' inside an attribute name).
PROPERTY_NAMES = tuple("sh_" + name.replace("-", "m") for name in COEFFICIENT_NAMES)
COMPUTED_PROPERTY = "sh_computed"


def has_coefficients(scene):
    """True when every one of the 9 coefficient properties exists on ``scene``."""
    return all(name in scene for name in PROPERTY_NAMES)


def get_coefficients(scene):
    """The scene's (9, 3) float64 L_lm; a LookupError if they were never set."""
    missing = [name for name in PROPERTY_NAMES if name not in scene]
    if missing:
        raise LookupError(
            f"scene '{scene.name}' has no SH lighting coefficients yet ({', '.join(missing)} "
            "missing): run Compute from World or set them first"
        )
    return np.array([list(scene[name]) for name in PROPERTY_NAMES], dtype=np.float64)


def check_coefficients_9x3(coeffs):
    """A finite (9, 3) float64 copy of ``coeffs`` or a ValueError saying what is wrong
    (``core.coefficients.check_coefficients``: numbers only, within Blender's float32 range).
    """
    return check_coefficients(coeffs)


def set_coefficients(scene, coeffs, computed=False):
    """Store (9, 3) L_lm on ``scene``; with ``computed`` also as the Reset values."""
    c = check_coefficients_9x3(coeffs)
    for name, rgb in zip(PROPERTY_NAMES, c):
        scene[name] = [float(v) for v in rgb]
    if computed:
        scene[COMPUTED_PROPERTY] = [float(v) for v in c.ravel()]
    return c


def get_computed(scene):
    """The (9, 3) values last computed from the world, or None."""
    if COMPUTED_PROPERTY not in scene:
        return None
    return np.array(list(scene[COMPUTED_PROPERTY]), dtype=np.float64).reshape(9, 3)
