"""Extract Lights in the UI: the operator and a small draw function for the panel."""

import bpy

from ...core.lights import LARGEST_RADIUS, MAX_COUNT
from ..design import lights
from .. import world_edit
from .polls import world_poll


class SHLIGHT_OT_extract_lights(bpy.types.Operator):
    """Take the world image's compact bright sources (sun, windows, softboxes) out as Sun
    lights and keep the rest of the world as SH lighting (one light: the sun; earlier
    extracted lights are updated or deleted, never doubled, and lights you made or duplicated
    are never touched)"""

    bl_idname = "shlight.extract_lights"
    bl_label = "Extract Lights"
    bl_options = {"REGISTER", "UNDO"}

    count: bpy.props.IntProperty(
        name="Lights", default=MAX_COUNT, min=0, max=MAX_COUNT,
        description="Largest number of lights to extract (with Error Target on, fewer when "
        "fewer are enough)")
    use_error_target: bpy.props.BoolProperty(
        name="Error Target", default=True,
        description="Stop once SH + lights are within the error target of the world: as many "
        "lights as the world needs (one sun makes one light)")
    error_target: bpy.props.FloatProperty(
        name="Target", default=100.0 * lights.ERROR_TARGET, min=0.01, max=10.0,
        subtype="PERCENTAGE",
        description="Mean error of SH + lights against the world's irradiance, % of its light")
    size_limit: bpy.props.FloatProperty(
        name="Size Limit", default=lights.SIZE_LIMIT, min=0.02, max=2.0 * LARGEST_RADIUS,
        subtype="ANGLE",
        description="Largest source taken out as a light, across; larger ones (a big window, "
        "a sky) stay in the SH lighting")

    @classmethod
    def poll(cls, context):
        return world_poll(cls, context)

    def invoke(self, context, event):
        return context.window_manager.invoke_props_dialog(self)

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.prop(self, "count")
        layout.prop(self, "use_error_target")
        row = layout.row()
        row.active = self.use_error_target  # the target counts only with Error Target on
        row.prop(self, "error_target")
        layout.prop(self, "size_limit")

    def execute(self, context):
        target = self.error_target / 100.0 if self.use_error_target else None
        try:
            info = lights.extract_lights(context.scene, self.count, target, self.size_limit)
        except (LookupError, ValueError) as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        message = info.report()
        try:
            refreshed = world_edit.refresh(context.scene)
        except ValueError as error:
            self.report({"WARNING"}, f"{message}; World Edit taken out: {error}")
            return {"FINISHED"}
        self.report({"INFO"}, f"{message}; {refreshed}" if refreshed else message)
        return {"FINISHED"}


def draw_lights(layout):
    """The Extract Lights button (for the Design panel)."""
    layout.operator("shlight.extract_lights", icon="LIGHT_SUN")


classes = (SHLIGHT_OT_extract_lights,)
register, unregister = bpy.utils.register_classes_factory(classes)
