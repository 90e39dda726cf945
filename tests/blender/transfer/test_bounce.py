"""The lamps' bounce (``transfer/bounce``): baked with the transfer where the scene has lamps,
added to what EEVEE renders and not to what Cycles renders.

A one-quad floor and a box under the SH world and a Sun, as an artist makes it: EEVEE
Transfer + the Sun is as bright as Cycles path tracing of the world and the Sun only with
the bounce; Cycles renders the same bits with or without it; a bake without lamps stores none
(and drops an earlier one); Remove leaves none of it behind.
"""

import blender_scenes as scenes
import bpy
import numpy as np
import pytest
import transfer_scenes as ts
from blender_scenes import run_execute

from sh_lighting.blender.data import compat
from sh_lighting.blender.shading import materials
from sh_lighting.blender.transfer import apply as transfer_apply
from sh_lighting.blender.transfer import bake, bounce, stale
from sh_lighting.blender.ui import operators

SUN_STRENGTH = 4.0


def _scene_with_sun():
    scene, ground, box = ts.lit_ground_and_box(1, 0)
    data = bpy.data.lights.new("Sun", "SUN")
    data.energy = SUN_STRENGTH
    data.angle = 0.02
    sun = bpy.data.objects.new("Sun", data)
    scene.collection.objects.link(sun)
    sun.rotation_euler = (0.7, 0.0, 0.6)
    return scene, ground, box, sun


def _bounce_nodes(material):
    return [n for n in material.node_tree.nodes
            if n.bl_idname == "ShaderNodeGroup" and n.node_tree == bounce.find_group()]


def test_a_bake_with_lamps_stores_their_bounce_and_one_without_drops_it(addon):
    scene, ground, box, sun = _scene_with_sun()
    info = bake.bake_transfer(scene, [ground, box], samples=16)
    assert len(info.basis_seconds) == 10 and any("bounce of 1 lamp" in n for n in info.notes)
    assert bake.record(ground)["store"] == "TEXELS" and bake.record(box)["bounce"] is True
    values = np.array([d.color[:3] for d in box.data.color_attributes[stale.BOUNCE_ATTRIBUTE].data])
    assert values.max() > 0.05 and values.min() >= 0.0  # the lit floor lights the box's sides
    assert stale.bounce_image() is not None
    bpy.data.objects.remove(sun)
    info = bake.bake_transfer(scene, [ground, box], samples=4)
    assert len(info.basis_seconds) == 9 and bake.record(box)["bounce"] is False
    assert box.data.color_attributes.get(stale.BOUNCE_ATTRIBUTE) is None
    assert bpy.data.images.get(stale.BOUNCE_IMAGE) is None


@pytest.mark.slow
def test_eevee_gets_the_lamps_bounce_and_cycles_does_not(addon, tmp_path):
    scene, ground, box, _sun = _scene_with_sun()
    scene.render.engine = "CYCLES"
    scene.cycles.samples = 256
    reference, alpha, _ = scenes.render(scene, tmp_path / "reference.exr")
    covered = (alpha > 0.999)[..., None].repeat(3, axis=-1)
    bake.bake_transfer(scene, [ground, box], samples=32)
    result = transfer_apply.apply_transfer([ground, box], scene, "KEEP_BSDF")
    assert result.changed
    grey = box.data.materials[0]
    (node,) = _bounce_nodes(grey)
    eevee_outputs = [n for n in grey.node_tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial"
                     and n.target == "EEVEE"]
    assert eevee_outputs

    renders = {}
    for engine in ("CYCLES", compat.eevee_engine_id()):
        scene.render.engine = engine
        scene.cycles.samples = 16
        for muted in (False, True):
            node.mute = muted
            renders[engine, muted] = scenes.render(scene, tmp_path / f"{engine}{muted}.exr")[0]
    node.mute = False
    assert np.array_equal(renders["CYCLES", False], renders["CYCLES", True])  # Cycles' own
    eevee = compat.eevee_engine_id()
    with_bounce = renders[eevee, False][covered].mean() / reference[covered].mean()
    without = renders[eevee, True][covered].mean() / reference[covered].mean()
    print(f"\nEEVEE brightness with the lamps' bounce {with_bounce:.3f}, without {without:.3f}")
    assert abs(with_bounce - 1.0) < 0.05 and abs(with_bounce - 1.0) < abs(without - 1.0)


def test_remove_takes_the_bounce_out_and_emission_only_gets_none(addon):
    scene, ground, box, _sun = _scene_with_sun()
    bake.bake_transfer(scene, [ground, box], samples=4)
    grey = box.data.materials[0]
    before = {n.name for n in grey.node_tree.nodes}
    transfer_apply.apply_transfer([ground, box], scene, "EMISSION")
    assert not _bounce_nodes(grey)
    materials.remove_from_materials([grey])
    transfer_apply.apply_transfer([ground, box], scene, "KEEP_BSDF")
    assert len(_bounce_nodes(grey)) == 1
    materials.remove_from_materials([grey])
    assert {n.name for n in grey.node_tree.nodes} == before
    assert sorted(transfer_apply.delete_bakes([ground, box])) == sorted([ground.name, box.name])
    assert box.data.color_attributes.get(stale.BOUNCE_ATTRIBUTE) is None
    assert bpy.data.images.get(stale.BOUNCE_IMAGE) is None


def test_the_default_apply_in_eevee_bakes_and_adds_the_bounce(addon):
    """As an artist: a Sun in the scene, EEVEE, Apply in the default mode, objects selected."""
    scene, ground, box, _sun = _scene_with_sun()
    scene.render.engine = compat.eevee_engine_id()
    for obj in (ground, box):
        obj.select_set(True)
    assert scene.sh_lighting.apply_mode == "AUTO"
    result, reports = run_execute(operators.SHLIGHT_OT_apply)
    assert result == {"FINISHED"}, reports
    assert bake.record(box)["bounce"] is True and bake.record(ground)["bounce"] is True
    (node,) = _bounce_nodes(box.data.materials[0])
    assert node.outputs["Shader"].is_linked
