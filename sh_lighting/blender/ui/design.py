"""Lighting design in the UI: rotate the light, change its exposure and colour, tame ringing,
take lights out of the world (Extract Lights, ``ui.lights``), see the basis.

Operators (all undoable, with polls that say why they are disabled) hand plain values to
``design`` and turn its errors into an ERROR report with nothing changed. Rotate, Exposure,
Saturation and Band Gains run at once with values that change nothing (``IDENTITY``; the
values are not remembered from the last use) and open Blender's Adjust Last Operation popup
(F9): every change of a value redoes the edit (undo and execute), so one use is one undo
step. (``invoke_props_popup`` pushed a step of its own before the first change: two "Rotate
Lighting" in Undo History per rotate.) The "Design" sub-panel holds the buttons; the "Basis Functions" sub-panel (closed
by default) the paper's figure 4. The irradiance sphere is at the top of the main panel.
"""

import math

import bpy

from ...core.minimum import negative_light_warning
from ..data import scene_data
from ..design import edits
from ..world import reader
from . import lights as lights_ui
from . import panels, previews
from .polls import NO_COEFFICIENTS, coefficients_poll, scene_poll

# Drag step of the angles, as Blender's own Rotation fields: 1° per pixel dragged (the default
# step, 3, turned 0.03° per pixel: 150 px, 3.9° in a 4.3 window)
ANGLE_STEP = 100
BASIS_SCALE = 3.0  # largest icon size, in UI units; smaller when 5 do not fit the width


class _Edit:
    """Mixin: runs ``self.apply(scene)`` (the edit's stored values) and reports
    ``self.message(result)`` with the store's note; design errors become an ERROR report,
    nothing changed."""

    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return coefficients_poll(cls, context)

    def message(self, result):
        return ""

    def execute(self, context):
        try:
            result = self.apply(context.scene)
        except (LookupError, ValueError) as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        note = getattr(result, "coefficients", result).note  # a key over an animated value
        parts = (self.message(result), note and f"SH lighting {note}")
        message = "; ".join(part for part in parts if part)
        if message:
            self.report({"INFO"}, message)
        return {"FINISHED"}


class _Live:
    """Mixin: from a button, run with the ``IDENTITY`` values (those not given), then the
    Adjust Last Operation popup, whose every change redoes the edit at once (the Properties
    editor has no redo panel); scripts calling with EXEC_DEFAULT run at once."""

    IDENTITY = {}

    def invoke(self, context, _event):
        for name, value in self.IDENTITY.items():
            if not self.properties.is_property_set(name):
                setattr(self, name, value)
        result = self.execute(context)
        if result == {"FINISHED"}:
            adjust_after(context)
        return result


def adjust_after(context):
    """Open Adjust Last Operation (F9) where ``context`` is, once the operator running now has
    finished (a timer: the next turn of the event loop); nothing without a window."""
    window, area, region = context.window, context.area, context.region
    if window is None or area is None:
        return

    def popup():
        try:
            with bpy.context.temp_override(window=window, area=area, region=region):
                bpy.ops.screen.redo_last("INVOKE_DEFAULT")
        except (RuntimeError, ReferenceError, TypeError):  # the area closed meanwhile
            pass
        return None

    bpy.app.timers.register(popup, first_interval=0.0)


