"""The "SH Lighting" panel, in World Properties and in the 3D Viewport sidebar.

Both places draw with the same functions; the "Coefficients" sub-panel shows, per L_lm, what
it does, its row value (scales the RGB triple) and the three channels, which are the scene's
custom properties themselves (keyframable, read by materials at render time). The "Node Group"
sub-panel shows the fit settings, what the SH node group holds (node count, left-out terms and
their exact error bound) and a "Refit" hint when the current lighting needs more.
"""

import bpy

from ..core.sh import COEFFICIENT_NAMES
from . import nodes, properties, scene_data

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


def draw_node_group(layout, context):
    """The fit settings and what the SH node group holds: node count, left-out terms, bound."""
    scene = context.scene
    settings = scene.sh_lighting
    layout.use_property_split = True
    layout.use_property_decorate = False
    layout.prop(settings, "fit_tolerance")
    layout.prop(settings, "clamp_mode")
    col = layout.column(align=True)
    tree = nodes.find_node_group()
    info = nodes.fit_info(tree)
    if tree is None:
        col.label(text="Node group: none yet (Apply creates it)", icon="NODETREE")
        return
    if info is None:
        col.label(text=f"Node group: {len(tree.nodes)} nodes, not fitted", icon="NODETREE")
    else:
        spec = info["spec"]
        kinds = ["grey (scalar math)" if spec.scalar else "RGB"]
        if spec.clamp:
            kinds.append("clamped at 0")
        col.label(text=f"Node group: {info['nodes']} nodes, {', '.join(kinds)}", icon="NODETREE")
        if info["omitted"]:
            col.label(text="Left out: " + " ".join(info["omitted"]))
            col.label(text=f"Left-out error ≤ {100.0 * info['bound']:.3g} % of mean irradiance")
        else:
            col.label(text="Left out: nothing (all 9 terms)")
    hint = nodes.refit_hint(scene, tree=tree, info=info)
    if hint:
        row = col.row()
        row.alert = True
        row.label(text=hint, icon="ERROR")
    layout.operator("shlight.refit", icon="FILE_REFRESH")


def draw_coefficients(layout, context):
    """One block per coefficient: name and meaning, row value, R G B custom-property fields."""
    scene = context.scene
    if not scene_data.has_coefficients(scene):
        col = layout.column(align=True)
        col.label(text="No coefficients yet", icon="INFO")
        col.label(text="Compute from World, or set them from Python")
        return
    settings = scene.sh_lighting
    for index, name in enumerate(COEFFICIENT_NAMES):
        col = layout.column(align=True)
        col.label(text=f"{name}: {properties.COEFFICIENT_PHRASES[index]}")
        col.prop(settings, properties.row_property_name(index), text="Row")
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
SHLIGHT_PT_world_node_group, SHLIGHT_PT_view3d_node_group = sub_panels(
    "node_group", "Node Group", draw_node_group, options={"DEFAULT_CLOSED"}
)

classes = (
    SHLIGHT_PT_world,
    SHLIGHT_PT_world_coefficients,
    SHLIGHT_PT_world_node_group,
    SHLIGHT_PT_view3d,
    SHLIGHT_PT_view3d_coefficients,
    SHLIGHT_PT_view3d_node_group,
)
register, unregister = bpy.utils.register_classes_factory(classes)
