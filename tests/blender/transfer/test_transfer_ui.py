"""Transfer in the UI (``blender/ui/transfer``): bake, the panel's stale message, Apply
Transfer in its default mode against path tracing, Delete, and the polls' reasons."""

import re
import bpy
import numpy as np
import pytest

import blender_scenes as scenes
import transfer_scenes as ts
from sh_lighting.blender.shading import materials
from sh_lighting.blender.transfer import apply as transfer_apply
from sh_lighting.blender.transfer import bake, nodes
from sh_lighting.blender.ui import transfer as transfer_ui

# Measured 0.96 % here (Keep BSDF, Cycles 16 samples: the BSDF gets no world and no
# diffuse-ray emission, so what is left is the camera's view of the transfer), as in Emission
# Only (tests/blender/transfer/test_transfer.py); the goal is 2 %.
RENDER_TOLERANCE = 0.02


def _select(objects, active=None):
    for obj in bpy.context.scene.objects:
        obj.select_set(obj in objects)
    bpy.context.view_layer.objects.active = active or (objects[0] if objects else None)


def _scene(ground_cuts=4, box_cuts=0):
    return ts.lit_ground_and_box(ground_cuts, box_cuts)


def test_bake_then_the_panel_says_when_an_edit_made_it_stale(addon):
    scene, ground, box = _scene()
    assert transfer_ui.transfer_lines(scene, ground) == [
        ("INFO", "No transfer baked: select meshes and bake")]
    _select([ground, box])
    assert bpy.ops.shlight.bake_transfer(samples=8) == {"FINISHED"}
    lines = transfer_ui.transfer_lines(scene, ground)
    assert lines[0][0] == "CHECKMARK" and lines[0][1].startswith("'Ground': baked, 8 samples")
    assert lines[1][1].startswith("'Ground' is baked per texel (too coarse for a shadow at "
                                  "its corners): ")  # 1 m quads
    assert lines[-1] == ("INFO", "2 baked, 0 stale")
    box.data.vertices[0].co.z += 0.2
    lines = transfer_ui.transfer_lines(scene, ground)
    assert lines[0] == ("ERROR", "'Ground': objects of the scene changed since the bake "
                                 "(moved, edited, added, hidden or removed): bake again")
    assert lines[-1] == ("ERROR", "2 baked, 2 stale: Ground, Box")
    _select([box])
    assert bpy.ops.shlight.delete_transfer() == {"FINISHED"}
    assert bake.record(box) is None and not box.data.color_attributes
    assert bake.record(ground) is not None


def test_polls_say_why(addon):
    scene, ground, box = _scene()
    _select([])
    assert not bpy.ops.shlight.bake_transfer.poll()
    assert not bpy.ops.shlight.delete_transfer.poll()
    _select([ground])
    assert not bpy.ops.shlight.apply_transfer.poll()  # nothing baked yet
    cls = transfer_ui.SHLIGHT_OT_apply_transfer
    messages = []
    cls.poll_message_set = classmethod(lambda c, text: messages.append(text))
    try:
        cls.poll(bpy.context)
    finally:
        del cls.poll_message_set
    assert messages == ["No baked object to apply to: bake the transfer first"]


def test_bake_refusal_is_reported_and_changes_nothing(addon):
    scene, ground, box = _scene()
    box.modifiers.new("Bevel", "BEVEL")
    _select([box])
    with pytest.raises(RuntimeError, match="'Box' has modifiers \\(Bevel\\)"):
        bpy.ops.shlight.bake_transfer(samples=8)
    assert bake.record(box) is None and not box.data.color_attributes


def test_the_dialog_tells_refusals_and_cost_before_ok_and_the_others_are_baked(addon):
    scene, ground, box = _scene()
    box.modifiers.new("Mirror", "MIRROR")  # overlaps the atlas's charts: refused
    lines = transfer_ui.dialog_lines(scene, [ground, box], samples=64)
    texts = [text for _icon, text in lines]
    assert ("ERROR", "Not baked: 'Box' has modifiers (Mirror): the transfer is stored on "
            "the mesh itself, so apply them (or disable them for renders) and bake again"
            ) in lines, texts
    cost = [t for t in texts if re.fullmatch(  # the ground per texel: its texels counted
        r"Bakes 1 object\(s\): 25 vertices, \d+ texels, 64 samples, about \d+ s", t)]
    assert cost, texts
    _select([ground, box])
    assert bpy.ops.shlight.bake_transfer(samples=8) == {"FINISHED"}
    assert bake.record(ground) is not None and bake.record(box) is None
    assert not box.data.color_attributes


@pytest.mark.slow
def test_apply_transfer_default_mode_matches_path_tracing(addon, tmp_path):
    scene, ground, box = _scene(24, 5)
    scene.cycles.samples = 512
    reference, alpha, _ = scenes.render(scene, tmp_path / "reference.exr")
    _select([ground, box])
    assert bpy.ops.shlight.bake_transfer(samples=64) == {"FINISHED"}
    assert bpy.ops.shlight.apply_transfer() == {"FINISHED"}  # default: Keep BSDF
    material = ground.material_slots[0].material
    groups = [n.node_tree for n in material.node_tree.nodes if n.bl_idname == "ShaderNodeGroup"]
    assert [g.name for g in groups] == [nodes.GROUP_NAME]
    scene.cycles.samples = 16
    estimate, _, _ = scenes.render(scene, tmp_path / "keep_bsdf.exr")
    mask = np.repeat((alpha > 0.999)[..., None], 3, axis=-1)
    error = ts.relative_rmse(estimate, reference, mask)
    assert error < RENDER_TOLERANCE, error
    # Cycles must not sample the transfer as a light (with Auto: 8.7 %, 6.4 % too bright).
    assert material.cycles.emission_sampling == "NONE"
    assert bpy.ops.shlight.delete_transfer() == {"FINISHED"}
    assert not [n for n in material.node_tree.nodes if n.bl_idname == "ShaderNodeGroup"]
    assert material.cycles.emission_sampling == "AUTO"
    assert bake.record(ground) is None and bake.record(box) is None