class SHLIGHT_OT_rotate(_Live, _Edit, bpy.types.Operator):
    """Rotate the SH lighting exactly (band by band) by yaw, pitch and roll"""

    bl_idname = "shlight.rotate"
    bl_label = "Rotate Lighting"
    IDENTITY = {"yaw": 0.0, "pitch": 0.0, "roll": 0.0}

    yaw: bpy.props.FloatProperty(
        name="Yaw", description="Turn about the vertical +Z axis (+90° takes +X to +Y)",
        subtype="ANGLE", soft_min=-math.tau, soft_max=math.tau, step=ANGLE_STEP,
        options={"SKIP_SAVE"},
    )
    pitch: bpy.props.FloatProperty(
        name="Pitch", description="Turn about +X (+90° takes +Y to +Z), before the yaw",
        subtype="ANGLE", soft_min=-math.tau, soft_max=math.tau, step=ANGLE_STEP,
        options={"SKIP_SAVE"},
    )
    roll: bpy.props.FloatProperty(
        name="Roll", description="Turn about +Y (+90° takes +Z to +X), before the pitch",
        subtype="ANGLE", soft_min=-math.tau, soft_max=math.tau, step=ANGLE_STEP,
        options={"SKIP_SAVE"},
    )

    def apply(self, scene):
        return edits.rotate(scene, self.yaw, self.pitch, self.roll)


def mapping_problem(context):
    """Why Match Mapping can only fail here (a sentence), or None when it can work."""
    if not scene_data.has_coefficients(context.scene):
        return NO_COEFFICIENTS
    try:
        source = panels.read_world(context)
    except ValueError as why:  # WorldError: no world, no image, ...
        return str(why)
    if isinstance(source, reader.ProceduralSource):
        return f"Needs an Environment Texture world image; {source.reason}"
    if source.rotation is None:
        return (f"World '{source.world}' has no Texture Coordinate → Mapping in front of its "
                "Environment Texture: no rotation to match")
    return None


class SHLIGHT_OT_match_mapping(_Edit, bpy.types.Operator):
    """Rotate the SH lighting by the world's Mapping node rotation, as Blender renders it:
    for coefficients computed from the image without that rotation"""

    bl_idname = "shlight.match_mapping"
    bl_label = "Match Mapping"

    @classmethod
    def poll(cls, context):
        if not scene_poll(cls, context):
            return False
        problem = mapping_problem(context)
        if problem:
            cls.poll_message_set(problem)
            return False
        return True

    def apply(self, scene):
        return edits.match_mapping(scene)

    def message(self, result):
        return "SH lighting rotated by the world's Mapping node rotation"


class SHLIGHT_OT_exposure(_Live, _Edit, bpy.types.Operator):
    """Make the SH lighting brighter or darker by photographic stops (×2 per stop)"""

    bl_idname = "shlight.exposure"
    bl_label = "Exposure"
    IDENTITY = {"stops": 0.0}

    stops: bpy.props.FloatProperty(
        name="Stops", description="Brightness change in stops: +1 doubles the light",
        default=0.0, soft_min=-4.0, soft_max=4.0, step=10, options={"SKIP_SAVE"},
    )

    def apply(self, scene):
        return edits.exposure(scene, self.stops)


class SHLIGHT_OT_saturation(_Live, _Edit, bpy.types.Operator):
    """Blend the colour of the SH lighting toward grey (or away from it), keeping its
    brightness"""

    bl_idname = "shlight.saturation"
    bl_label = "Saturation"
    IDENTITY = {"amount": 1.0}

    amount: bpy.props.FloatProperty(
        name="Amount", description="0 grey, 1 unchanged, above 1 more colourful",
        default=0.5, soft_min=0.0, soft_max=2.0, subtype="FACTOR", options={"SKIP_SAVE"},
    )
    band: bpy.props.EnumProperty(
        name="Bands",
        description="Which coefficients change colour",
        items=(
            ("ALL", "All", "Every coefficient"),
            ("AMBIENT", "Ambient", "Only L00 (l = 0): the overall tint"),
            ("DIRECTIONAL", "Directional", "Only l = 1: the colour of the main light direction"),
            ("QUADRATIC", "Quadratic", "Only l = 2"),
            ("COLOURED", "Directional and Quadratic",
             "l = 1 and 2: keep the ambient tint, change the directional colour"),
        ),
        default="ALL",
    )

    def apply(self, scene):
        return edits.saturation(scene, self.amount, self.band)


