"""Measured luminaires in the UI: Add > Light > Measured Luminaire, refit, remove, the panel."""

import dataclasses

import bpy
from bpy_extras.io_utils import ImportHelper

from ...core.sh import COEFFICIENT_NAMES
from ..data import scene_data
from ..luminaire import build
from . import previews
from .polls import scene_poll

NOT_OURS = "Select a measured luminaire made by Add > Light > Measured Luminaire"


class _FitSettingsMixin:
    """The fit's settings, shared by Add and Refit."""

    error_target: bpy.props.FloatProperty(
        name="Error Target", default=3.0, min=0.1, max=50.0, subtype="PERCENTAGE",
        description="Relative RMS error of the intensity over the sphere at which the EEVEE "
        "fit stops adding lamps")
    max_lamps: bpy.props.IntProperty(
        name="Lamps", default=8, min=1, max=8,
        description="Most EEVEE lamps (spot and point lights) the fit may use")
    check_distance: bpy.props.FloatProperty(
        name="Check Distance", default=2.0, min=0.01, soft_max=20.0, unit="LENGTH",
        description="Distance of the floor and walls around the luminaire whose illuminance error "
        "(EEVEE lamps against the file) the panel shows")
    near_distance: bpy.props.FloatProperty(
        name="Near Field Distance", default=0.0, min=0.0, soft_max=10.0, unit="LENGTH",
        description="Distance from the luminaire to the nearest surface it lights. Closer than "
        "5 times the luminous opening, the opening is split into cells (at most 4 x 4), each "
        "with its own copy of the lamps (more EEVEE lamps, more shadow maps). 0: far field, "
        "one set")

    def fit_settings(self):
        return build.FitSettings(self.error_target / 100.0, self.max_lamps, self.check_distance,
                                 self.near_distance)


class SHLIGHT_OT_add_luminaire(bpy.types.Operator, ImportHelper, _FitSettingsMixin):
    """Add a measured luminaire from an IES or EULUMDAT file: exact in Cycles (Blender's IES
    node), a few fitted spot and point lights in EEVEE, with shadows in both"""

    bl_idname = "shlight.add_luminaire"
    bl_label = "Measured Luminaire"
    bl_options = {"REGISTER", "UNDO"}

    filter_glob: bpy.props.StringProperty(default="*.ies;*.IES;*.ldt;*.LDT", options={"HIDDEN"})

    @classmethod
    def poll(cls, context):
        return scene_poll(cls, context)

    def execute(self, context):
        try:
            info = build.add_luminaire(
                context.scene, self.filepath, collection=context.collection,
                location=tuple(context.scene.cursor.location), settings=self.fit_settings())
        except ValueError as error:  # PhotometryError too: one line, nothing created
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        for obj in context.selected_objects:
            obj.select_set(False)
        info.root.select_set(True)
        context.view_layer.objects.active = info.root
        self.report({"INFO"}, info.report())
        return {"FINISHED"}


def _luminaire_poll(cls, context):
    if not scene_poll(cls, context):
        return False
    if not build.is_luminaire(context.scene, context.object):
        cls.poll_message_set(NOT_OURS)
        return False
    return True


class SHLIGHT_OT_refit_luminaire(bpy.types.Operator, _FitSettingsMixin):
    """Fit the luminaire's EEVEE lamps again with another error target, lamp count or check
    distance (the Cycles light does not change)"""

    bl_idname = "shlight.refit_luminaire"
    bl_label = "Refit EEVEE Lamps"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return _luminaire_poll(cls, context)

    def invoke(self, context, event):
        info = context.object.data.get(build.INFO, {})
        self.error_target = 100.0 * info.get("error_target", 0.03)
        self.max_lamps = info.get("max_lamps", 8)
        self.check_distance = info.get("check_distance", 2.0)
        self.near_distance = info.get("near_distance", 0.0)
        return context.window_manager.invoke_props_dialog(self)

    def execute(self, context):
        try:
            info = build.refit(context.scene, context.object, self.fit_settings())
        except ValueError as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        self.report({"INFO"}, info.report())
        return {"FINISHED"}