def test_each_remove_restores_only_the_emission_sampling_it_changed(addon):
    """Apply Transfer and the plain Apply keep the Emission Sampling they replace in the same
    record, so either Remove (the panel's Remove, Delete Transfer) puts it back, and only
    while it is still the None they set: a value chosen since is the user's."""
    scene, ground, box = _scene(2, 0)
    bake.bake_transfer(scene, [ground, box], samples=1)
    material = ground.material_slots[0].material
    material.cycles.emission_sampling = "FRONT"
    _select([ground, box])
    assert bpy.ops.shlight.apply_transfer() == {"FINISHED"}
    assert material.cycles.emission_sampling == "NONE"
    assert bpy.ops.shlight.remove() == {"FINISHED"}  # the plain Remove
    assert material.cycles.emission_sampling == "FRONT"
    assert bake.record(ground) is None  # Remove deletes the bake with the lighting
    bake.bake_transfer(scene, [ground, box], samples=1)
    assert bpy.ops.shlight.apply() == {"FINISHED"}
    assert bpy.ops.shlight.apply_transfer() == {"FINISHED"}  # over the plain Apply
    assert material.cycles.emission_sampling == "NONE"
    assert bpy.ops.shlight.delete_transfer() == {"FINISHED"}
    assert material.cycles.emission_sampling == "FRONT"
    bake.bake_transfer(scene, [ground, box], samples=1)
    assert bpy.ops.shlight.apply_transfer() == {"FINISHED"}
    material.cycles.emission_sampling = "BACK"  # the user's choice after Apply
    assert bpy.ops.shlight.remove() == {"FINISHED"}
    assert material.cycles.emission_sampling == "BACK"
    assert not materials.is_applied(material)


def test_plain_apply_keeps_the_transfer_and_apply_transfer_follows_the_panels_mode(addon):
    """Keep BSDF's Apply reaches the whole scene: a plain Apply for an object added later must
    not take the shadows off the baked ones. Remove, then Apply, gives SH without them."""
    scene, ground, box = _scene(2, 0)
    bake.bake_transfer(scene, [ground], samples=1)
    ground.data.materials[0] = ts.diffuse_material("Ground Grey")
    scene.sh_lighting.apply_mode = "EMISSION"
    _select([ground])
    assert bpy.ops.shlight.apply_transfer() == {"FINISHED"}
    material = ground.material_slots[0].material
    assert materials.mode_of(material) == "EMISSION"  # the panel's Mode
    scene.sh_lighting.apply_mode = "KEEP_BSDF"
    _select([box])
    assert bpy.ops.shlight.apply() == {"FINISHED"}  # widened to the whole scene
    assert materials.mode_of(material) == "KEEP_BSDF"
    assert transfer_apply.uses_transfer(material)
    assert not transfer_apply.uses_transfer(box.material_slots[0].material)
    scene.sh_lighting.apply_target = "ALL"
    assert bpy.ops.shlight.remove() == {"FINISHED"}
    assert bpy.ops.shlight.apply() == {"FINISHED"}
    assert materials.is_applied(material) and not transfer_apply.uses_transfer(material)


def _addon_attributes():
    """Every trace of a bake: the corners' attributes, the atlas's UV maps and images."""
    return sorted([f"{mesh.name}.{attribute.name}" for mesh in bpy.data.meshes
                   for attribute in mesh.attributes
                   if attribute.name.startswith(("sh_T", "sh_transfer"))]
                  + [image.name for image in bpy.data.images if "Transfer" in image.name])


def test_remove_and_delete_transfer_leave_no_attribute_of_the_add_on(addon):
    scene, ground, box = _scene(2, 0)
    _select([ground, box])
    assert bpy.ops.shlight.bake_transfer(samples=1) == {"FINISHED"}
    assert len(_addon_attributes()) == 19  # the box's 9 attributes, the ground's UV map and
    # the atlas's 9 images (the 1 m ground quads are too coarse: baked per texel)
    assert "Ground.sh_transfer_uv" in _addon_attributes()
    assert bpy.ops.shlight.apply_transfer() == {"FINISHED"}
    _select([ground])
    assert bpy.ops.shlight.remove() == {"FINISHED"}  # Keep BSDF: the whole scene's
    assert _addon_attributes() == []
    assert bake.record(ground) is None and bake.record(box) is None
    # Delete Transfer: also what an interrupted bake left (the scratch attribute, no record)
    _select([ground, box])
    assert bpy.ops.shlight.bake_transfer(samples=1) == {"FINISHED"}
    box.data.color_attributes.new(bake.SCRATCH_NAME, "FLOAT_COLOR", "CORNER")
    del box[bake.RECORD]
    assert bpy.ops.shlight.delete_transfer() == {"FINISHED"}
    assert _addon_attributes() == [] and bake.record(ground) is None