class SHLIGHT_OT_band_gains(_Live, _Edit, bpy.types.Operator):
    """Scale the ambient (l = 0), directional (l = 1) and quadratic (l = 2) terms of the
    lighting separately"""

    bl_idname = "shlight.band_gains"
    bl_label = "Band Gains"
    IDENTITY = {"ambient": 1.0, "directional": 1.0, "quadratic": 1.0}

    ambient: bpy.props.FloatProperty(
        name="Ambient", description="Gain of L00 (l = 0): the mean light",
        default=1.0, soft_min=0.0, soft_max=4.0, options={"SKIP_SAVE"},
    )
    directional: bpy.props.FloatProperty(
        name="Directional", description="Gain of l = 1: the difference between opposite sides",
        default=1.0, soft_min=0.0, soft_max=4.0, options={"SKIP_SAVE"},
    )
    quadratic: bpy.props.FloatProperty(
        name="Quadratic", description="Gain of l = 2: the finer shape (poles vs horizon, ...)",
        default=1.0, soft_min=0.0, soft_max=4.0, options={"SKIP_SAVE"},
    )

    def apply(self, scene):
        return edits.band_gains(scene, self.ambient, self.directional, self.quadratic)


class SHLIGHT_OT_flip_vertical(_Edit, bpy.types.Operator):
    """Mirror the lighting top to bottom: what came from above comes from below, and back
    again on a second click"""

    bl_idname = "shlight.flip_vertical"
    bl_label = "Flip Vertically"

    def apply(self, scene):
        return edits.flip_vertical(scene)


# The smoothing buttons, in an artist's words from least to most (the paper's windows in their
# tooltips): Lanczos damps less than Hanning at the same width (l = 2: 0.41 vs 0.25).
SMOOTHING_ORDER = ("MINIMAL", "LANCZOS", "HANNING")
SMOOTHING_LABELS = {"MINIMAL": "Just Enough", "LANCZOS": "Gentle", "HANNING": "Strong"}
SMOOTHING_TIPS = {
    "MINIMAL": "Just Enough: the least smoothing that leaves no negative light (the minimal "
               "non-negative window)",
    "LANCZOS": "Gentle: softens the lighting's rings a little (a Lanczos window, w_l = "
               "sinc(l / 3))",
    "HANNING": "Strong: softens them more (a Hanning window, w_l = (1 + cos(π l / 3)) / 2)",
}


class SHLIGHT_OT_window(_Edit, bpy.types.Operator):
    """Smooth the SH lighting to tame ringing (negative light behind a bright source); reports
    what it costs against the world image"""

    bl_idname = "shlight.window"
    bl_label = "Window"

    kind: bpy.props.EnumProperty(
        name="Window",
        description="How the directional and quadratic bands are damped",
        items=(
            ("HANNING", "Hanning", "w_l = (1 + cos(π l / width)) / 2"),
            ("LANCZOS", "Lanczos", "w_l = sinc(l / width)"),
            ("MINIMAL", "Minimal Non-Negative",
             "The least smoothing that makes the irradiance non-negative for every normal"),
        ),
        default="MINIMAL",
    )
    width: bpy.props.FloatProperty(
        name="Width", description="Width of the Hanning and Lanczos windows (3: the usual L + 1)",
        default=edits.DEFAULT_WIDTH, min=0.01, soft_min=1.0, soft_max=10.0,
    )

    @classmethod
    def description(cls, context, props):
        """What the button does in words, then the paper's (the window and its formula); for
        Just Enough with negative light, the warning it removes (the panel's button)."""
        words = SMOOTHING_TIPS[props.kind]
        scene = context.scene
        if props.kind == "MINIMAL" and scene is not None and scene_data.has_coefficients(scene):
            try:
                warning = negative_light_warning(scene_data.get_coefficients(scene))
            except ValueError:
                warning = ""
            if warning:
                return (f"{warning}.\nClick: the least smoothing that makes the irradiance "
                        "non-negative for every normal")
        return f"{words}.\n{cls.bl_rna.description}"

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.prop(self, "kind")
        row = layout.row()
        row.active = self.kind != "MINIMAL"
        row.prop(self, "width")

    def apply(self, scene):
        return edits.apply_window(scene, self.kind, self.width)

    def message(self, result):
        return window_report(result)


