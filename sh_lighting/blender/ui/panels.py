"""The "SH Lighting" panel, in World Properties and in the 3D Viewport sidebar.

Both draw with the same functions: presets (a header popover), the irradiance sphere with the
negative-light warning, Compute / Reset, the capture width (procedural worlds), Apply /
Remove; the "Coefficients" sub-panel has per L_lm its name (tooltip: what it does now), a
swatch of c_lm and the gain s_lm (L_lm = s_lm · c_lm). Texts wrap to the panel's width.
Nothing here writes coefficients: fields and buttons go through properties and operators.
"""

import textwrap

import bpy

from ...core.edits import describe_coefficients
from ...core.minimum import (
    irradiance_minimum, mean_irradiance, negative_light_is_small, negative_light_warning)
from ...core.sh import COEFFICIENT_NAMES, COEFFICIENT_PHRASES
from ...choices import resolve_mode
from ..data import scene_data
from ..design import edits
from ..shading import materials, notes
from ..world import reader
from .. import world_edit
from . import presets as presets_ui
from .operators import beyond_selection
from . import previews

CHANNELS = "RGB"
# What each coefficient does, in an artist's few words (its name L_lm and the full wording are
# in the tooltips): light overall, from +Y (back) vs −Y (front), above vs below, +X (right) vs
# −X (left), along the diagonals, at the poles vs the horizon, along X vs along Y.
SHORT_PHRASES = ("Overall", "Back/front", "Up/down", "Right/left", "Diagonal XY",
                 "Diagonal YZ", "Poles/sides", "Diagonal XZ", "X vs Y")
# What the swatch beside each line is (its tooltip and the gain's say it)
SWATCH_NOTE = ("The swatch beside it is the term's colour (for a term that takes light away, "
               "the colour it takes)")
IRRADIANCE_SCALE = 6.0  # the sphere: 6 UI units (120 px at scale 1)
CHARACTER_WIDTH = 6.5  # mean width of a UI character in px at scale 1 (Blender's default font)
CHOICE_LABEL_FACTOR = 0.26  # the label column of Apply To and Mode
SHOW_CHANNELS = "sh_lighting_show_channels"
# Lines under Apply (read in full in the sidebar: notes.MODE_NOTE_CHARACTERS)
BEYOND_LINE = "Also {count} material(s) not selected"
PREVIEW_LINE = "Preview adds its studio light too"  # WindowManager: which rows show R, G, B


def wrapped(layout, context, text, icon="NONE"):
    """``text`` as labels wrapped to the width of the region being drawn (one per line)."""
    region = getattr(context, "region", None)
    width = region.width if region is not None and region.width > 1 else 300
    scale = ui_scale(context)
    indent = 0 if icon == "NONE" else 22
    chars = max(16, int((width - 60 - indent) / (CHARACTER_WIDTH * scale)))
    col = layout.column(align=True)
    for i, line in enumerate(textwrap.wrap(text, chars) or [""]):
        col.label(text=line, icon=icon if i == 0 else ("BLANK1" if icon != "NONE" else "NONE"))
    return col


def choice_row(layout, data, prop, label):
    """An expanded enum with its label in a column of ``CHOICE_LABEL_FACTOR`` of the width:
    property split leaves the buttons too little room, and "Emission Only" would be cut short
    at the sidebar's default width."""
    split = layout.split(factor=CHOICE_LABEL_FACTOR)
    column = split.column()
    column.alignment = "RIGHT"
    column.label(text=label)
    row = split.row(align=True)
    row.use_property_split = False
    row.prop(data, prop, expand=True)


def ui_scale(context):
    """The UI scale (1 when there is none: background mode reports 0)."""
    scale = context.preferences.system.ui_scale if context.preferences else 0.0
    return scale if scale > 0.0 else 1.0


def read_world(context):
    """``reader.read_world`` of the context's scene as its view layer's depsgraph last
    evaluated it (drawing and polls must not trigger an evaluation); a WorldError for a
    world that gives no lighting."""
    depsgraph = context.view_layer.depsgraph if context.view_layer is not None else None
    return reader.read_world(context.scene, depsgraph)


