"""User settings of SH Lighting (one PointerProperty, ``Scene.sh_lighting``) and the UI data
of the coefficient custom properties.

The coefficients themselves are *not* stored here: they are the plain custom properties
``scene["sh_L00"]`` ... of ``scene_data`` (so a .blend renders without the add-on). The group
only adds, per coefficient, a signed "row" value whose getter and setter read and write that
custom property: the row value is the mean of the R, G and B values, and setting it rescales
the triple proportionally (keeping its colour). Nothing is stored for the rows themselves.

Custom properties get their editing hints (description, soft limits, no 0-1 clamp) from
``ensure_coefficient_ui``, which ``store_coefficients`` calls after every write.
"""

import bpy
import numpy as np

from ..core.pruning import DEFAULT_RELATIVE_TOLERANCE
from ..core.sh import COEFFICIENT_NAMES
from . import nodes, scene_data

# What each coefficient does, in Blender world axes (REFERENCE.md §1: Y1-1 ∝ y, Y10 ∝ z,
# Y11 ∝ x, Y2-2 ∝ xy, Y2-1 ∝ yz, Y20 ∝ 3z² - 1, Y21 ∝ xz, Y22 ∝ x² - y²).
COEFFICIENT_PHRASES = (
    "ambient (overall brightness)",
    "light from +Y vs −Y",
    "light from above vs below",
    "light from +X vs −X",
    "xy diagonal",
    "yz diagonal",
    "top/bottom vs horizon",
    "xz diagonal",
    "x vs y axis",
)

# Coefficients are signed HDR radiance: no hard limits, a drag range that the UI widens by
# itself when a value lies outside it.
SOFT_LIMIT = 10.0
PRECISION = 4
STEP = 1  # UI step in hundredths: 0.01 per click

# Below this fraction of the triple's largest magnitude, the channel mean counts as zero and
# setting a row adds the change to every channel instead of rescaling (no huge factors).
_MEAN_EPSILON = 1e-6

APPLY_TARGETS = (
    ("SELECTED", "Selected", "Materials of the selected objects"),
    ("ALL", "All", "Materials of every object in the scene"),
)

DEFAULT_CAPTURE_WIDTH = 256

CLAMP_MODES = (
    ("AUTO", "Auto", "Clamp the irradiance at 0 only where it can go negative"),
    ("ALWAYS", "Always", "Always clamp the irradiance at 0 (one more node)"),
    ("NEVER", "Never", "Never clamp: negative irradiance renders as is"),
)


def _refit(self, context):
    """Update callback of the fit settings: refit the file's SH group to them."""
    nodes.refit_node_group(self.id_data)


def coefficient_description(index):
    """The tooltip of coefficient ``index``: name, what it does, what the numbers are."""
    return (
        f"{COEFFICIENT_NAMES[index]}, {COEFFICIENT_PHRASES[index]}: signed RGB lighting "
        "coefficient L_lm (radiance, Blender world axes); keyframable"
    )


def ensure_coefficient_ui(scene):
    """Give each existing coefficient custom property its UI data: a description, soft limits,
    3 plain number fields (subtype NONE, which neither clamps to 0-1 nor shows a colour swatch).
    """
    for index, name in enumerate(scene_data.PROPERTY_NAMES):
        if name not in scene:
            continue
        scene.id_properties_ui(name).update(
            subtype="NONE",
            description=coefficient_description(index),
            soft_min=-SOFT_LIMIT,
            soft_max=SOFT_LIMIT,
            precision=PRECISION,
            step=STEP,
        )


def store_coefficients(scene, coeffs, computed=False):
    """``scene_data.set_coefficients`` plus the UI data of the custom properties, then the
    file's SH node group refitted to the new values (``nodes.refit_node_group``: rebuilt only
    when the set of needed terms changes; nothing happens without a group).
    """
    c = scene_data.set_coefficients(scene, coeffs, computed=computed)
    ensure_coefficient_ui(scene)
    nodes.refit_node_group(scene)
    return c


def reset_coefficients(scene):
    """Store the values last computed from the world as the coefficients again (Reset).

    A LookupError if nothing was computed yet. Returns the restored (9, 3) array.
    """
    computed = scene_data.get_computed(scene)
    if computed is None:
        raise LookupError("Nothing to reset to: run Compute from World first")
    return store_coefficients(scene, computed)


def row_value(rgb):
    """The row value of an RGB triple: its signed channel mean."""
    return float(np.mean(rgb))


