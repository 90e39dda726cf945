"""User settings of SH Lighting: one PointerProperty, ``Scene.sh_lighting``.

The coefficients are *not* stored here: they are the plain custom properties of
``scene_data`` (``scene["sh_L00"]``, ``scene["sh_L00_gain"]``, ...), so that a .blend renders
without the add-on and every value an artist edits is keyframable.
"""

import bpy

from ...choices import APPLY_MODE_ITEMS, APPLY_MODE_VALUES, APPLY_MODES

APPLY_TARGETS = (
    ("SELECTED", "Selected", "Materials of the selected objects"),
    ("ALL", "All", "Materials of every object in the scene"),
)

DEFAULT_CAPTURE_WIDTH = 256


class SHLIGHT_PG_settings(bpy.types.PropertyGroup):
    """Per-scene settings of SH Lighting (user choices only, no transient state)."""

    apply_target: bpy.props.EnumProperty(
        name="Apply To",
        description="Which materials Apply and Remove change",
        items=APPLY_TARGETS,
        default="SELECTED",
    )
    apply_mode: bpy.props.EnumProperty(
        name="Mode",
        description="How Apply lights the materials (the line below says what it does in the "
                    "current render engine)",
        items=[(*item, "NONE", APPLY_MODE_VALUES[item[0]]) for item in APPLY_MODE_ITEMS],
        default=APPLY_MODES[0],
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
            "procedural world; the height is half of it (an odd width is rounded up)"
        ),
        default=DEFAULT_CAPTURE_WIDTH,
        min=16,
        soft_min=64,
        soft_max=2048,
        subtype="PIXEL",
    )


def capture_width_for(settings, addon_preferences):
    """The capture width to use: the scene's override, else the preferences', else 256; an
    odd width is rounded up to the next even one (the capture's height is half of it).

    ``settings`` is a scene's ``sh_lighting`` group or None, ``addon_preferences`` the add-on's
    preferences or None.
    """
    if settings is not None and settings.use_capture_width:
        width = int(settings.capture_width)
    elif addon_preferences is not None:
        width = int(addon_preferences.capture_resolution)
    else:
        width = DEFAULT_CAPTURE_WIDTH
    return width + width % 2


classes = (SHLIGHT_PG_settings,)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)
    bpy.types.Scene.sh_lighting = bpy.props.PointerProperty(
        type=SHLIGHT_PG_settings,
        name="SH Lighting",
        description=(
            "Settings of SH Lighting (the coefficients are the scene's sh_L* custom properties)"
        ),
    )


def unregister():
    del bpy.types.Scene.sh_lighting
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