def world_kind(context):
    """"image" (read directly), "procedural" (captured by a Cycles render) or "none"."""
    try:
        source = read_world(context)
    except reader.WorldError:
        return "none"
    return "procedural" if isinstance(source, reader.ProceduralSource) else "image"


def negative_light_line(coeffs):
    """The button under the sphere when the irradiance dips below zero, with how deep (its
    minimum, % of the mean; the tooltip says where and over how much of the sphere)."""
    mean = mean_irradiance(coeffs)
    if (mean <= 0.0).any():
        return "Negative light: smooth it"
    depth = 100.0 * float((irradiance_minimum(coeffs).value / mean).min())
    if negative_light_is_small(coeffs):
        return f"Slight negative light ({depth:.1f} %)"
    return f"Negative light ({depth:.0f} %): smooth it"


def sphere_caption(stops):
    """The line under the sphere: what it is and how it is exposed."""
    return f"White ball, auto-exposed ({stops:+.1f} EV)"


def draw_sphere(layout, context, coeffs):
    """The irradiance sphere of ``coeffs``, centred, and the negative-light warning."""
    try:
        preview, stops = previews.irradiance(coeffs)
    except ValueError as error:  # e.g. coefficients typed in as NaN
        wrapped(layout, context, str(error), icon="ERROR")
        return
    col = layout.column(align=True)
    row = col.row()
    row.alignment = "CENTER"
    row.template_icon(icon_value=preview.icon_id, scale=IRRADIANCE_SCALE)
    # One line under the sphere either way (the panel does not jump while dragging): the
    # negative-light warning as a button that smooths it (the whole warning in its tooltip),
    # or what the sphere shows: it is exposed to its own range (brightest point white), and
    # the line says by how much, so a brighter lighting reads as a lower exposure.
    row = col.row()
    if negative_light_warning(coeffs):
        text = negative_light_line(coeffs)
        small = negative_light_is_small(coeffs)
        row.alert = not small  # a small dip is said quietly (core.minimum.SMALL_NEGATIVE)
        op = row.operator("shlight.window", text=text, icon="INFO" if small else "ERROR")
        op.kind = "MINIMAL"
    else:
        row.alignment = "CENTER"
        row.label(text=sphere_caption(stops))


def draw_problems(layout, context):
    """What is wrong with the scene's coefficient and gain properties (``scene_data.problems``:
    text, a dict, NaN... put there by a script or a key), with Repair; True if anything is."""
    found = scene_data.problems(context.scene)
    for _name, message in found:
        wrapped(layout, context, message, icon="ERROR")
    if found:
        layout.operator(SHLIGHT_OT_repair.bl_idname, icon="TOOL_SETTINGS")
    return bool(found)


class SHLIGHT_OT_repair(bpy.types.Operator):
    """Write a valid value over each invalid SH coefficient or gain property: a gain 1, a
    coefficient its Reset value (else 0). Keyframed or driven ones are fixed in their
    keyframes or driver"""

    bl_idname = "shlight.repair"
    bl_label = "Repair"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        if context.scene is None or not scene_data.problems(context.scene):
            cls.poll_message_set("Every SH coefficient and gain property is valid")
            return False
        return True

    def execute(self, context):
        try:
            repaired = scene_data.repair(context.scene)
        except ValueError as error:
            self.report({"ERROR"}, f"Nothing repaired: {error}")
            return {"CANCELLED"}
        self.report({"INFO"}, f"Repaired {', '.join(repaired)}")
        return {"FINISHED"}