def scaled_row(rgb, value):
    """``rgb`` changed so that its channel mean becomes ``value``.

    Rescales proportionally (keeps the colour, flips it through zero for a negative factor);
    a triple whose mean is (numerically) zero cannot be rescaled and is shifted instead, so
    an all-zero triple becomes grey.
    """
    rgb = np.asarray(rgb, dtype=np.float64)
    mean = float(np.mean(rgb))
    largest = float(np.max(np.abs(rgb)))
    if largest > 0.0 and abs(mean) > _MEAN_EPSILON * largest:
        return rgb * (value / mean)
    return rgb + (value - mean)


def _row_property(index):
    name = scene_data.PROPERTY_NAMES[index]

    def get_row(self):
        scene = self.id_data
        return row_value(scene[name]) if name in scene else 0.0

    def set_row(self, value):
        scene = self.id_data
        if scene_data.has_coefficients(scene):
            coeffs = scene_data.get_coefficients(scene)
        else:
            coeffs = np.zeros((9, 3))
            for i, existing in enumerate(scene_data.PROPERTY_NAMES):
                if existing in scene:
                    coeffs[i] = list(scene[existing])
        coeffs[index] = scaled_row(coeffs[index], value)
        store_coefficients(scene, coeffs)

    return bpy.props.FloatProperty(
        name=COEFFICIENT_NAMES[index],
        description=(
            f"{COEFFICIENT_NAMES[index]}, {COEFFICIENT_PHRASES[index]}: mean of the RGB "
            "coefficient; changing it rescales all three channels (keyframe the RGB values)"
        ),
        get=get_row,
        set=set_row,
        soft_min=-SOFT_LIMIT,
        soft_max=SOFT_LIMIT,
        precision=PRECISION,
        step=STEP,
        options=set(),  # not animatable: the custom property is what renders and animates
    )


def row_property_name(index):
    """Attribute of ``Scene.sh_lighting`` holding row ``index``: 'row_L00', 'row_L1m1', ..."""
    return "row_" + scene_data.PROPERTY_NAMES[index][len("sh_") :]


class SHLIGHT_PG_settings(bpy.types.PropertyGroup):
    """Per-scene settings of SH Lighting (user choices only, no transient state)."""

    __annotations__ = {row_property_name(i): _row_property(i) for i in range(9)}

    apply_target: bpy.props.EnumProperty(
        name="Apply To",
        description="Which materials Apply and Remove change",
        items=APPLY_TARGETS,
        default="SELECTED",
    )
    use_capture_width: bpy.props.BoolProperty(
        name="Capture Width",
        description=(
            "Use a capture width of its own for this scene instead of the one in the add-on "
            "preferences, when capturing a procedural world"
        ),
        default=False,
    )
    capture_width: bpy.props.IntProperty(
        name="Capture Width",
        description=(
            "Width in pixels of the equirectangular image rendered to capture this scene's "
            "procedural world; the height is half of it"
        ),
        default=DEFAULT_CAPTURE_WIDTH,
        min=16,
        soft_min=64,
        soft_max=2048,
        subtype="PIXEL",
    )
    fit_tolerance: bpy.props.FloatProperty(
        name="Fit Tolerance",
        description=(
            "Leave a term out of the SH node group when it, and the sum of all left-out "
            "terms, stay below this fraction of the mean irradiance everywhere on the sphere "
            "at every keyframed frame; 0 keeps all nine terms"
        ),
        default=DEFAULT_RELATIVE_TOLERANCE,
        min=0.0,
        max=1.0,
        soft_max=0.05,
        precision=4,
        step=1,
        subtype="FACTOR",
        update=_refit,
    )
    clamp_mode: bpy.props.EnumProperty(
        name="Clamp",
        description="Clamp the irradiance of the SH node group at 0 (max(E, 0))",
        items=CLAMP_MODES,
        default="AUTO",
        update=_refit,
    )


def capture_width_for(settings, addon_preferences):
    """The capture width to use: the scene's override, else the preferences', else 256.

    ``settings`` is a scene's ``sh_lighting`` group or None, ``addon_preferences`` the add-on's
    preferences or None.
    """
    if settings is not None and settings.use_capture_width:
        return int(settings.capture_width)
    if addon_preferences is not None:
        return int(addon_preferences.capture_resolution)
    return DEFAULT_CAPTURE_WIDTH


classes = (SHLIGHT_PG_settings,)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)
    bpy.types.Scene.sh_lighting = bpy.props.PointerProperty(
        type=SHLIGHT_PG_settings,
        name="SH Lighting",
        description="Settings of SH Lighting (the coefficients are the scene's sh_L* properties)",
    )


def unregister():
    del bpy.types.Scene.sh_lighting
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
