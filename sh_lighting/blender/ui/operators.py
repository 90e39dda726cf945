"""Operators: Compute from World, Reset, Apply, Remove.

Each operator reads the context once, hands plain values (scene, materials, widths) to the
logic in ``world``, ``scene_data`` and ``materials``, and turns their exceptions into an
ERROR report and {'CANCELLED'} with nothing changed. All are undoable and work in background
mode (``bpy.ops.shlight.compute_from_world()``); polls say why a button is disabled.
"""

import time

import bpy

from ...choices import APPLY_MODE_ITEMS, resolve_mode
from ..data import scene_data
from ..shading import materials, notes
from ..transfer import apply as transfer_apply
from ..transfer import bake, on_apply
from ..design import compute as design_compute
from ..world import compute
from .. import world_edit
from .bake_steps import BakeSteps, baked_line, quiet_image_library
from .polls import coefficients_poll, scene_poll, world_poll


def objects_for_target(context, target):
    """The objects Apply and Remove act on: the selected ones, or every object of the scene."""
    if target == "SELECTED":
        return list(context.selected_objects or ())
    return list(context.scene.objects)


def bare_objects_note(names, limit=3):
    """"N object(s) have no material (a, b, ...): give them a material first", or ""."""
    if not names:
        return ""
    shown = ", ".join(names[:limit]) + (", ..." if len(names) > limit else "")
    return f"{len(names)} object(s) have no material ({shown}): give them a material first"


def beyond_selection(context):
    """The materials Apply will change beyond the selected objects' (Keep BSDF turns the
    world's diffuse light off for the whole scene, so every material gets SH): [] unless
    Apply To is Selected and Mode Keep BSDF."""
    settings = context.scene.sh_lighting
    if settings.apply_target != "SELECTED" or settings.apply_mode != "KEEP_BSDF":
        return []
    chosen = set(materials.materials_of(context.selected_objects or ()))
    return [m for m in materials.materials_of(context.scene.objects) if m not in chosen]


def file_materials():
    """The file's local materials (Remove checks none of them is still lit by SH)."""
    return [m for m in bpy.data.materials if m.library is None]


def _skip_reasons(result, limit=3):
    """Up to ``limit`` "material: reason" strings of a ``materials.Result``."""
    return [f"{name}: {reason}" for name, reason in result.skipped[:limit]]


def _target_poll(cls, context, world_too=False):
    """Shared poll of Apply and Remove: a scene with settings and something to act on
    (``world_too``: an Edit World mode or an edited world needs no objects)."""
    if not scene_poll(cls, context):
        return False
    scene = context.scene
    if world_too and (world_edit.is_edited(scene.world) or resolve_mode(
            scene.sh_lighting.apply_mode, scene.render.engine) == "WORLD"):
        return True
    target = scene.sh_lighting.apply_target
    if target == "SELECTED" and not context.selected_objects:
        cls.poll_message_set("No objects selected: select objects or set Apply To to All")
        return False
    if target == "ALL" and not len(scene.objects):
        cls.poll_message_set("The scene has no objects")
        return False
    return True


def with_note(message, stored):
    """``message`` and, when the write of ``stored`` keyed or cleared animated values, what
    it did (``scene_data.Stored.note``)."""
    return f"{message}; {stored.note}" if stored.note else message


