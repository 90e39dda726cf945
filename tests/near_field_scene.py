"""A linear luminaire close over a floor, rendered by Cycles: the far-field fit, the near field's
cells, and a dense grid of the exact IES light over the luminous opening (the reference).

The luminaire is Prolicht E30-0019 (tests/data, a real measurement, 1.195 × 0.21 m opening)
``HEIGHT`` m over a floor seen from above (an orthographic camera, ``SPAN`` m square). Only
the representation differs: every light is a point (radius 0) rendered alone with one sample
and a 0.01 px filter, which is its exact direct illuminance, and the maps are summed (Cycles
picks one light per sample, so one render of them all would be noisy). The reference spreads
the file's own distribution (Blender's IES node, the luminaire's packed text) evenly over the
opening: ``GRID`` (along the length, along the width) point lights of 1/count the power each.
"""

import math
import time
from pathlib import Path

import bpy
import numpy as np
from blender_scenes import read_exr
from luminaire_scenes import direct_light_scene

from sh_lighting.blender.luminaire import build

FILE = Path(__file__).resolve().parent / "data" / "photometry" / "prolicht_e30_0019.ldt"
HEIGHT = 0.45  # metres over the floor: 0.38 × the opening's 1.195 m, deep in its near field
SPAN = 3.0  # metres of floor seen
SIZE = 40  # pixels
GRID = (16, 4)  # the reference's lights along the opening's length (local Y) and width (X)


def floor_scene(size=SIZE):
    scene, material = direct_light_scene(size)
    mesh = bpy.data.meshes.new("Floor")
    mesh.from_pydata([(-5, -5, 0), (5, -5, 0), (5, 5, 0), (-5, 5, 0)], [], [(0, 1, 2, 3)])
    mesh.materials.append(material)
    floor = bpy.data.objects.new("Floor", mesh)
    scene.collection.objects.link(floor)
    data = bpy.data.cameras.new("cam_floor")
    data.type, data.ortho_scale, data.clip_end = "ORTHO", SPAN, 100.0
    camera = bpy.data.objects.new("cam_floor", data)
    camera.location = (0.0, 0.0, 10.0)
    scene.collection.objects.link(camera)
    scene.camera = camera
    return scene


def render_floor(scene, folder, tag):
    """E on the floor (π × the rendered radiance), rows top to bottom."""
    path = Path(folder) / f"{tag}.exr"
    scene.render.filepath = str(path)
    bpy.ops.render.render(write_still=True)
    layer = scene.view_layers[0].name
    return math.pi * read_exr(path)[f"{layer}.Combined.R"].astype(np.float64)


def render_each(scene, lights, folder, tag):
    """The sum of each light's render alone (every other light in the scene hidden)."""
    everything = [o for o in scene.objects if o.type == "LIGHT"]
    total = 0.0
    for light in lights:
        for other in everything:
            other.hide_render = other is not light
        total = total + render_floor(scene, folder, tag)
    for other in everything:
        other.hide_render = False
    return total


def _as_points(objects):
    for obj in objects:
        obj.data.shadow_soft_size = 0.0
        if obj.data.node_tree is not None:  # the EEVEE lamps emit in Cycles here
            emission = obj.data.node_tree.nodes["Emission"]
            if not emission.inputs["Strength"].links:
                emission.inputs["Strength"].default_value = 1.0


def reference_lights(scene, root, text, grid=GRID):
    """``grid`` IES point lights over the opening, 1/count of the luminaire's power each."""
    length, width = (abs(v) for v in root.data[build.INFO]["opening_m"][:2])
    count = grid[0] * grid[1]
    made = []
    for i in range(grid[0]):
        for j in range(grid[1]):
            data = bpy.data.lights.new(f"ref {i} {j}", "POINT")
            data.energy = root.data.energy / count
            data.shadow_soft_size = 0.0
            if data.node_tree is None:
                data.use_nodes = True
            ies = data.node_tree.nodes.new("ShaderNodeTexIES")
            ies.mode, ies.ies = "INTERNAL", text
            data.node_tree.links.new(ies.outputs["Fac"],
                                     data.node_tree.nodes["Emission"].inputs["Strength"])
            obj = bpy.data.objects.new(data.name, data)
            y = ((i + 0.5) / grid[0] - 0.5) * length
            x = ((j + 0.5) / grid[1] - 0.5) * width
            obj.location = (root.location.x + x, root.location.y + y, root.location.z)
            scene.collection.objects.link(obj)
            made.append(obj)
    return made


def relative_rmse(a, b):
    return float(np.sqrt(np.mean((a - b) ** 2)) / np.sqrt(np.mean(b ** 2)))


def measure(folder, lamps=2, height=HEIGHT, grid=GRID, path=FILE):
    """{"far": …, "near": …, "cycles_cells": …, "ies": … relative RMSE against the reference,
    and the counts and seconds}: (a) the far-field fit, (b) the near field's EEVEE cells,
    Cycles' near-field cells, and the one exact IES light (Cycles' far field)."""
    scene = floor_scene()
    started = time.perf_counter()
    settings = build.FitSettings(max_lamps=lamps)
    info = build.add_luminaire(scene, path, location=(0.0, 0.0, height), settings=settings)
    fit_seconds = time.perf_counter() - started
    root, text = info.root, build.ies_text_of(scene, info.root)
    _as_points([root, *info.lamps])
    maps = {"ies": render_each(scene, [root], folder, "ies"),
            "far": render_each(scene, info.lamps, folder, "far")}
    reference = reference_lights(scene, root, text, grid)
    maps["reference"] = render_each(scene, reference, folder, "reference")
    for obj in reference:
        data = obj.data
        bpy.data.objects.remove(obj)
        bpy.data.lights.remove(data)
    near = build.refit(scene, root, build.FitSettings(max_lamps=lamps, near_distance=height))
    _as_points([*near.lamps, *near.cycles_cells])
    maps["root_when_near"] = render_each(scene, [root], folder, "root")
    maps["near"] = render_each(scene, near.lamps, folder, "near")
    maps["cycles_cells"] = render_each(scene, near.cycles_cells, folder, "cells")
    errors = {k: relative_rmse(maps[k], maps["reference"])
              for k in ("ies", "far", "near", "cycles_cells")}
    cells = root.data[build.INFO]["cells"]
    return {"errors": errors, "maps": maps, "cells": tuple(cells), "fit_lamps": len(info.lamps),
            "near_lamps": len(near.lamps), "fit_seconds": fit_seconds,
            "opening_m": tuple(root.data[build.INFO]["opening_m"]), "root": root}
