"""Apply follows the material as it is now, Cycles renders at 1 sample.

A white sphere under a world of radiance 0.6 + 0.3 z (nine terms exact), no lamps, the world's
glossy and transmission visibility off: each pixel is then the SH emission alone (deterministic
at one sample), and a render's mean over the sphere is proportional to the SH albedo.
"""

import bpy
import pytest

from benchmarks.shadow_scene import ShadowScene, covered, diffuse_material, principled_material
from sh_lighting import api
from sh_lighting.blender.data import compat
from sh_lighting.blender.shading import materials, notes, world_diffuse

SIZE = 24


@pytest.fixture
def sphere(hdri_dir, tmp_path):
    s = ShadowScene(hdri_dir / "studio.exr", SIZE, tmp_path)
    api.set_coefficients(s.scene, s.use_gradient_world())
    s.plane.hide_render = True
    s.world.cycles_visibility.glossy = s.world.cycles_visibility.transmission = False
    s.sphere.visible_glossy = s.sphere.visible_transmission = False
    return s


def _mean(s):
    _, image = s.render(1)
    mask = covered(image)
    return float(image[..., :3][mask].mean()) if mask.any() else 0.0, image


def _use(s, material):
    s.sphere.data.materials[0] = material
    return material


def test_base_colour_edited_or_keyframed_after_apply_is_followed(sphere):
    s = sphere
    material = _use(s, diffuse_material("Keyed", (1.0, 1.0, 1.0)))
    colour = material.node_tree.nodes["Diffuse BSDF"].inputs["Color"]
    colour.keyframe_insert("default_value", frame=1)
    colour.default_value = (0.1, 0.1, 0.1, 1.0)
    colour.keyframe_insert("default_value", frame=2)
    s.scene.frame_set(1)
    assert materials.apply_to_materials([material], s.scene, mode="EMISSION").changed
    white, _ = _mean(s)
    s.scene.frame_set(2)
    keyed, _ = _mean(s)
    assert white > 0.3 and keyed / white == pytest.approx(0.1, rel=1e-4)
    material.node_tree.animation_data.action = None  # now edited by hand, where the panel
    held = colour.links[0].from_node  # shows the colour: on the node now feeding Color
    assert held.bl_idname == "ShaderNodeRGB"
    held.outputs[0].default_value = (0.5, 0.5, 0.5, 1.0)
    edited, _ = _mean(s)
    print(f"\nkeyed white {white:.4f}, keyed 0.1 {keyed / white:.5f}, edited 0.5 "
          f"{edited / white:.5f} of white")
    assert edited / white == pytest.approx(0.5, rel=1e-4)
    materials.remove_from_materials([material])
    assert not colour.is_linked and tuple(colour.default_value) == (0.5, 0.5, 0.5, 1.0)


@pytest.mark.parametrize("mode", materials.MODES)
def test_transparent_materials_do_not_glow(sphere, mode):
    s = sphere
    clear = _use(s, principled_material("Alpha 0", Alpha=0.0))
    assert materials.apply_to_materials([clear], s.scene, mode=mode).changed
    alpha_zero, _ = _mean(s)
    mixed = bpy.data.materials.new("Mix Transparent")
    tree = compat.ensure_node_tree(mixed)
    mix = tree.nodes.new("ShaderNodeMixShader")
    mix.inputs["Fac"].default_value = 0.0  # all Transparent
    tree.links.new(tree.nodes.new("ShaderNodeBsdfTransparent").outputs[0], mix.inputs[1])
    tree.links.new(tree.nodes["Principled BSDF"].outputs[0], mix.inputs[2])
    tree.links.new(mix.outputs[0], tree.nodes["Material Output"].inputs["Surface"])
    _use(s, mixed)
    assert materials.apply_to_materials([mixed], s.scene, mode=mode).changed
    _, image = s.render(1)
    print(f"\n{mode}: Alpha 0 renders {alpha_zero:.4f}, Mix(Transparent) peak "
          f"{image[..., :3].max():.4f}")
    assert alpha_zero < 1e-6 and image[..., :3].max() < 1e-6


def test_mix_with_black_emission_gets_half_the_sh_term(sphere):
    s = sphere
    plain = _use(s, principled_material("Plain", IOR=1.0))
    materials.apply_to_materials([plain], s.scene)  # the default mode
    full, _ = _mean(s)
    half = principled_material("Half", IOR=1.0)
    tree = half.node_tree
    mix = tree.nodes.new("ShaderNodeMixShader")
    emission = tree.nodes.new("ShaderNodeEmission")
    emission.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    tree.links.new(tree.nodes["Principled BSDF"].outputs[0], mix.inputs[1])
    tree.links.new(emission.outputs[0], mix.inputs[2])
    tree.links.new(mix.outputs[0], tree.nodes["Material Output"].inputs["Surface"])
    _use(s, half)
    materials.apply_to_materials([half], s.scene)
    mixed, _ = _mean(s)
    assert full > 0.3 and mixed / full == pytest.approx(0.5, rel=1e-4)
    held = mix.inputs["Fac"].links[0].from_node  # the Fac is held by a Value node now
    held.outputs[0].default_value = 0.75  # followed, no re-Apply
    quarter, _ = _mean(s)
    print(f"\nMix 0.5 with black Emission: {mixed / full:.5f} of the plain BSDF; Fac 0.75: "
          f"{quarter / full:.5f}")
    assert quarter / full == pytest.approx(0.25, rel=1e-4)