class SHLIGHT_OT_compute_from_world(bpy.types.Operator):
    """Compute the 9 SH lighting coefficients from the scene's world (image or procedural)"""

    bl_idname = "shlight.compute_from_world"
    bl_label = "Compute from World"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return world_poll(cls, context)

    def execute(self, context):
        start = time.perf_counter()
        # An 8K image takes seconds: the wait cursor shows progress, the status bar says what
        # is being done until the report replaces it.
        wm = context.window_manager
        workspace = getattr(context, "workspace", None)
        wm.progress_begin(0, 1)
        wm.progress_update(0)
        if workspace is not None:
            workspace.status_text_set("Computing the lighting of the world…")
        try:
            stored, info = design_compute.compute_from_world(
                context.scene, error_normals=compute.REPORT_ERROR_NORMALS)
        except ValueError as error:  # WorldError and invalid coefficients
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        finally:
            wm.progress_update(1)
            wm.progress_end()
            if workspace is not None:
                workspace.status_text_set(None)
        message = with_note(compute.report(info, time.perf_counter() - start), stored)
        try:
            refreshed = world_edit.refresh(context.scene)
        except ValueError as error:
            self.report({"WARNING"}, f"{message}; World Edit taken out: {error}")
            return {"FINISHED"}
        self.report({"INFO"}, f"{message}; {refreshed}" if refreshed else message)
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
            stored = scene_data.reset(context.scene)
        except (LookupError, TypeError, ValueError) as error:
            self.report({"ERROR"}, f"Cannot reset: {error}")
            return {"CANCELLED"}
        self.report({"INFO"}, with_note("SH lighting reset to the values computed from the world",
                                        stored))
        return {"FINISHED"}


