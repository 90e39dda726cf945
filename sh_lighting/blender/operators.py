"""Operators: Compute from World, Reset, Apply, Remove, Refit.

Each operator reads the context once, hands plain values (scene, materials, widths) to the
logic in ``world``, ``scene_data`` and ``materials``, and turns their exceptions into an
ERROR report and {'CANCELLED'} with nothing changed. All are undoable and work in background
mode (``bpy.ops.shlight.compute_from_world()``); polls say why a button is disabled.
"""

import time

import bpy

from . import materials, nodes, properties, scene_data, world_cache
from .polls import coefficients_poll, scene_poll


def objects_for_target(context, target):
    """The objects Apply and Remove act on: the selected ones, or every object of the scene."""
    if target == "SELECTED":
        return list(context.selected_objects or ())
    return list(context.scene.objects)


def materials_of(objects):
    """The distinct materials in the material slots of ``objects``, in slot order."""
    found = {}
    for obj in objects:
        for slot in getattr(obj, "material_slots", ()):
            if slot.material is not None:
                found.setdefault(slot.material.name_full, slot.material)
    return list(found.values())


def _skip_reasons(result, limit=3):
    """Up to ``limit`` "material: reason" strings of a ``materials.Result``."""
    return [f"{name}: {reason}" for name, reason in result.skipped[:limit]]


def _target_poll(cls, context):
    """Shared poll of Apply and Remove: a scene with settings and something to act on."""
    if not scene_poll(cls, context):
        return False
    scene = context.scene
    target = scene.sh_lighting.apply_target
    if target == "SELECTED" and not context.selected_objects:
        cls.poll_message_set("No objects selected: select objects or set Apply To to All")
        return False
    if target == "ALL" and not len(scene.objects):
        cls.poll_message_set("The scene has no objects")
        return False
    return True


class SHLIGHT_OT_compute_from_world(bpy.types.Operator):
    """Compute the 9 SH lighting coefficients from the scene's world (image or procedural)"""

    bl_idname = "shlight.compute_from_world"
    bl_label = "Compute from World"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return scene_poll(cls, context)

    def execute(self, context):
        start = time.perf_counter()
        try:
            _coeffs, info = world_cache.compute_and_store(context.scene)
        except ValueError as error:  # WorldError and invalid coefficients
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        elapsed = time.perf_counter() - start
        if info.cached:
            self.report(
                {"INFO"}, f"SH lighting reused: world '{info.world}' has not changed since it "
                "was last computed"
            )
            return {"FINISHED"}
        origin = "the world image" if info.source == "image" else "a capture of the world"
        self.report({"INFO"}, f"SH lighting computed from {origin} in {elapsed:.2f} s")
        return {"FINISHED"}


class SHLIGHT_OT_reset(bpy.types.Operator):
    """Set the coefficients back to the values last computed from the world"""

    bl_idname = "shlight.reset"
    bl_label = "Reset"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        if not scene_poll(cls, context):
            return False
        if scene_data.COMPUTED_PROPERTY not in context.scene:
            cls.poll_message_set("Nothing to reset to: run Compute from World first")
            return False
        return True

    def execute(self, context):
        try:
            properties.reset_coefficients(context.scene)
        except (LookupError, TypeError, ValueError) as error:
            self.report({"ERROR"}, f"Cannot reset: {error}")
            return {"CANCELLED"}
        self.report({"INFO"}, "SH lighting reset to the values computed from the world")
        return {"FINISHED"}


class SHLIGHT_OT_apply(bpy.types.Operator):
    """Add SH irradiance lighting to the materials of the selected objects (or of all objects),
    reading the scene's coefficients at render time"""

    bl_idname = "shlight.apply"
    bl_label = "Apply to Materials"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return _target_poll(cls, context) and coefficients_poll(cls, context)

    def execute(self, context):
        scene = context.scene
        mats = materials_of(objects_for_target(context, scene.sh_lighting.apply_target))
        try:
            result = materials.apply_to_materials(mats, scene)
        except (LookupError, ValueError) as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        changed, skipped = len(result.changed), len(result.skipped)
        message = f"SH lighting applied to {changed} material(s), {skipped} skipped"
        reasons = _skip_reasons(result)
        if reasons:
            message += " (" + "; ".join(reasons) + ")"
        self.report({"WARNING"} if skipped and not changed else {"INFO"}, message)
        return {"FINISHED"}


class SHLIGHT_OT_remove(bpy.types.Operator):
    """Remove SH irradiance lighting from the materials of the selected objects (or of all
    objects), restoring what Apply changed"""

    bl_idname = "shlight.remove"
    bl_label = "Remove from Materials"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return _target_poll(cls, context)

    def execute(self, context):
        scene = context.scene
        mats = materials_of(objects_for_target(context, scene.sh_lighting.apply_target))
        try:
            result = materials.remove_from_materials(mats)
        except (LookupError, ValueError) as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        changed, skipped = len(result.changed), len(result.skipped)
        self.report(
            {"INFO"}, f"SH lighting removed from {changed} material(s), {skipped} skipped"
        )
        return {"FINISHED"}


def fit_summary(report):
    """One line about a ``nodes.FitReport``: node count, what was left out, its exact bound."""
    left_out = ", ".join(report.omitted) if report.omitted else "nothing"
    text = f"{report.node_count} nodes; left out: {left_out}"
    if report.omitted:
        text += f" (error ≤ {100.0 * report.bound:.3g} % of the mean irradiance)"
    return text


class SHLIGHT_OT_refit(bpy.types.Operator):
    """Fit the SH Irradiance node group to the coefficients of every scene at every keyframed
    frame: only the terms they need, scalar math for grey lighting, a clamp only if needed"""

    bl_idname = "shlight.refit"
    bl_label = "Refit Node Group"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        if not scene_poll(cls, context):
            return False
        if nodes.find_node_group() is None:
            cls.poll_message_set("No SH Irradiance node group yet: Apply to materials first")
            return False
        return True

    def execute(self, context):
        report = nodes.refit_node_group(context.scene)
        state = "rebuilt" if report.rebuilt else "already fitted"
        self.report({"INFO"}, f"SH node group {state}: {fit_summary(report)}")
        return {"FINISHED"}


classes = (
    SHLIGHT_OT_compute_from_world,
    SHLIGHT_OT_reset,
    SHLIGHT_OT_apply,
    SHLIGHT_OT_remove,
    SHLIGHT_OT_refit,
)
_register_classes, _unregister_classes = bpy.utils.register_classes_factory(classes)


def register():
    _register_classes()
    world_cache.register_cache()


def unregister():
    world_cache.unregister_cache()
    _unregister_classes()
