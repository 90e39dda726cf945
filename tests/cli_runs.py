"""Shared by the command-line tests: running ``python -m sh_lighting`` in a fresh process with
a temporary HOME and Blender user folder, and the tiny inputs (a constant-colour EXR, a .blend
with a grey sphere lit by it, the exact preset).
"""

import atexit
import math
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import bpy
import numpy as np
from blender_files import write_exr

from sh_lighting.formats.presets import write_preset

ROOT = Path(__file__).resolve().parents[1]
SKY = (0.2, 0.5, 1.5)
ALBEDO = 0.5
EXACT = np.zeros((9, 3))
EXACT[0] = 2.0 * math.sqrt(math.pi) * np.array(SKY)
SIZE = (32, 16)
HOME = tempfile.mkdtemp(prefix="sh_lighting_test_home_")
atexit.register(shutil.rmtree, HOME, ignore_errors=True)


def run(*args, cwd=ROOT, env_extra=None, python_args=("-m", "sh_lighting"), timeout=120):
    """Run the command line in a fresh process; returns the CompletedProcess.

    HOME and Blender's user folder are a temporary folder: nothing touches the real ones.
    """
    env = {**os.environ, "PYTHONPATH": str(ROOT), "HOME": HOME,
           "BLENDER_USER_RESOURCES": os.path.join(HOME, "blender"), **(env_extra or {})}
    env.pop("BLENDER_USER_SCRIPTS", None)
    env.pop("BLENDER_USER_CONFIG", None)
    return subprocess.run(
        [sys.executable, *python_args, *map(str, args)],
        cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout,
    )




def constant_pixels(rgb, height=8, width=16):
    pixels = np.ones((height, width, 4), dtype=np.float32)
    pixels[..., :3] = rgb
    return pixels


def build_blend(path, hdri):
    """Sphere with a grey Principled material, an Environment Texture world, camera, EXR out."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    mesh = bpy.data.meshes.new("Ball")
    import bmesh

    bm = bmesh.new()
    bmesh.ops.create_uvsphere(bm, u_segments=32, v_segments=16, radius=1.0)
    bm.to_mesh(mesh)
    bm.free()
    for polygon in mesh.polygons:
        polygon.use_smooth = True
    ball = bpy.data.objects.new("Ball", mesh)
    scene.collection.objects.link(ball)
    material = bpy.data.materials.new("Grey")
    if material.node_tree is None:
        material.use_nodes = True
    bsdf = next(n for n in material.node_tree.nodes if n.type == "BSDF_PRINCIPLED")
    bsdf.inputs["Base Color"].default_value = (ALBEDO, ALBEDO, ALBEDO, 1.0)
    mesh.materials.append(material)

    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    camera.data.type = "ORTHO"
    camera.data.ortho_scale = 4.0
    camera.location = (0.0, -5.0, 0.0)
    camera.rotation_euler = (math.pi / 2, 0.0, 0.0)
    scene.collection.objects.link(camera)
    scene.camera = camera

    world = bpy.data.worlds.new("Sky")
    if world.node_tree is None:
        world.use_nodes = True
    tree = world.node_tree
    background = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeBackground")
    texture = tree.nodes.new("ShaderNodeTexEnvironment")
    texture.image = bpy.data.images.load(str(hdri))
    tree.links.new(texture.outputs["Color"], background.inputs["Color"])
    world.cycles.sampling_method = "NONE"  # no importance map: 2.5 s less per frame
    scene.world = world

    render = scene.render
    render.engine = "CYCLES"
    render.resolution_x, render.resolution_y = SIZE
    render.resolution_percentage = 100
    render.dither_intensity = 0.0
    render.image_settings.file_format = "OPEN_EXR"
    render.image_settings.color_depth = "32"
    scene.view_settings.view_transform = "Standard"
    scene.cycles.samples = 4
    scene.cycles.use_denoising = False
    scene.cycles.device = "CPU"
    bpy.ops.wm.save_as_mainfile(filepath=str(path), copy=True)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    return path


def table_row(stdout, name):
    """The R, G, B numbers printed for coefficient ``name``."""
    for line in stdout.splitlines():
        parts = line.split()
        if parts and parts[0] == name:
            return [float(v) for v in parts[1:4]]
    raise AssertionError(f"no {name} row in:\n{stdout}")


def hidden_files(folder):
    return [p.name for p in Path(folder).iterdir() if p.name.startswith(".")]


def make_inputs(folder):
    """{"hdri", "blend", "preset"}: the constant sky as an EXR, a scene lit by it, its preset."""
    folder = Path(folder)
    hdri = Path(write_exr(folder / "sky.exr", constant_pixels(SKY)))
    blend = build_blend(folder / "scene.blend", hdri)
    preset = write_preset(folder / "sky.json", EXACT, {"name": "sky"})
    return {"hdri": hdri, "blend": blend, "preset": preset}