def test_surface_from_a_node_group_is_refused_not_given_a_stray_colour(sphere):
    s = sphere
    group = bpy.data.node_groups.new("My Shader", "ShaderNodeTree")
    group.interface.new_socket("Shader", in_out="OUTPUT", socket_type="NodeSocketShader")
    inner = group.nodes.new("ShaderNodeBsdfDiffuse")
    out = group.nodes.new("NodeGroupOutput")
    group.links.new(inner.outputs[0], out.inputs[0])
    material = bpy.data.materials.new("Grouped")
    tree = compat.ensure_node_tree(material)
    tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (1.0, 0.0, 0.0, 1.0)
    tree.nodes["Principled BSDF"].location = (-600, 400)  # stray, unconnected
    node = tree.nodes.new("ShaderNodeGroup")
    node.node_tree = group
    tree.links.new(node.outputs[0], tree.nodes["Material Output"].inputs["Surface"])
    before = len(tree.nodes)
    result = materials.apply_to_materials([material], s.scene)
    assert result.changed == [] and "node group 'My Shader'" in result.skipped[0][1]
    assert len(tree.nodes) == before and s.world.cycles_visibility.diffuse is True


def test_apply_and_remove_reach_the_evaluated_scene_and_restore_emission_sampling(sphere):
    """Open viewports draw the evaluated copies: they must change at once."""
    s = sphere
    material = s.sphere.data.materials[0]
    depsgraph = bpy.context.evaluated_depsgraph_get()
    assert s.world.evaluated_get(depsgraph).cycles_visibility.diffuse is True
    assert material.cycles.emission_sampling == "AUTO"
    materials.apply_to_materials([material], s.scene)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    assert s.world.evaluated_get(depsgraph).cycles_visibility.diffuse is False
    assert material.cycles.emission_sampling == "NONE"
    materials.remove_from_materials([material])
    depsgraph = bpy.context.evaluated_depsgraph_get()
    assert s.world.evaluated_get(depsgraph).cycles_visibility.diffuse is True
    assert material.cycles.emission_sampling == "AUTO"


def test_linked_world_is_refused_with_nothing_changed(sphere, tmp_path):
    s = sphere
    path = tmp_path / "library.blend"
    bpy.data.libraries.write(str(path), {s.world})
    with bpy.data.libraries.load(str(path), link=True) as (source, target):
        target.worlds = [source.worlds[0]]
    linked = target.worlds[0]
    assert linked.library is not None
    s.scene.world = linked
    material = s.sphere.data.materials[0]
    nodes_before = len(material.node_tree.nodes)
    with pytest.raises(world_diffuse.WorldError, match="linked from library"):
        materials.apply_to_materials([material], s.scene)
    assert len(material.node_tree.nodes) == nodes_before
    assert materials.apply_to_materials([material], s.scene, mode="EMISSION").changed


def test_world_switched_after_apply_is_named_by_the_status_line(sphere):
    s = sphere
    materials.apply_to_materials([s.sphere.data.materials[0]], s.scene)
    assert notes.keep_bsdf_warning(s.scene) is None
    s.scene.world = bpy.data.worlds.new("Another")
    warning = notes.keep_bsdf_warning(s.scene)
    assert warning is not None and "'Another'" in warning and "Apply" in warning


def test_a_second_scene_sharing_the_material_is_counted_once_and_told_what_it_lacks(
        sphere, addon):
    """Apply (Keep BSDF) in one scene, the material also shown in a second
    scene with its own world and no coefficients. That world stops giving diffuse light too
    (no double count), and Apply says in its report what that scene then lacks."""
    from blender_scenes import run_execute

    from sh_lighting.blender.ui.operators import SHLIGHT_OT_apply

    s = sphere
    other = bpy.data.scenes.new("Second")
    other.world = bpy.data.worlds.new("Second World")
    other.collection.objects.link(s.sphere)
    plane = bpy.data.objects.new("Own", s.plane.data.copy())
    plane.data.materials[0] = diffuse_material("Own Grey", (0.5, 0.5, 0.5))
    other.collection.objects.link(plane)
    result, reports = run_execute(SHLIGHT_OT_apply, mode="KEEP_BSDF")  # named: in Cycles the default edits the world
    assert result == {"FINISHED"}
    assert materials.mode_of(s.sphere.data.materials[0]) == "KEEP_BSDF"
    assert other.world.evaluated_get(bpy.context.evaluated_depsgraph_get()) \
        .cycles_visibility.diffuse is False
    (kinds, message), = reports
    assert kinds == {"WARNING"}
    assert ("scene 'Second' shows 1 of these material(s), so its world 'Second World' gives no "
            "diffuse light there either, but it has no SH coefficients (Compute there) and its "
            "1 other material(s) ('Own Grey') have no SH (Apply there)") in message
    api.set_coefficients(other, api.get_coefficients(s.scene))
    materials.apply_to_materials([plane.data.materials[0]], other)
    assert notes.shared_scene_notes(s.scene, [s.sphere.data.materials[0].name]) == []
    materials.remove_from_materials(bpy.data.materials)
    assert other.world.cycles_visibility.diffuse is True