class SHLIGHT_OT_luminaire_near_from_scene(bpy.types.Operator):
    """Set Near Field Distance to the distance from the luminaire, along its axis, to the first
    surface below it, and fit again (the near field's cells if that surface is close)"""

    bl_idname = "shlight.luminaire_near_from_scene"
    bl_label = "Near Field from Scene"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return _luminaire_poll(cls, context)

    def execute(self, context):
        root = context.object
        distance = build.lit_distance(context.scene, root)
        if distance is None:
            self.report({"WARNING"}, f"No surface along '{root.name}''s axis: it keeps its "
                                     "Near Field Distance")
            return {"CANCELLED"}
        settings = build.settings_of(root)
        try:
            info = build.refit(context.scene, root, dataclasses.replace(
                settings, near_distance=round(distance, 3)))
        except ValueError as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        self.report({"INFO"}, f"Near Field Distance {distance:.3f} m (the surface along the "
                              f"axis); {info.report()}")
        return {"FINISHED"}


class SHLIGHT_OT_remove_luminaire(bpy.types.Operator):
    """Delete this measured luminaire: its light, EEVEE lamps and packed IES text (copies
    you made are kept)"""

    bl_idname = "shlight.remove_luminaire"
    bl_label = "Remove Luminaire"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return _luminaire_poll(cls, context)

    def execute(self, context):
        name = context.object.name
        build.remove_luminaire(context.scene, context.object)
        self.report({"INFO"}, f"Removed measured luminaire '{name}'")
        return {"FINISHED"}


class SHLIGHT_OT_luminaire_temperature(bpy.types.Operator):
    """Colour the luminaire as a blackbody at a temperature, in Cycles and EEVEE (Blender's
    Light Temperature where it has one, else the colour)"""

    bl_idname = "shlight.luminaire_temperature"
    bl_label = "Colour Temperature"
    bl_options = {"REGISTER", "UNDO"}

    kelvin: bpy.props.FloatProperty(
        name="Temperature", default=3000.0, min=build.TEMPERATURE_RANGE[0],
        max=build.TEMPERATURE_RANGE[1], subtype="TEMPERATURE" if bpy.app.version >= (4, 0, 0)
        else "NONE", description="Blackbody temperature in kelvin (2700 warm, 6500 daylight)")

    @classmethod
    def poll(cls, context):
        return _luminaire_poll(cls, context)

    def execute(self, context):
        try:
            build.set_colour_temperature(context.object, float(self.kelvin))
        except ValueError as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        context.object.data.update_tag()
        return {"FINISHED"}


def draw_nine(layout, context, root):
    """The scene's nine beside the ones the luminaire adds at the 3D cursor (R G B)."""
    scene = context.scene
    try:
        own = build.luminaire_sh_at(scene, root, tuple(scene.cursor.location))
    except ValueError as error:
        layout.label(text=str(error), icon="ERROR")
        return
    try:
        ours = scene_data.get_coefficients(scene)
    except (LookupError, ValueError):
        ours = None
    col = layout.column(align=True)
    col.label(text="SH at the 3D cursor (R G B): scene | this luminaire adds")
    for index, name in enumerate(COEFFICIENT_NAMES):
        row = col.row(align=True)
        split = row.split(factor=0.14)
        split.label(text=name)
        split = split.split(factor=0.5)
        split.label(text=" ".join(f"{v:.3g}" for v in ours[index]) if ours is not None else "-")
        split.label(text=" ".join(f"{v:.3g}" for v in own[index]))


