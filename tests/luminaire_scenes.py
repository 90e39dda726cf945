"""A floor and a wall lit by a luminaire 2 m up, rendered by Cycles into illuminance maps.

Direct light only (no bounces), white Diffuse BSDF, black world, a point light of radius 0:
one sample per pixel with a 0.01 px filter is the exact direct illuminance E/π at the pixel's
centre (no noise). The floor is −2h ≤ x ≤ h, |y| ≤ 2h seen from above (the square |x|, |y| ≤ 2h), the wall the plane
x = h (|y| ≤ 2h, 0 ≤ z ≤ 4h) seen from −X, h = 2 m, the luminaire at (0, 0, h). A 1 W
luminaire gives I/177.83 W/sr per candela (Blender's IES scale).
"""

import math

import bpy
import numpy as np
from blender_scenes import black_world, read_exr, setup_render

from sh_lighting.blender.data import compat

HEIGHT = 2.0
SIZE = 48


def direct_light_scene(size=SIZE):
    """(scene, a white Diffuse material): black world, direct light only, ``size`` px."""
    scene = bpy.context.scene
    black_world(scene)
    setup_render(scene, size=size)
    scene.render.film_transparent = False
    scene.cycles.max_bounces = 0
    scene.view_layers[0].use_pass_normal = False
    material = bpy.data.materials.new("White")
    tree = compat.ensure_node_tree(material)
    tree.nodes.clear()
    diffuse = tree.nodes.new("ShaderNodeBsdfDiffuse")
    diffuse.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    out = tree.nodes.new("ShaderNodeOutputMaterial")
    tree.links.new(diffuse.outputs[0], out.inputs["Surface"])
    return scene, material


def scene_with_floor_and_wall(size=SIZE):
    scene, material = direct_light_scene(size)
    h = HEIGHT
    _quad(scene, "Floor", [(-2 * h, -2 * h, 0), (h, -2 * h, 0), (h, 2 * h, 0),
                           (-2 * h, 2 * h, 0)], material)  # up to the wall
    _quad(scene, "Wall", [(h, -2 * h, 0), (h, -2 * h, 4 * h), (h, 2 * h, 4 * h),
                          (h, 2 * h, 0)], material)
    return scene


def _quad(scene, name, corners, material):
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(corners, [], [(0, 1, 2, 3)])
    mesh.materials.append(material)
    obj = bpy.data.objects.new(name, mesh)
    scene.collection.objects.link(obj)
    return obj


def _camera(scene, which):
    h = HEIGHT
    data = bpy.data.cameras.new(which)
    data.type = "ORTHO"
    data.ortho_scale = 4 * h
    data.clip_end = 100.0
    obj = bpy.data.objects.new(which, data)
    if which == "floor":
        obj.location = (0.0, 0.0, 10.0)
    else:  # looking along +X at the wall, image up = +Z, image right = +Y
        obj.location = (-10.0, 0.0, 2 * h)
        obj.rotation_euler = (math.pi / 2, 0.0, -math.pi / 2)
    scene.collection.objects.link(obj)
    return obj


def illuminance_maps(scene, tmp_path, tag):
    """{"floor": E, "wall": E} (rows top to bottom), E = π × the rendered radiance."""
    maps = {}
    for which in ("floor", "wall"):
        camera = scene.objects.get(f"cam_{which}")
        if camera is None:
            camera = _camera(scene, which)
            camera.name = f"cam_{which}"
        scene.camera = camera
        path = tmp_path / f"{tag}_{which}.exr"
        scene.render.filepath = str(path)
        bpy.ops.render.render(write_still=True)
        channels = read_exr(path)
        layer = scene.view_layers[0].name
        maps[which] = math.pi * channels[f"{layer}.Combined.R"].astype(np.float64)
    return maps


def predicted_maps(intensity, size=SIZE):
    """The same maps from a candela function of the light's local directions (1 W)."""
    h = HEIGHT
    u = (np.arange(size) + 0.5) / size * 4 * h - 2 * h  # left to right, top to bottom
    columns, rows = np.meshgrid(u, u)
    # floor from above: image right = +X, down = −Y; points relative to the luminaire
    floor = np.stack([columns, -rows, np.full_like(rows, -h)], axis=-1)
    # wall from −X: image right = −Y, down = −Z, z from 4h down to 0
    wall = np.stack([np.full_like(rows, h), -columns, (2 * h - rows) - h], axis=-1)
    beyond_wall = floor[..., 0] > h
    return {"floor": np.where(beyond_wall, 0.0,
                              _illuminance(intensity, floor, np.array([0.0, 0.0, 1.0]))),
            "wall": _illuminance(intensity, wall, np.array([-1.0, 0.0, 0.0]))}


def _illuminance(intensity, points, normal):
    r = np.linalg.norm(points, axis=-1)
    dirs = points / r[..., None]
    cosine = np.clip(-(dirs @ normal), 0.0, None)
    return intensity(dirs) / 177.83 * cosine / r ** 2


def relative_rmse(a, b):
    return float(np.sqrt(np.mean((a - b) ** 2)) / np.sqrt(np.mean(b ** 2)))