def draw_main(layout, context):
    """Sphere, Compute / Reset, capture width (procedural worlds), Apply / Remove."""
    scene = context.scene
    settings = scene.sh_lighting
    layout.use_property_split = True
    layout.use_property_decorate = False
    if scene_data.has_coefficients(scene):
        if not draw_problems(layout, context):
            draw_sphere(layout, context, scene_data.get_coefficients(scene))

    row = layout.row(align=True)
    row.scale_y = 1.2
    split = row.split(factor=0.68, align=True)
    split.operator("shlight.compute_from_world", icon="WORLD")
    split.operator("shlight.reset", icon="LOOP_BACK")

    if world_kind(context) == "procedural":
        row = layout.row(heading="Capture Width")
        row.prop(settings, "use_capture_width", text="")
        sub = row.row()
        sub.active = settings.use_capture_width
        sub.prop(settings, "capture_width", text="")

    choice_row(layout, settings, "apply_target", "Apply To")
    choice_row(layout, settings, "apply_mode", "Mode")
    row = layout.row(align=True)
    row.operator("shlight.apply", text="Apply", icon="MATERIAL")
    row.operator("shlight.remove", text="Remove", icon="X")
    column = layout.column(align=True)
    mode = resolve_mode(settings.apply_mode, scene.render.engine)
    if mode == "WORLD":
        lines = world_edit.status_lines(scene, settings.apply_mode)
    else:
        lines = notes.status_lines(scene, mode)
        if settings.apply_mode == "AUTO":
            label = "Keep BSDF, Shadows" if mode == "TRANSFER" else "Keep BSDF"
            lines.insert(0, ("INFO", f"Default here: {label}"))
    for icon, line in lines:
        column.label(text=line, icon=icon)
    beyond = beyond_selection(context)
    if beyond:
        column.label(text=BEYOND_LINE.format(count=len(beyond)), icon="INFO")
    shading = studio_preview(context)
    if shading is not None:
        column.label(text=PREVIEW_LINE, icon="ERROR")
        column.prop(shading, "use_scene_world", text="Preview with the Scene World")


def studio_preview(context):
    """The shading of a 3D Viewport in Material Preview whose studio HDRI lights the BSDFs of
    the scene's Keep BSDF materials on top of their SH light (it is not the scene's world),
    or None. The context's own viewport first, else one of the screen's. (Emission Only
    materials show their SH light alone there.)"""
    scene = context.scene
    if not any(materials.mode_of(m) == "KEEP_BSDF"
               for m in materials.materials_of(scene.objects)):
        return None
    spaces = [getattr(context, "space_data", None)]
    screen = getattr(context, "screen", None)
    for area in getattr(screen, "areas", ()):
        spaces.extend(space for space in area.spaces if space.type == "VIEW_3D")
    for space in spaces:
        shading = getattr(space, "shading", None) if getattr(space, "type", "") == "VIEW_3D" \
            else None
        if shading is not None and shading.type == "MATERIAL" and not shading.use_scene_world:
            return shading
    return None


def draw_presets_header(layout, context):
    """The presets popover in the panel header (``presets_ui.SHLIGHT_PT_presets``), labelled
    with the preset the scene's values come from, if any."""
    label = presets_ui.menu_label(context.scene)
    layout.emboss = "NONE"
    layout.popover(panel="SHLIGHT_PT_presets", icon="PRESET",
                   text="" if label == presets_ui.PRESETS_LABEL else label)


def draw_coefficients(layout, context):
    """One line per coefficient: name (tooltip: what it does), swatch, strength; R G B when
    the line is open."""
    scene = context.scene
    if not scene_data.has_coefficients(scene):
        wrapped(layout, context, "No coefficients yet: press Compute from World or load a "
                "preset (header menu)", icon="INFO")
        return
    if draw_problems(layout, context):
        return
    coeffs = scene_data.get_coefficients(scene)
    shown = getattr(context.window_manager, SHOW_CHANNELS, (False,) * 9)
    col = layout.column(align=True)
    for index, name in enumerate(COEFFICIENT_NAMES):
        row = col.row(align=True)
        split = row.split(factor=0.42, align=True)
        left = split.row(align=True)
        left.alignment = "LEFT"
        op = left.operator(
            SHLIGHT_OT_show_channels.bl_idname, text=SHORT_PHRASES[index],
            icon="DISCLOSURE_TRI_DOWN" if shown[index] else "DISCLOSURE_TRI_RIGHT",
            emboss=False)
        op.index = index
        right = split.row(align=True)
        right.template_icon(icon_value=previews.swatch(index, coeffs[index]).icon_id)
        # A label of its own: Blender titles a text-less field's tooltip with the property's
        # key ("sh_L10_gain"); with one, the tooltip is the description alone
        right.prop(scene, f'["{scene_data.GAIN_NAMES[index]}"]', text="×")
        if shown[index]:
            box = col.box().column(align=True)
            path = f'["{scene_data.PROPERTY_NAMES[index]}"]'
            for channel, letter in enumerate(CHANNELS):
                box.prop(scene, path, index=channel, text=letter)


