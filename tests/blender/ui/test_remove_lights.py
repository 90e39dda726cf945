"""Remove after Extract Lights puts the scene back as it was before Apply: the materials, the
world (its nodes and ray visibility) and the lights (the Sun lamps Extract Lights made are
deleted; an artist's duplicate of one stays), and the SH lighting holds the whole world again
(else the sun lit the scene twice: the world and the lamp)."""

import bpy
import numpy as np
from blender_scenes import environment_world
from numpy.testing import assert_allclose

from sh_lighting import api
from sh_lighting.blender.data import compat, scene_data
from sh_lighting.blender.design import lights


def world_state(world):
    tree = world.node_tree
    return (sorted((n.name, n.bl_idname) for n in tree.nodes),
            sorted((link.from_node.name, link.from_socket.identifier, link.to_node.name,
                    link.to_socket.identifier) for link in tree.links),
            world.cycles_visibility.diffuse, world.cycles_visibility.glossy)


def sunrise_scene(hdri_dir):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    environment_world(scene, str(hdri_dir / "sunrise.exr"))
    bpy.ops.mesh.primitive_plane_add(size=8.0)
    floor = bpy.context.object
    floor.data.materials.append(bpy.data.materials.new("Floor"))
    compat.ensure_node_tree(floor.active_material)
    floor.select_set(True)
    return scene, floor


def test_remove_after_extract_lights_deletes_its_suns_and_restores_the_world(addon, hdri_dir):
    scene, _floor = sunrise_scene(hdri_dir)
    assert bpy.ops.shlight.compute_from_world() == {"FINISHED"}
    whole = scene_data.get_coefficients(scene).copy()
    world_before = world_state(scene.world)
    assert bpy.ops.shlight.apply() == {"FINISHED"}
    assert world_state(scene.world) != world_before  # Keep BSDF's EEVEE World Output
    assert bpy.ops.shlight.extract_lights(count=2, use_error_target=False) == {"FINISHED"}
    made = [obj.name for obj in lights.extracted_lights(scene)]
    assert len(made) == 2
    copy = bpy.data.objects[made[0]].copy()  # what Shift+D makes: the artist's own lamp
    scene.collection.objects.link(copy)
    assert bpy.ops.shlight.remove() == {"FINISHED"}
    assert not lights.extracted_lights(scene)
    assert [o.name for o in scene.objects if o.type == "LIGHT"] == [copy.name]
    assert not [c for c in bpy.data.collections if c.name.startswith("SH Lights")]
    assert world_state(scene.world) == world_before
    assert_allclose(scene_data.get_coefficients(scene), whole, rtol=1e-6, atol=1e-6)


def test_remove_keeps_the_suns_while_a_material_is_still_lit_by_sh(addon, hdri_dir):
    """Remove on part of the materials (Emission Only: the world still lights the others)
    leaves the lamps to the materials still applied."""
    scene, floor = sunrise_scene(hdri_dir)
    bpy.ops.mesh.primitive_cube_add()
    cube = bpy.context.object
    cube.data.materials.append(bpy.data.materials.new("Cube"))
    compat.ensure_node_tree(cube.active_material)
    api.compute_from_world(scene)
    for obj in scene.objects:
        obj.select_set(True)
    assert bpy.ops.shlight.apply(mode="EMISSION") == {"FINISHED"}
    api.extract_lights(scene, count=1)
    for obj in scene.objects:
        obj.select_set(obj == floor)
    assert bpy.ops.shlight.remove() == {"FINISHED"}
    assert len(lights.extracted_lights(scene)) == 1
    assert np.isfinite(scene_data.get_coefficients(scene)).all()
