"""Transfer in the UI: Bake Transfer, Apply Transfer, Delete Transfer and the "Transfer
(Shadows)" sub-panel. The logic is ``blender.transfer``; nothing here bakes or writes data
itself."""

import bpy

from ...choices import MATERIAL_MODES
from ..transfer import apply as transfer_apply
from ..transfer import bake
from . import panels
from .bake_steps import BakeSteps, baked_line, quiet_image_library
from ..shading.materials import materials_of
from .operators import objects_for_target
from .polls import coefficients_poll, scene_poll

MODE_ITEMS = (
    ("SCENE", "Panel's Mode", "The Mode chosen in the panel beside Apply (the scene's setting)"),
    ("KEEP_BSDF", "Keep BSDF",
     "Keep the material's BSDF (lamps, shadows, reflections); the transfer replaces the "
     "world's diffuse light (Cycles)"),
    ("EMISSION", "Emission Only",
     "The transfer alone drives the surface: shadows and bounce light, noise free at one "
     "sample; no lamps or reflections"),
)


def _selected_meshes(context):
    return [o for o in (context.selected_objects or ()) if o.type == "MESH"]


class SHLIGHT_OT_bake_transfer(BakeSteps, bpy.types.Operator):
    """Bake the selected meshes' transfer with Cycles: how much of each of the nine SH terms
    reaches each face corner through the scene's shadows and bounce light. The dialog says
    what it will cost; in a window it runs with a progress bar, Esc stops it"""

    bl_idname = "shlight.bake_transfer"
    bl_label = "Bake Transfer"
    bl_options = {"REGISTER", "UNDO"}

    samples: bpy.props.IntProperty(
        name="Samples", default=bake.DEFAULT_SAMPLES, min=1, max=bake.MAX_SAMPLES,
        soft_max=1024,
        description="Cycles samples per face corner and basis function (noise falls as "
                    "1/sqrt(samples))")
    use_error_target: bpy.props.BoolProperty(
        name="Error Target", default=False,
        description="Choose the samples for a noise target (two short probe bakes first)")
    error_target: bpy.props.FloatProperty(
        name="Target", default=1.0, min=0.05, max=50.0, subtype="PERCENTAGE",
        description="Noise of the ambient transfer, relative RMS over the corners, %")
    store: bpy.props.EnumProperty(
        name="Store", default="AUTO",
        items=[("AUTO", "Automatic", "Per texel for meshes too coarse to carry a shadow at "
                "their corners (a plain floor), per corner for the others"),
               ("CORNERS", "Per Corner", "In the meshes' colour attributes: dense meshes"),
               ("TEXELS", "Per Texel", "In a lightmap atlas on a UV map the add-on adds (your "
                "UV maps untouched): any mesh, at a texel size from the scene's scale")],
        description="Where the transfer is stored")

    @classmethod
    def poll(cls, context):
        if not scene_poll(cls, context):
            return False
        if not _selected_meshes(context):
            cls.poll_message_set("Select the meshes to bake")
            return False
        return True

    def invoke(self, context, event):
        self._modal = True  # from the dialog: run modally (a script's call runs at once)
        return context.window_manager.invoke_props_dialog(self, width=420)

    def draw(self, context):
        layout = self.layout
        layout.prop(self, "samples")
        layout.prop(self, "store")
        row = layout.row()
        row.prop(self, "use_error_target")
        sub = row.row()
        sub.active = self.use_error_target
        sub.prop(self, "error_target")
        for icon, text in dialog_lines(context.scene, _selected_meshes(context), self.samples,
                                       self.store):
            panels.wrapped(layout, context, text, icon=icon)

    def execute(self, context):
        quiet_image_library()
        selected = _selected_meshes(context)
        objects = [o for o in selected
                   if bake.refusal(context.scene, o, store=self.store) is None]
        skipped = [bake.refusal(context.scene, o, store=self.store)
                   for o in selected if o not in objects]
        if not objects:  # nothing to bake: the first reason, as the bake itself gives it
            objects, skipped = selected, []
        try:
            target = self.error_target / 100.0 if self.use_error_target else None
            job = bake.Bake(context.scene, objects, self.samples,
                            report=lambda text: self.report({"INFO"}, text), error_target=target,
                            store=self.store)
        except (bake.TransferError, RuntimeError) as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        self._skipped = skipped
        return self.run_bake(context, job)

    def baked(self, context, info):
        self.report({"INFO"}, baked_line(info))
        for reason in self._skipped:
            self.report({"WARNING"}, f"Not baked: {reason}")
        for note in info.notes:
            self.report({"WARNING"}, note)
        return {"FINISHED"}


def dialog_lines(scene, objects, samples, store="AUTO"):
    """What the Bake dialog says before OK: [(icon, text)] the objects it cannot bake (why,
    what to do), the cost (objects, vertices, texels, estimated seconds) and the objects
    baked per texel (or too coarse per corner)."""
    plan = bake.plan(scene, objects, samples, store)
    lines = [("ERROR", f"Not baked: {reason}") for _name, reason in plan.refused]
    if plan.objects:
        lines.append(("TIME", (
            f"Bakes {len(plan.objects)} object(s): {plan.vertices} vertices, "
            + (f"{plan.texels} texels, " if plan.texels else "")
            + f"{samples} samples, about {plan.seconds:.0f} s")))
    else:
        lines.append(("ERROR", "Nothing to bake: select meshes that can be baked"))
    lines.extend(("INFO", line) for line in plan.coarse)
    return lines


