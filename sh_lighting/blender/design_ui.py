"""Lighting design in the UI: see the basis, rotate the light, tame ringing, split off the sun.

Operators (all undoable, with polls that say why they are disabled) hand plain values to
``design`` and turn its errors into an ERROR report with nothing changed. The "Design"
sub-panel, under both SH Lighting panels, shows the 9 basis functions (the paper's figure 4)
and the irradiance sphere of the current coefficients (``previews``), the negative-light
warning, what each coefficient does, and the buttons.
"""

import math
import textwrap

import bpy

from ..core.edits import describe_coefficients
from ..core.minimum import negative_light_warning
from . import design, lights_ui, panels, previews, scene_data
from .polls import NO_COEFFICIENTS, coefficients_poll, scene_poll

WARNING_WIDTH = 44  # characters per line of the wrapped warning
BASIS_SCALE = 3.0
IRRADIANCE_SCALE = 7.0
BAND_LABELS = ("l = 0", "l = 1", "l = 2")


class _Edit:
    """Mixin: runs ``self.apply(scene)``; design errors become an ERROR report, nothing changed."""

    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return coefficients_poll(cls, context)

    def execute(self, context):
        try:
            message = self.apply(context.scene)
        except (LookupError, ValueError) as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        if message:
            self.report({"INFO"}, message)
        return {"FINISHED"}


class _Dialog:
    """Mixin: from a button, ask for the settings first (the Properties editor has no redo
    panel); scripts calling with EXEC_DEFAULT run at once."""

    def invoke(self, context, event):
        return context.window_manager.invoke_props_dialog(self)


class SHLIGHT_OT_rotate(_Dialog, _Edit, bpy.types.Operator):
    """Rotate the SH lighting exactly (band by band), by yaw, pitch and roll or by the world's
    Mapping node rotation"""

    bl_idname = "shlight.rotate"
    bl_label = "Rotate Lighting"

    mode: bpy.props.EnumProperty(
        name="Rotate By",
        description="Where the rotation comes from",
        items=(
            ("ANGLES", "Angles", "Yaw about +Z, then pitch about +X, then roll about +Y"),
            (
                "MAPPING",
                "Match Mapping Node",
                "The world's Mapping node rotation, as Blender renders it: for coefficients "
                "computed from the image without that rotation",
            ),
        ),
        default="ANGLES",
    )
    yaw: bpy.props.FloatProperty(
        name="Yaw", description="Turn about the vertical +Z axis (+90° takes +X to +Y)",
        subtype="ANGLE", soft_min=-math.tau, soft_max=math.tau,
    )
    pitch: bpy.props.FloatProperty(
        name="Pitch", description="Turn about +X (+90° takes +Y to +Z), before the yaw",
        subtype="ANGLE", soft_min=-math.tau, soft_max=math.tau,
    )
    roll: bpy.props.FloatProperty(
        name="Roll", description="Turn about +Y (+90° takes +Z to +X), before the pitch",
        subtype="ANGLE", soft_min=-math.tau, soft_max=math.tau,
    )

    def invoke(self, context, event):
        if self.mode == "MAPPING":
            return self.execute(context)
        return super().invoke(context, event)

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.prop(self, "mode")
        col = layout.column(align=True)
        col.active = self.mode == "ANGLES"
        for name in ("yaw", "pitch", "roll"):
            col.prop(self, name)

    def apply(self, scene):
        if self.mode == "MAPPING":
            design.match_mapping(scene)
            return "SH lighting rotated by the world's Mapping node rotation"
        design.rotate(scene, self.yaw, self.pitch, self.roll)
        return None


class SHLIGHT_OT_exposure(_Edit, bpy.types.Operator):
    """Make the SH lighting brighter or darker by photographic stops (×2 per stop)"""

    bl_idname = "shlight.exposure"
    bl_label = "Exposure"

    stops: bpy.props.FloatProperty(
        name="Stops", description="Brightness change in stops: +1 doubles the light",
        default=1.0, soft_min=-10.0, soft_max=10.0, step=50,
    )

    def apply(self, scene):
        design.exposure(scene, self.stops)


class SHLIGHT_OT_saturation(_Dialog, _Edit, bpy.types.Operator):
    """Blend the colour of the SH lighting toward grey (or away from it), keeping its
    brightness"""

    bl_idname = "shlight.saturation"
    bl_label = "Saturation"

    amount: bpy.props.FloatProperty(
        name="Amount", description="0 grey, 1 unchanged, above 1 more colourful",
        default=0.5, soft_min=0.0, soft_max=2.0, subtype="FACTOR",
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
        design.saturation(scene, self.amount, self.band)


class SHLIGHT_OT_band_gains(_Dialog, _Edit, bpy.types.Operator):
    """Scale the ambient (l = 0), directional (l = 1) and quadratic (l = 2) terms of the
    lighting separately"""

    bl_idname = "shlight.band_gains"
    bl_label = "Band Gains"

    ambient: bpy.props.FloatProperty(
        name="Ambient", description="Gain of L00 (l = 0): the mean light",
        default=1.0, soft_min=0.0, soft_max=4.0,
    )
    directional: bpy.props.FloatProperty(
        name="Directional", description="Gain of l = 1: the difference between opposite sides",
        default=1.0, soft_min=0.0, soft_max=4.0,
    )
    quadratic: bpy.props.FloatProperty(
        name="Quadratic", description="Gain of l = 2: the finer shape (poles vs horizon, ...)",
        default=1.0, soft_min=0.0, soft_max=4.0,
    )

    def apply(self, scene):
        design.band_gains(scene, self.ambient, self.directional, self.quadratic)


class SHLIGHT_OT_flip_vertical(_Edit, bpy.types.Operator):
    """Mirror the SH lighting top to bottom: lit from below instead of above"""

    bl_idname = "shlight.flip_vertical"
    bl_label = "Lit from Below"

    def apply(self, scene):
        design.flip_vertical(scene)


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
        default=design.DEFAULT_WIDTH, min=0.01, soft_min=1.0, soft_max=10.0,
    )

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.prop(self, "kind")
        row = layout.row()
        row.active = self.kind != "MINIMAL"
        row.prop(self, "width")

    def apply(self, scene):
        return design.apply_window(scene, self.kind, self.width).report()