class SHLIGHT_OT_apply(BakeSteps, bpy.types.Operator):
    """Add SH irradiance lighting to the materials of the selected objects (or of all objects),
    reading the scene's coefficients at render time"""

    bl_idname = "shlight.apply"
    bl_label = "Apply to Materials"
    bl_options = {"REGISTER", "UNDO"}
    cancel_message = "Apply cancelled during the shadows' bake: nothing changed"

    mode: bpy.props.EnumProperty(
        name="Mode",
        items=(("SCENE", "Panel's Mode", "The Mode chosen in the panel (the scene's setting)"),
               *APPLY_MODE_ITEMS),
        default="SCENE",
        description="Keep the BSDF (SH replaces the world's diffuse light) or emission only; "
                    "by default the Mode chosen in the panel",
        options={"SKIP_SAVE"},
    )

    @classmethod
    def poll(cls, context):
        return _target_poll(cls, context, world_too=True) and coefficients_poll(cls, context)

    @classmethod
    def description(cls, context, props):
        """The docstring, what the bake Keep BSDF with Shadows starts costs (or why the Default
        starts none), and how many materials beyond the selection Keep BSDF changes."""
        text = cls.bl_rna.description
        scene = context.scene
        asked = scene.sh_lighting.apply_mode if props.mode == "SCENE" else props.mode
        if resolve_mode(asked, scene.render.engine) == "TRANSFER":
            need = on_apply.needed(
                scene, objects_for_target(context, scene.sh_lighting.apply_target))
            if on_apply.starts_bake(need, asked):
                text += f".\nApply {on_apply.cost_line(need)} (Esc stops it)"
            elif need.objects:
                text += f".\nApply gives {on_apply.skipped_bake_line(need)}"
        beyond = beyond_selection(context) if props.mode == "SCENE" else []
        if beyond:
            shown = ", ".join(m.name for m in beyond[:3]) + (", ..." if len(beyond) > 3 else "")
            text += (f".\nKeep BSDF also changes {len(beyond)} material(s) of objects not "
                     f"selected ({shown}): it turns the world's diffuse light off for the "
                     "whole scene, so every material there gets the SH light")
        return text

    def invoke(self, context, event):
        self._modal = True  # from a button: a bake before Apply runs modally
        return self.execute(context)

    def execute(self, context):
        scene = context.scene
        settings = scene.sh_lighting
        asked = getattr(self, "mode", "SCENE")
        if asked == "SCENE":
            asked = settings.apply_mode
        mode = resolve_mode(asked, scene.render.engine)
        if mode == "WORLD":
            return _edit_world(self, scene)
        objects = objects_for_target(context, settings.apply_target)
        if mode == "TRANSFER":
            return self._with_shadows(context, objects, asked)
        mats = materials.materials_of(objects)
        bare = bare_objects_note(materials.objects_without_material(objects))
        if not mats and bare:
            self.report({"WARNING"}, f"SH lighting applied to no material: {bare}")
            return {"CANCELLED"}
        widened = []
        if mode == "KEEP_BSDF":
            # The world stops lighting every diffuse surface: every material it lit gets SH,
            # not only the selected ones.
            everything = materials.materials_of(scene.objects)
            widened = [m for m in everything if m not in mats]
            mats = everything
        try:
            result, kept = transfer_apply.apply_keeping_transfer(mats, scene, mode)
        except (LookupError, ValueError) as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        if result.changed and world_edit.is_edited(scene.world):
            world_edit.remove(scene.world)  # the materials light it now: not twice
        changed, skipped = len(result.changed), len(result.skipped)
        label = dict((key, name) for key, name, _text in APPLY_MODE_ITEMS)[mode]
        message = f"SH lighting ({label}) applied to {changed} material(s), {skipped} skipped"
        if widened:
            message += (f", {len(widened)} of them beyond the selection: Keep BSDF turns the "
                        "world's diffuse light off for the whole scene")
        reasons = _skip_reasons(result)
        if reasons:
            message += " (" + "; ".join(reasons) + ")"
        if kept:
            message += (f"; {len(kept)} keep the transfer (shadows): Remove, then Apply, for "
                        "SH without it")
        if mode == "KEEP_BSDF" and result.skipped:
            message += "; the skipped ones now get no diffuse light from the world"
        lamps = notes.emission_lamp_note(scene) if mode == "EMISSION" else None
        if lamps and changed:
            message += f"; {lamps}"
        shared = notes.shared_scene_notes(scene, result.changed) if mode == "KEEP_BSDF" else []
        if shared:
            message += "; " + "; ".join(shared)
        reflections = notes.reflection_note(scene, result.changed) if mode == "KEEP_BSDF" else None
        if reflections:
            message += f"; {reflections}"
        if bare:
            message += f"; {bare}"
        warn = ((skipped or bare) and not changed) or (lamps and changed) or shared
        self.report({"WARNING"} if warn else {"INFO"}, message)
        return {"FINISHED"}

    def _with_shadows(self, context, objects, asked):
        """Keep BSDF with Shadows: the bake ``on_apply`` asks for (modal from a button),
        then ``baked``."""
        scene = context.scene
        need = on_apply.needed(scene, objects)
        self._objects = objects
        self._notes = [f"no shadows on '{name}': {why}" for name, why in need.refused]
        if not on_apply.starts_bake(need, asked):
            if need.objects:
                self._notes.append(on_apply.skipped_bake_line(need))
            return self.baked(context, None)
        quiet_image_library()
        try:
            job = bake.Bake(scene, need.objects,
                            report=lambda text: self.report({"INFO"}, text))
        except (bake.TransferError, RuntimeError) as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        return self.run_bake(context, job)

    def baked(self, context, info):
        """After the bake (``info``; None: none ran): Keep BSDF, the transfer where baked."""
        scene = context.scene
        notes_ = list(self._notes)
        if info is not None:
            self.report({"INFO"}, baked_line(info))
            notes_ = list(info.notes) + notes_
        objects = [o for o in self._objects if _alive(o)]
        try:
            result, lit = on_apply.apply_with_transfer(scene, objects)
        except (LookupError, ValueError) as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        if result.changed and world_edit.is_edited(scene.world):
            world_edit.remove(scene.world)  # the materials light it now: not twice
        changed, skipped = len(result.changed), len(result.skipped)
        message = (f"SH lighting (Keep BSDF with Shadows) applied to {changed} material(s), "
                   f"{len(lit)} with the transfer's shadows, {skipped} skipped")
        chosen = {m.name_full for m in materials.materials_of(objects)}
        widened = [name for name in result.changed if name not in chosen]
        if widened:
            message += (f", {len(widened)} of them beyond the selection: Keep BSDF turns the "
                        "world's diffuse light off for the whole scene")
        reasons = _skip_reasons(result)
        if reasons:
            message += " (" + "; ".join(reasons) + ")"
        extra = notes.shared_scene_notes(scene, result.changed)
        reflections = notes.reflection_note(scene, result.changed)
        bare = bare_objects_note(materials.objects_without_material(objects))
        message += "".join(f"; {line}" for line in notes_ + extra + [reflections, bare] if line)
        warn = not changed or extra or (not lit and result.changed)
        self.report({"WARNING"} if warn else {"INFO"}, message)
        return {"FINISHED"}