def draw_near_field(layout, info):
    """The near field's cells, or the distance under which it would start."""
    cells = info.get("cells", (1, 1))
    size = max((abs(v) for v in info.get("opening_m", (0.0, 0.0))[:2]), default=0.0)
    if cells[0] * cells[1] > 1:
        layout.label(text=f"Near field: {cells[0]} x {cells[1]} cells for surfaces "
                          f"{info.get('near_distance', 0):.2f} m away, each lamp copied per cell")
    elif size > 0:
        layout.label(text=f"Far field: surfaces closer than {5 * size:.2f} m (5 x its "
                          f"{size:.2f} m opening) need Near Field Distance (Refit, or Near "
                          "Field from Scene)")


class SHLIGHT_PT_luminaire(bpy.types.Panel):
    """The luminaire's file, flux, fit errors and SH coefficients (Light properties)."""

    bl_label = "Measured Luminaire"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "data"

    @classmethod
    def poll(cls, context):
        return (context.scene is not None and context.object is not None
                and context.object.type == "LIGHT"
                and build.is_luminaire(context.scene, context.object))

    def draw(self, context):
        layout = self.layout
        light = context.object.data
        info = light.get(build.INFO, {})
        col = layout.column(align=True)
        col.label(text=f"File: {info.get('source', '?')}", icon="FILE")
        col.label(text=f"Flux {info.get('flux_lm', 0):.0f} lm, peak {info.get('peak_cd', 0):.0f} cd")
        layout.prop(light, "energy", text="Intensity (1 W = the file's candela)")
        layout.prop(light, "color")
        row = layout.row(align=True)
        if hasattr(light, "temperature"):  # Blender 5.0: the lamps follow it by drivers
            row.prop(light, "use_temperature", text="")
            sub = row.row(align=True)
            sub.active = light.use_temperature
            sub.prop(light, "temperature")
        else:
            row.operator(SHLIGHT_OT_luminaire_temperature.bl_idname, icon="LIGHT_SUN")
        box = layout.box()
        box.label(text=f"EEVEE: {info.get('lamps', 0)} lamp(s), Cycles: the IES node (exact)")
        draw_near_field(box, info)
        box.operator(SHLIGHT_OT_luminaire_near_from_scene.bl_idname, icon="DRIVER_DISTANCE")
        box.label(text=f"Intensity error {100 * info.get('intensity_error', 0):.1f} % "
                       "(relative RMS over the sphere)")
        distance = info.get("check_distance", 0)
        box.label(text=f"Illuminance error {100 * info.get('plane_error', 0):.1f} % on a floor, "
                       f"{100 * info.get('wall_error', 0):.1f} % on walls {distance:.2f} m away")
        curves = build.polar_of(context.object)
        if curves is not None:
            try:
                icon = previews.polar(context.object.name, *curves).icon_id
            except (RuntimeError, ValueError) as error:  # not registered, bad stored curves
                box.label(text=str(error), icon="ERROR")
            else:
                box.template_icon(icon_value=icon, scale=8.0)
                box.label(text="Polar: red C0-C180, blue C90-C270; thick the file, "
                               "thin the EEVEE lamps")
        row = layout.row(align=True)
        row.operator(SHLIGHT_OT_refit_luminaire.bl_idname, icon="FILE_REFRESH")
        row.operator(SHLIGHT_OT_remove_luminaire.bl_idname, icon="TRASH")
        draw_nine(layout, context, context.object)


def draw_add_menu(self, context):
    self.layout.operator(SHLIGHT_OT_add_luminaire.bl_idname, icon="LIGHT_SPOT")


classes = (SHLIGHT_OT_add_luminaire, SHLIGHT_OT_refit_luminaire,
           SHLIGHT_OT_luminaire_near_from_scene, SHLIGHT_OT_remove_luminaire,
           SHLIGHT_OT_luminaire_temperature, SHLIGHT_PT_luminaire)
_register_classes, _unregister_classes = bpy.utils.register_classes_factory(classes)


def register():
    _register_classes()
    bpy.types.VIEW3D_MT_light_add.append(draw_add_menu)  # Add > Light


def unregister():
    bpy.types.VIEW3D_MT_light_add.remove(draw_add_menu)
    _unregister_classes()