class SHLIGHT_OT_show_channels(bpy.types.Operator):
    """Show or hide the R, G, B values of this coefficient"""

    bl_idname = "shlight.show_channels"
    bl_label = "Show Channels"
    bl_options = {"INTERNAL"}

    index: bpy.props.IntProperty(min=0, max=8, options={"SKIP_SAVE", "HIDDEN"})

    @classmethod
    def description(cls, context, props):
        """What the coefficient does now (``core.edits.describe_coefficients``) and the click."""
        text = f"{COEFFICIENT_NAMES[props.index]}: {COEFFICIENT_PHRASES[props.index]}"
        scene = context.scene
        if scene is not None and scene_data.has_coefficients(scene):
            try:
                text = describe_coefficients(scene_data.get_coefficients(scene),
                                             edits.luminance())[props.index]
            except ValueError:
                pass
        return f"{text}.\n{SWATCH_NOTE}.\nClick to show or hide its R, G, B values"

    def execute(self, context):
        shown = getattr(context.window_manager, SHOW_CHANNELS)
        shown[self.index] = not shown[self.index]
        for area in context.screen.areas if context.screen else ():
            area.tag_redraw()
        return {"FINISHED"}


class _SceneMixin:
    @classmethod
    def poll(cls, context):
        return context.scene is not None and hasattr(context.scene, "sh_lighting")


# Where the add-on shows itself: World Properties and the 3D Viewport sidebar.
LOCATIONS = {
    "world": {"bl_space_type": "PROPERTIES", "bl_region_type": "WINDOW", "bl_context": "world"},
    "view3d": {"bl_space_type": "VIEW_3D", "bl_region_type": "UI", "bl_category": "SH Lighting"},
}


def _panel(name, label, draw, parent=None, options=(), header_preset=None):
    """One Panel class per location, ``SHLIGHT_PT_<location>[_<name>]``, drawing ``draw``."""
    panels = []
    for where, settings in LOCATIONS.items():
        attributes = {"bl_label": label, "bl_options": set(options), **settings,
                      "draw": lambda self, context: draw(self.layout, context)}
        if header_preset is not None:
            attributes["draw_header_preset"] = (
                lambda self, context: header_preset(self.layout, context))
        if parent is not None:
            attributes["bl_parent_id"] = f"SHLIGHT_PT_{where}"
        suffix = f"_{name}" if name else ""
        panels.append(type(f"SHLIGHT_PT_{where}{suffix}", (_SceneMixin, bpy.types.Panel), attributes))
    return tuple(panels)


def sub_panels(name, label, draw, options=()):
    """A sub-panel ``label`` under each main panel, sharing ``draw(layout, context)``."""
    return _panel(name, label, draw, parent=True, options=options)


SHLIGHT_PT_world, SHLIGHT_PT_view3d = _panel(
    "", "SH Lighting", draw_main, header_preset=draw_presets_header)
SHLIGHT_PT_world_coefficients, SHLIGHT_PT_view3d_coefficients = sub_panels(
    "coefficients", "Coefficients", draw_coefficients
)

classes = (
    SHLIGHT_OT_show_channels,
    SHLIGHT_OT_repair,
    SHLIGHT_PT_world,
    SHLIGHT_PT_world_coefficients,
    SHLIGHT_PT_view3d,
    SHLIGHT_PT_view3d_coefficients,
)
_register_classes, _unregister_classes = bpy.utils.register_classes_factory(classes)


def register():
    setattr(bpy.types.WindowManager, SHOW_CHANNELS, bpy.props.BoolVectorProperty(
        name="Show Channels", description="Which coefficients show their R, G, B values",
        size=9, options=set()))
    _register_classes()


def unregister():
    _unregister_classes()
    delattr(bpy.types.WindowManager, SHOW_CHANNELS)
