"""Tiny scenes for the transfer tests and benchmark: a ground grid with a box on it, a world
emitting exactly Σ L_lm Y_lm, and the materials a path-traced reference and a transfer render
use."""

import blender_scenes as scenes
import bmesh
import bpy
import numpy as np
from mathutils import Vector

from sh_lighting.blender.data import compat, scene_data
from sh_lighting.blender.transfer import basis
from sh_lighting.blender.transfer import nodes as transfer_nodes
from sh_lighting.core.sh import sh_basis, spread_normals

ALBEDO = 0.8
# Grey lighting (the same in R, G, B): a sky brighter above and towards +X; non-negative
# everywhere (checked by ``sh_world``).
LIGHTING = np.array([2.0, 0.1, 0.8, 0.35, 0.05, 0.0, 0.15, -0.1, 0.08])


def mesh_object(name, build, location=(0.0, 0.0, 0.0)):
    mesh = bpy.data.meshes.new(name)
    bm = bmesh.new()
    build(bm)
    bm.to_mesh(mesh)
    bm.free()
    obj = bpy.data.objects.new(name, mesh)
    obj.location = location
    bpy.context.scene.collection.objects.link(obj)
    return obj


def ground_and_box(ground_cuts=16, box_cuts=3):
    """A 4 m ground grid and a 1 m box standing on it; both with a grey Diffuse BSDF."""
    ground = mesh_object("Ground", lambda bm: bmesh.ops.create_grid(
        bm, x_segments=ground_cuts, y_segments=ground_cuts, size=2.0))

    def box(bm):
        bmesh.ops.create_cube(bm, size=1.0)
        bmesh.ops.subdivide_edges(bm, edges=bm.edges[:], cuts=box_cuts, use_grid_fill=True)

    cube = mesh_object("Box", box, (0.3, 0.2, 0.5))
    material = diffuse_material()
    for obj in (ground, cube):
        obj.data.materials.append(material)
    bpy.context.view_layer.update()
    return ground, cube


def diffuse_material(name="Grey"):
    material = bpy.data.materials.new(name)
    compat.ensure_node_tree(material)
    bsdf = material.node_tree.nodes["Principled BSDF"]
    diffuse = material.node_tree.nodes.new("ShaderNodeBsdfDiffuse")
    diffuse.inputs["Color"].default_value = (ALBEDO, ALBEDO, ALBEDO, 1.0)
    output = material.node_tree.nodes["Material Output"]
    material.node_tree.nodes.remove(bsdf)
    material.node_tree.links.new(diffuse.outputs[0], output.inputs["Surface"])
    return material


def transfer_material(name="Transfer"):
    """Emission of the "SH Transfer" group's Diffuse (albedo ALBEDO): the transfer alone."""
    material = bpy.data.materials.new(name)
    tree = compat.ensure_node_tree(material)
    tree.nodes.remove(tree.nodes["Principled BSDF"])
    group = tree.nodes.new("ShaderNodeGroup")
    group.node_tree = transfer_nodes.ensure_node_group()
    group.inputs["Albedo"].default_value = (ALBEDO, ALBEDO, ALBEDO, 1.0)
    tree.links.new(group.outputs["Shader"], tree.nodes["Material Output"].inputs["Surface"])
    return material


def use_material(objects, material):
    for obj in objects:
        obj.data.materials.clear()
        obj.data.materials.append(material)


def store_lighting(scene, lighting=LIGHTING):
    coeffs = np.repeat(np.asarray(lighting, float)[:, None], 3, axis=1)
    scene_data.store(scene, coeffs, {"source": "SCRIPT"})
    return coeffs


def sh_world(scene, lighting=LIGHTING):
    """A world of radiance Σ L_lm Y_lm(ω) (grey), built from ``basis``' Y_lm nodes."""
    radiance = sh_basis(spread_normals(4000)) @ np.asarray(lighting)
    assert radiance.min() > 0.0, "test lighting must be non-negative"
    world = basis.new_basis_world(0)
    world.name = "SH world"
    tree = world.node_tree
    background = tree.nodes["Background"]
    total = tree.nodes.new("ShaderNodeMath")
    total.operation = "MULTIPLY"
    total.inputs[0].default_value = 1.0
    total.inputs[1].default_value = lighting[0] * basis.Y00
    for index in range(1, 9):
        if lighting[index] == 0.0:
            continue
        value = basis._basis_value(tree, index)
        term = tree.nodes.new("ShaderNodeMath")
        term.operation = "MULTIPLY_ADD"
        tree.links.new(value, term.inputs[0])
        term.inputs[1].default_value = lighting[index]
        tree.links.new(total.outputs[0], term.inputs[2])
        total = term
    tree.links.new(total.outputs[0], background.inputs["Color"])
    world.cycles.sampling_method = "NONE"
    scene.world = world
    return world


def camera(scene, location=(4.5, -4.5, 3.6), target=(0.0, 0.0, 0.3)):
    data = bpy.data.cameras.new("Camera")
    data.lens = 40.0
    obj = bpy.data.objects.new("Camera", data)
    scene.collection.objects.link(obj)
    obj.location = location
    direction = Vector(target) - Vector(location)
    obj.rotation_euler = direction.to_track_quat("-Z", "Y").to_euler()
    scene.camera = obj
    return obj


def lit_ground_and_box(ground_cuts, box_cuts):
    """(scene, ground, box): ``ground_and_box`` seen by ``camera``, lit by ``LIGHTING`` stored
    and emitted by the world, rendered at 48 px and 16 samples."""
    scene = bpy.context.scene
    ground, box = ground_and_box(ground_cuts, box_cuts)
    camera(scene)
    store_lighting(scene)
    sh_world(scene)
    scenes.setup_render(scene, size=48, samples=16)
    return scene, ground, box


def relative_rmse(estimate, reference, mask):
    difference = (estimate - reference)[mask]
    return float(np.sqrt(np.mean(difference ** 2)) / np.sqrt(np.mean(reference[mask] ** 2)))