def window_report(result):
    """One readable line about a ``edits.WindowResult``: the band factors and the error
    against the world image with and without the window, or why it is not shown."""
    w = result.window
    text = (f"Smoothing '{SMOOTHING_LABELS[result.kind]}' ({edits.LABELS[result.kind]} window) "
            f"applied: directional ×{w[1]:.2f}, quadratic ×{w[2]:.2f}")
    cost = result.cost
    if cost is not None:
        text += (f"; error vs the world image {100 * cost.windowed_mean.max():.1f} % of its "
                 f"light (without: {100 * cost.plain_mean.max():.1f} %)")
    elif result.note:
        text += f"; {result.note}"
    return text


# -- the Design and Basis Functions sub-panels ---------------------------------------------


def draw_basis(layout, context):
    """The 9 Y_lm as in figure 4: one row per band (l = 0, 1, 2), green positive, blue
    negative; the icons shrink together so that the five of l = 2 fit the panel."""
    region = getattr(context, "region", None)
    width = region.width if region is not None and region.width > 1 else 300
    unit = 20.0 * panels.ui_scale(context)
    scale = max(1.0, min(BASIS_SCALE, (width - 40) / (5 * unit) - 0.2))
    panels.wrapped(layout, context, "Rows l = 0, 1, 2 (L00; L1-1 L10 L11; L2-2 … L22): "
                   "green positive, blue negative")
    icons = previews.basis()
    col = layout.column(align=True)
    for band in range(3):
        row = col.row(align=True)
        row.alignment = "CENTER"
        for k in range(band * band, (band + 1) * (band + 1)):
            row.template_icon(icon_value=icons[k].icon_id, scale=scale)


def draw_design(layout, context):
    """The Design sub-panel (both places): the edit buttons."""
    col = layout.column(align=True)
    row = col.row(align=True)
    row.operator("shlight.rotate", text="Rotate", icon="ORIENTATION_GIMBAL")
    row.operator("shlight.match_mapping", icon="WORLD")
    row = col.row(align=True)
    row.operator("shlight.exposure", icon="LIGHT_SUN")
    row.operator("shlight.saturation", icon="COLOR")
    row = col.row(align=True)
    row.operator("shlight.band_gains")
    row.operator("shlight.flip_vertical", icon="MOD_MIRROR")

    col = layout.column(align=True)
    col.label(text="Smooth the lighting")
    row = col.row(align=True)
    for kind in SMOOTHING_ORDER:
        row.operator("shlight.window", text=SMOOTHING_LABELS[kind]).kind = kind
    lights_ui.draw_lights(layout.row(align=True))


SHLIGHT_PT_world_design, SHLIGHT_PT_view3d_design = panels.sub_panels(
    "design", "Design", draw_design, options={"DEFAULT_CLOSED"}
)
SHLIGHT_PT_world_basis, SHLIGHT_PT_view3d_basis = panels.sub_panels(
    "basis", "Basis Functions", draw_basis, options={"DEFAULT_CLOSED"}
)


classes = (
    SHLIGHT_OT_rotate,
    SHLIGHT_OT_match_mapping,
    SHLIGHT_OT_exposure,
    SHLIGHT_OT_saturation,
    SHLIGHT_OT_band_gains,
    SHLIGHT_OT_flip_vertical,
    SHLIGHT_OT_window,
    SHLIGHT_PT_world_design,
    SHLIGHT_PT_view3d_design,
    SHLIGHT_PT_world_basis,
    SHLIGHT_PT_view3d_basis,
)
_register_classes, _unregister_classes = bpy.utils.register_classes_factory(classes)


def register():
    previews.register()
    _register_classes()


def unregister():
    _unregister_classes()
    previews.unregister()
