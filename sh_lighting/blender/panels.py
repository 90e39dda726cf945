"""The "SH Lighting" panel, in World Properties and in the 3D Viewport sidebar.

Both places draw with the same functions; the "Coefficients" sub-panel shows, per L_lm, what
it does, its gain s_lm and its three channels c_lm: the scene's custom properties themselves
(``scene_data``: keyframable, read by materials at render time; the lighting is s_lm · c_lm).
"""

import bpy

from ..core.sh import COEFFICIENT_NAMES
from ..core.sh import COEFFICIENT_PHRASES
from . import scene_data

CHANNELS = "RGB"


def draw_main(layout, context):
    """Buttons and settings: Compute / Reset, capture width, Apply / Remove with their target."""
    scene = context.scene
    settings = scene.sh_lighting
    layout.use_property_split = True
    layout.use_property_decorate = False

    col = layout.column(align=True)
    col.operator("shlight.compute_from_world", icon="WORLD")
    col.operator("shlight.reset", icon="LOOP_BACK")

    row = layout.row(heading="Capture Width")
    row.prop(settings, "use_capture_width", text="")
    sub = row.row()
    sub.active = settings.use_capture_width
    sub.prop(settings, "capture_width", text="")

    layout.prop(settings, "apply_target", expand=True)
    row = layout.row(align=True)
    row.operator("shlight.apply", text="Apply", icon="MATERIAL")
    row.operator("shlight.remove", text="Remove", icon="X")


def draw_coefficients(layout, context):
    """One block per coefficient: name and meaning, its gain, R G B: custom-property fields."""
    scene = context.scene
    if not scene_data.has_coefficients(scene):
        col = layout.column(align=True)
        col.label(text="No coefficients yet", icon="INFO")
        col.label(text="Compute from World, or set them from Python")
        return
    for index, name in enumerate(COEFFICIENT_NAMES):
        col = layout.column(align=True)
        col.label(text=f"{name}: {COEFFICIENT_PHRASES[index]}")
        gain = scene_data.GAIN_NAMES[index]
        if gain in scene:
            col.prop(scene, f'["{gain}"]', text="Gain")
        row = col.row(align=True)
        path = f'["{scene_data.PROPERTY_NAMES[index]}"]'
        for channel, letter in enumerate(CHANNELS):
            row.prop(scene, path, index=channel, text=letter)


class _SceneMixin:
    @classmethod
    def poll(cls, context):
        return context.scene is not None and hasattr(context.scene, "sh_lighting")


# Where the add-on shows itself: World Properties and the 3D Viewport sidebar.
LOCATIONS = {
    "world": {"bl_space_type": "PROPERTIES", "bl_region_type": "WINDOW", "bl_context": "world"},
    "view3d": {"bl_space_type": "VIEW_3D", "bl_region_type": "UI", "bl_category": "SH Lighting"},
}


def _panel(name, label, draw, parent=None, options=()):
    """One Panel class per location, ``SHLIGHT_PT_<location>[_<name>]``, drawing ``draw``."""
    panels = []
    for where, settings in LOCATIONS.items():
        attributes = {"bl_label": label, "bl_options": set(options), **settings,
                      "draw": lambda self, context: draw(self.layout, context)}
        if parent is not None:
            attributes["bl_parent_id"] = f"SHLIGHT_PT_{where}"
        suffix = f"_{name}" if name else ""
        panels.append(type(f"SHLIGHT_PT_{where}{suffix}", (_SceneMixin, bpy.types.Panel), attributes))
    return tuple(panels)


def sub_panels(name, label, draw, options=()):
    """A sub-panel ``label`` under each main panel, sharing ``draw(layout, context)``."""
    return _panel(name, label, draw, parent=True, options=options)


SHLIGHT_PT_world, SHLIGHT_PT_view3d = _panel("", "SH Lighting", draw_main)
SHLIGHT_PT_world_coefficients, SHLIGHT_PT_view3d_coefficients = sub_panels(
    "coefficients", "Coefficients", draw_coefficients
)

classes = (
    SHLIGHT_PT_world,
    SHLIGHT_PT_world_coefficients,
    SHLIGHT_PT_view3d,
    SHLIGHT_PT_view3d_coefficients,
)
register, unregister = bpy.utils.register_classes_factory(classes)