def _alive(obj):
    """Whether ``obj`` still exists (a modal bake lets the user delete nothing, but undo can)."""
    try:
        return obj.name is not None
    except ReferenceError:
        return False


def _edit_world(operator, scene):
    """Apply in mode "WORLD": the world edited, the SH taken out of the scene's materials
    (the world lights them now; nothing counted twice)."""
    try:
        clamping = world_edit.edit_world(scene)
    except (LookupError, ValueError) as error:
        operator.report({"ERROR"}, str(error))
        return {"CANCELLED"}
    message = world_edit.applied_message(scene, clamping)
    applied = [m for m in materials.materials_of(scene.objects) if materials.is_applied(m)]
    if applied:
        result = materials.remove_from_materials(applied)
        message += (f"; SH lighting taken out of {len(result.changed)} material(s): the "
                    "edited world lights them")
    note = world_edit.clamping_note(clamping)
    if note:
        message += f"; {note}"
    operator.report({"WARNING"} if note else {"INFO"}, message)
    return {"FINISHED"}


class SHLIGHT_OT_remove(bpy.types.Operator):
    """Remove SH irradiance lighting from the materials of the selected objects (or of all
    objects), restoring what Apply changed"""

    bl_idname = "shlight.remove"
    bl_label = "Remove from Materials"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return _target_poll(cls, context, world_too=True)

    def execute(self, context):
        scene = context.scene
        world = world_edit.remove(scene.world) and scene.world.name
        mats = materials.materials_of(objects_for_target(context, scene.sh_lighting.apply_target))
        if world and not any(materials.is_applied(m) for m in mats):
            self.report({"INFO"}, f"World Edit removed: world '{world}' is as it was")
            return {"FINISHED"}
        widened = []
        if any(materials.mode_of(m) == "KEEP_BSDF" for m in mats):
            # The world gets its diffuse light back only once no Keep BSDF material is left:
            # a material removed alone would be lit by neither.
            keeping = [m for m in materials.materials_of(scene.objects)
                       if materials.mode_of(m) == "KEEP_BSDF"]
            widened = [m for m in keeping if m not in mats]
            mats = mats + widened
        try:
            result = materials.remove_from_materials(mats)
        except (LookupError, ValueError) as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        changed, skipped = len(result.changed), len(result.skipped)
        message = f"SH lighting removed from {changed} material(s), {skipped} skipped"
        if world:
            message = f"World Edit removed from world '{world}'; " + message
        if widened:
            message += (f", {len(widened)} of them beyond the selection: the world lights "
                        "diffuse surfaces again, for the whole scene")
        baked = transfer_apply.delete_bakes(
            objects_for_target(context, scene.sh_lighting.apply_target), result.changed)
        if baked:
            message += f"; the transfer bake of {len(baked)} object(s) deleted"
        if not any(materials.is_applied(m) for m in file_materials()):
            # The world lights everything again: Extract Lights' lamps would light it twice
            deleted = design_compute.take_lights_back(scene)
            if deleted:
                message += (f"; {len(deleted)} extracted light(s) deleted "
                            f"({', '.join(deleted)}), the SH holds the whole world again")
        self.report({"INFO"}, message)
        return {"FINISHED"}


classes = (
    SHLIGHT_OT_compute_from_world,
    SHLIGHT_OT_reset,
    SHLIGHT_OT_apply,
    SHLIGHT_OT_remove,
)
register, unregister = bpy.utils.register_classes_factory(classes)
