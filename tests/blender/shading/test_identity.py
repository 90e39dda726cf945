"""What Apply makes is the add-on's by identity, never by a mark a copy inherits: the
reflection maps (``shading.glossy``) follow their world through a rename and a new image, a
copied world gets its own; Remove deletes only what the add-on made (never a user's copy of a
map, of the world's EEVEE nodes or of the SH node); Apply says when a material shown in
another scene now reflects this scene's world there."""

import bpy
import numpy as np
import pytest

from benchmarks.shadow_scene import ShadowScene, principled_material
from sh_lighting import api
from sh_lighting.blender.shading import glossy, materials, notes, world_diffuse

pytestmark = pytest.mark.blender


@pytest.fixture
def applied(addon, hdri_dir, tmp_path):
    """A glossy sphere under forest.exr, Keep BSDF applied: the world has its maps."""
    s = ShadowScene(hdri_dir / "forest.exr", 8, tmp_path)
    s.sphere.data.materials[0] = principled_material("Glossy", Metallic=0.8, Roughness=0.5)
    api.compute_from_world(s.scene)
    s.mats = materials.materials_of(s.scene.objects)
    materials.apply_to_materials(s.mats, s.scene, "KEEP_BSDF")
    return s


def shown_maps(material):
    """The reflection maps the material's nodes look up, by roughness level."""
    return [n.image for n in material.node_tree.nodes
            if n.bl_idname == "ShaderNodeTexEnvironment" and n.label.startswith(f"{glossy.LABEL} r = ")]


def mean(image):
    pixels = np.empty(len(image.pixels), np.float32)
    image.pixels.foreach_get(pixels)
    return pixels.reshape(-1, 4)[:, :3].mean()


def made_images():
    return sorted(image.name for image in bpy.data.images if glossy.is_made(image))


def test_maps_follow_a_renamed_world_and_its_new_brightness(applied):
    s = applied
    glossy_material = s.sphere.data.materials[0]
    shown = shown_maps(glossy_material)
    assert len(shown) > 1 and shown == glossy.maps_of(s.world)
    before = mean(shown[-1])
    s.world.name = "Renamed sky"
    s.world.node_tree.nodes["Background"].inputs["Strength"].default_value = 5.0
    api.compute_from_world(s.scene)
    assert glossy.maps_of(s.world) == shown_maps(glossy_material)  # the material's, rewritten
    assert mean(shown_maps(glossy_material)[-1]) == pytest.approx(5.0 * before, rel=1e-5)


def test_remove_deletes_the_add_ons_maps_and_never_a_users_copy(applied):
    s = applied
    ours = made_images()
    assert len(ours) == len(glossy.maps_of(s.world)) + 1  # and the split-sum table
    copy = glossy.maps_of(s.world)[0].copy()  # the user's: it inherits the custom property
    table_copy = glossy.table_image().copy()
    assert glossy.IMAGE_MARKER in copy and glossy.IMAGE_MARKER in table_copy
    mine = bpy.data.materials.new("Mine")
    mine.use_nodes = True
    texture = mine.node_tree.nodes.new("ShaderNodeTexEnvironment")
    texture.image = copy
    assert made_images() == ours  # a copy is not the add-on's
    materials.remove_from_materials(s.mats)
    assert made_images() == []
    assert copy.name in bpy.data.images and table_copy.name in bpy.data.images
    assert texture.image == copy


def test_compute_never_rewrites_a_users_copy_named_like_a_map(applied):
    s = applied
    shown = glossy.maps_of(s.world)
    copy = shown[-1].copy()
    before = mean(copy)
    s.world.node_tree.nodes["Background"].inputs["Strength"].default_value = 3.0
    api.compute_from_world(s.scene)
    assert mean(copy) == pytest.approx(before)
    assert mean(shown[-1]) == pytest.approx(3.0 * before, rel=1e-5)


def test_a_copied_world_gets_its_own_maps_and_leaves_the_originals(applied):
    s = applied
    originals = glossy.maps_of(s.world)
    levels = [mean(image) for image in originals]
    other = bpy.data.scenes.new("Other")
    other.world = s.world.copy()  # inherits the original world's custom properties
    assert glossy.maps_of(other.world) is None  # the originals are not the copy's
    other.world.node_tree.nodes["Background"].inputs["Strength"].default_value = 4.0
    api.compute_from_world(other)
    assert [mean(image) for image in originals] == pytest.approx(levels)
    assert glossy.maps_of(s.world) == originals


def test_apply_says_when_a_material_shown_in_another_scene_switches_its_reflections(
        applied):
    s = applied
    glossy_material = s.sphere.data.materials[0]
    other = bpy.data.scenes.new("Studio B")
    other.world = s.world.copy()
    other.world.name = "World B"
    other.world.node_tree.nodes["Background"].inputs["Strength"].default_value = 2.0
    api.set_coefficients(other, api.get_coefficients(s.scene))
    holder = bpy.data.objects.new("B sphere", s.sphere.data)  # the same mesh and material
    other.collection.objects.link(holder)
    result = materials.apply_to_materials([glossy_material], other, "KEEP_BSDF")
    assert result.changed == [glossy_material.name]
    lines = notes.shared_scene_notes(other, result.changed)
    assert any(f"scene '{s.scene.name}'" in line and "EEVEE" in line and "'World B'" in line
               and f"'{s.world.name}'" in line for line in lines), lines


def test_remove_leaves_a_users_copy_of_the_worlds_eevee_nodes(applied):
    """The world's EEVEE nodes Apply added are deleted by the names its record holds: a
    user's duplicate (Shift+D copies the node's custom property) stays, and so does a World
    Output of theirs made that way (not taken for ours)."""
    s = applied
    tree = s.world.node_tree
    ours = [n for n in tree.nodes if world_diffuse.NODE_MARKER in n]
    assert len(ours) == 3
    copy = tree.nodes.new("ShaderNodeLightPath")  # what Shift+D of ours makes
    copy[world_diffuse.NODE_MARKER] = True
    name = copy.name
    materials.remove_from_materials(s.mats)
    assert [n.name for n in tree.nodes if world_diffuse.NODE_MARKER in n] == [name]
    assert not world_diffuse.is_prepared(s.world)


def test_remove_leaves_a_users_copy_of_the_sh_node(applied):
    """A Shift+D copy of the SH Irradiance node (its record, a custom property, copied) is the
    user's: Remove restores the material and deletes Apply's node, never the copy."""
    s = applied
    material = s.plane.data.materials[0]
    (ours,) = materials.added_nodes(material)
    copy = material.node_tree.nodes.new("ShaderNodeGroup")
    copy.node_tree = ours.node_tree
    copy[materials.NODE_MARKER] = ours[materials.NODE_MARKER]
    assert materials.added_nodes(material) == [ours]
    materials.remove_from_materials(s.mats)
    assert copy.name in material.node_tree.nodes and not materials.is_applied(material)