class SHLIGHT_OT_apply_transfer(bpy.types.Operator):
    """Light the baked objects' materials by the transfer: the SH lighting with the baked
    shadows and bounce light, still edited live by the coefficients"""

    bl_idname = "shlight.apply_transfer"
    bl_label = "Apply Transfer"
    bl_options = {"REGISTER", "UNDO"}

    mode: bpy.props.EnumProperty(name="Mode", items=MODE_ITEMS, default="SCENE",
                                 description="How the transfer joins the material; by default "
                                             "the Mode chosen in the panel, as for Apply",
                                 options={"SKIP_SAVE"})

    @classmethod
    def poll(cls, context):
        if not coefficients_poll(cls, context):
            return False
        target = context.scene.sh_lighting.apply_target
        if not transfer_apply.baked_objects(objects_for_target(context, target)):
            cls.poll_message_set("No baked object to apply to: bake the transfer first")
            return False
        return True

    def execute(self, context):
        scene = context.scene
        # Cameras, lamps, empties (Select All) have no transfer to apply: left out silently
        objects = [o for o in objects_for_target(context, scene.sh_lighting.apply_target)
                   if o.type == "MESH"]
        try:
            mode = scene.sh_lighting.apply_mode if self.mode == "SCENE" else self.mode
            if mode not in MATERIAL_MODES:  # the world's modes: the transfer lights materials
                mode = "KEEP_BSDF"
            result = transfer_apply.apply_transfer(objects, scene, mode)
        except ValueError as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        shown = "; ".join(f"{name}: {reason}" for name, reason in result.skipped[:3])
        if not result.changed:
            self.report({"WARNING"}, f"No material changed. {shown}")
            return {"CANCELLED"}
        text = f"Transfer applied to {len(result.changed)} material(s)"
        self.report({"WARNING" if result.skipped else "INFO"},
                    text + (f"; skipped {len(result.skipped)}: {shown}" if shown else ""))
        return {"FINISHED"}


class SHLIGHT_OT_delete_transfer(bpy.types.Operator):
    """Delete the selected objects' transfer bake (its attributes), and take the transfer out
    of their materials"""

    bl_idname = "shlight.delete_transfer"
    bl_label = "Delete Transfer"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        if not scene_poll(cls, context):
            return False
        if not any(bake.has_transfer(o) for o in _selected_meshes(context)):
            cls.poll_message_set("No selected object has a transfer bake")
            return False
        return True

    def execute(self, context):
        objects = [o for o in _selected_meshes(context) if bake.has_transfer(o)]
        transfer_apply.remove_transfer_from(materials_of(objects))
        for obj in objects:
            bake.remove_transfer(obj)
        self.report({"INFO"}, f"Deleted the transfer of {len(objects)} object(s)")
        return {"FINISHED"}


def transfer_lines(scene, active):
    """What the panel says: [(icon, text)] for the active object and the scene's bakes."""
    baked = [o for o in scene.objects if o.type == "MESH" and bake.record(o) is not None]
    if not baked:
        return [("INFO", "No transfer baked: select meshes and bake")]
    depsgraph = bake.evaluated_depsgraph(scene)
    scene_print = bake.scene_fingerprint(scene, depsgraph)
    states = {o.name: bake.status(scene, o, scene_print, depsgraph) for o in baked}
    stale = [name for name, (state, _message) in states.items() if state == "STALE"]
    lines = []
    if active is not None and active.name in states:
        state, message = states[active.name]
        lines.append(("ERROR" if state == "STALE" else "CHECKMARK", message))
        lines.extend(("INFO", line) for line in bake.record(active).get("coarse", ()))
    lines.append(("ERROR" if stale else "INFO",
                  f"{len(baked)} baked, {len(stale)} stale"
                  + (f": {', '.join(stale[:3])}" if stale else "")))
    return lines


def draw_transfer(layout, context):
    scene = context.scene
    row = layout.row(align=True)
    row.operator(SHLIGHT_OT_bake_transfer.bl_idname, icon="RENDER_STILL")
    row.operator(SHLIGHT_OT_delete_transfer.bl_idname, text="", icon="TRASH")
    layout.operator(SHLIGHT_OT_apply_transfer.bl_idname, icon="MATERIAL")
    for icon, text in transfer_lines(scene, context.active_object):
        panels.wrapped(layout, context, text, icon=icon)


SHLIGHT_PT_world_transfer, SHLIGHT_PT_view3d_transfer = panels.sub_panels(
    "transfer", "Transfer (Shadows)", draw_transfer, options=("DEFAULT_CLOSED",))

classes = (
    SHLIGHT_OT_bake_transfer,
    SHLIGHT_OT_apply_transfer,
    SHLIGHT_OT_delete_transfer,
    SHLIGHT_PT_world_transfer,
    SHLIGHT_PT_view3d_transfer,
)
register, unregister = bpy.utils.register_classes_factory(classes)