class SHLIGHT_OT_split_sun(_Edit, bpy.types.Operator):
    """Take the sun out of the world image as a Sun light (direction, size, colour, strength)
    and keep the rest of the world as SH lighting"""

    bl_idname = "shlight.split_sun"
    bl_label = "Split Sun"

    @classmethod
    def poll(cls, context):
        if not scene_poll(cls, context):
            return False
        if context.scene.world is None:
            cls.poll_message_set("The scene has no world: give it an HDR image first")
            return False
        return True

    def apply(self, scene):  # WorldError and DesignError are ValueErrors: _Edit reports them
        info = design.split_sun(scene)
        if info is None:
            return "No sun found in the world image: nothing changed"
        d = ", ".join(f"{v:+.3f}" for v in info.direction)
        verb = "created" if info.created else "updated"
        return (
            f"Sun light '{info.light}' {verb}: toward ({d}), {info.strength:.4g} W/m², "
            f"{info.power_fraction:.0%} of the world's light; the coefficients hold the rest"
        )


# -- the Design sub-panel ----------------------------------------------------------------------


def draw_basis(layout):
    """The 9 Y_lm as in figure 4: one row per band, green positive, blue negative."""
    col = layout.column(align=True)
    col.label(text="Basis functions (green +, blue −)")
    icons = previews.basis()
    for band, label in enumerate(BAND_LABELS):
        row = col.row(align=True)
        row.alignment = "CENTER"
        for k in range(band * band, (band + 1) * (band + 1)):
            row.template_icon(icon_value=icons[k].icon_id, scale=BASIS_SCALE)
        row.label(text=label)


def draw_lighting(layout, scene):
    """The irradiance sphere, the negative-light warning and the words for each coefficient."""
    coeffs = scene_data.get_coefficients(scene)
    col = layout.column(align=True)
    col.label(text="White sphere, front view, Film exposure")
    preview = previews.irradiance(coeffs, scene.view_settings.exposure)
    col.template_icon(icon_value=preview.icon_id, scale=IRRADIANCE_SCALE)
    warning = negative_light_warning(coeffs)  # design.negative_warning, without a 2nd read
    if warning:
        box = layout.box().column(align=True)
        for i, line in enumerate(textwrap.wrap(warning, WARNING_WIDTH)):
            box.label(text=line, icon="ERROR" if i == 0 else "BLANK1")
    col = layout.column(align=True)
    for line in describe_coefficients(coeffs, design.luminance()):  # design.describe
        col.label(text=line)


def draw_buttons(layout):
    col = layout.column(align=True)
    row = col.row(align=True)
    row.operator("shlight.rotate", text="Rotate", icon="ORIENTATION_GIMBAL").mode = (
        "ANGLES"
    )
    row.operator("shlight.rotate", text="Match Mapping", icon="WORLD").mode = "MAPPING"
    row = col.row(align=True)
    row.operator("shlight.exposure", text="−1 Stop").stops = -1.0
    row.operator("shlight.exposure", text="+1 Stop").stops = 1.0
    row = col.row(align=True)
    row.operator("shlight.saturation", icon="COLOR")
    row.operator("shlight.band_gains")
    col.operator("shlight.flip_vertical", icon="MOD_MIRROR")

    col = layout.column(align=True)
    col.label(text="Tame ringing")
    row = col.row(align=True)
    for kind in design.WINDOWS:
        row.operator("shlight.window", text=design.LABELS[kind]).kind = kind
    row = layout.row(align=True)
    row.operator("shlight.split_sun", icon="LIGHT_SUN")
    lights_ui.draw_lights(row)


def draw_design(layout, context):
    """The Design sub-panel (both places): previews, warning, words, buttons."""
    scene = context.scene
    draw_basis(layout)
    if scene_data.has_coefficients(scene):
        try:
            draw_lighting(layout, scene)
        except ValueError as error:  # e.g. coefficients typed in as NaN
            layout.label(text=str(error), icon="ERROR")
    else:
        layout.label(text=NO_COEFFICIENTS, icon="INFO")
    draw_buttons(layout)


SHLIGHT_PT_world_design, SHLIGHT_PT_view3d_design = panels.sub_panels(
    "design", "Design", draw_design, options={"DEFAULT_CLOSED"}
)


classes = (
    SHLIGHT_OT_rotate,
    SHLIGHT_OT_exposure,
    SHLIGHT_OT_saturation,
    SHLIGHT_OT_band_gains,
    SHLIGHT_OT_flip_vertical,
    SHLIGHT_OT_window,
    SHLIGHT_OT_split_sun,
    SHLIGHT_PT_world_design,
    SHLIGHT_PT_view3d_design,
)
_register_classes, _unregister_classes = bpy.utils.register_classes_factory(classes)


def register():
    previews.register()
    _register_classes()


def unregister():
    _unregister_classes()
    previews.unregister()

