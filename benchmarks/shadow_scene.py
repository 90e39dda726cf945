"""A sphere on a ground plane under an HDRI world (plus lamps): the scene with shadows that
tests/blender/shading/test_keep_bsdf.py renders for its proofs and bench_lights.py for the report.

Unit UV sphere (smooth) standing on a 8 × 8 plane, white materials, an orthographic camera
looking down at 35°, Cycles CPU with the exact-comparison settings of ``render_bench``
(no denoising or dithering, pixel filter 0.01 px, 'Standard' view, float EXR) and the world
texture read with 'Closest' interpolation (the piecewise constant map the core integrates).
"""

import time
from pathlib import Path

import bpy
import numpy as np

from sh_lighting.blender.data import compat
from sh_lighting.blender.world.images import load_image_pixels
from tests.blender_scenes import environment_world

from .render_bench import _settings, add_camera

CAMERA = (0.0, -6.0, 4.2)
ORTHO = 5.0


def diffuse_material(name, colour=(1.0, 1.0, 1.0)):
    """A material whose Surface is one Diffuse BSDF of ``colour``."""
    material = bpy.data.materials.new(name)
    tree = compat.ensure_node_tree(material)
    for node in [n for n in tree.nodes if n.bl_idname != "ShaderNodeOutputMaterial"]:
        tree.nodes.remove(node)
    bsdf = tree.nodes.new("ShaderNodeBsdfDiffuse")
    bsdf.inputs["Color"].default_value = (*colour, 1.0)
    tree.links.new(bsdf.outputs["BSDF"], tree.nodes["Material Output"].inputs["Surface"])
    return material


def principled_material(name, **inputs):
    """A white Principled BSDF material with the given inputs (e.g. Metallic=0.5)."""
    material = bpy.data.materials.new(name)
    bsdf = compat.ensure_node_tree(material).nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    for key, value in inputs.items():
        bsdf.inputs[key.replace("_", " ")].default_value = value
    return material


class ShadowScene:
    """The scene in a fresh (factory) Blender; ``render`` writes into ``workdir``."""

    def __init__(self, hdri_path, size, workdir, strength=1.0):
        bpy.ops.wm.read_factory_settings(use_empty=True)
        self.scene = bpy.context.scene
        self.size = size
        self.workdir = Path(workdir)
        self.count = 0
        self.hdri = bpy.data.images.load(str(hdri_path), check_existing=False)
        self.world = environment_world(self.scene, self.hdri, strength,
                                       interpolation="Closest", name="HDRI")
        bpy.ops.mesh.primitive_uv_sphere_add(radius=1.0, segments=64, ring_count=32,
                                             location=(0.0, 0.0, 1.0))
        self.sphere = bpy.context.object
        bpy.ops.object.shade_smooth()
        bpy.ops.mesh.primitive_plane_add(size=8.0)
        self.plane = bpy.context.object
        for obj in (self.sphere, self.plane):
            obj.data.materials.append(diffuse_material(f"White {obj.name}"))
        add_camera(self.scene, CAMERA, ORTHO)
        _settings(self.scene, size, "CYCLES")
        self.scene.cycles.max_bounces = 4
        self.scene.render.film_transparent = True

    def use_gradient_world(self, a=0.6, b=0.3):
        """A procedural world of radiance L(ω) = a + b z (grey), whose 9 coefficients are
        exact: L00 = 2√π a, L10 = 2√(π/3) b, the rest 0 (irradiance π a + (2π/3) b n_z).
        Returns them (9, 3)."""
        world = bpy.data.worlds.new("Gradient")
        tree = compat.ensure_node_tree(world)
        coordinate = tree.nodes.new("ShaderNodeTexCoord")
        separate = tree.nodes.new("ShaderNodeSeparateXYZ")
        ramp = tree.nodes.new("ShaderNodeMath")
        ramp.operation = "MULTIPLY_ADD"
        ramp.inputs[1].default_value, ramp.inputs[2].default_value = b, a
        tree.links.new(coordinate.outputs["Generated"], separate.inputs[0])
        tree.links.new(separate.outputs["Z"], ramp.inputs[0])
        tree.links.new(ramp.outputs[0], tree.nodes["Background"].inputs["Color"])
        self.world = self.scene.world = world
        coeffs = np.zeros((9, 3))
        coeffs[0], coeffs[2] = 2.0 * np.sqrt(np.pi) * a, 2.0 * np.sqrt(np.pi / 3.0) * b
        return coeffs

    def hdri_pixels(self):
        """The world image as the core sees it: float32 (H, W, 4), rows top to bottom."""
        return load_image_pixels(bpy.path.abspath(self.hdri.filepath))

    def add_sun(self, direction, strength, angle=0.0, colour=(1.0, 1.0, 1.0)):
        """A Sun lamp shining from unit ``direction`` (toward the sun), ``strength`` W/m²."""
        from mathutils import Vector

        light = bpy.data.lights.new("Key", type="SUN")
        light.energy, light.angle, light.color = strength, angle, colour
        obj = bpy.data.objects.new("Key", light)
        obj.rotation_euler = Vector(direction).to_track_quat("Z", "Y").to_euler()
        self.scene.collection.objects.link(obj)
        return obj

    def render(self, samples=1, seed=0):
        """(seconds, RGBA float32 (size, size, 4) rows top to bottom) of one Cycles render."""
        self.count += 1
        self.scene.cycles.samples = samples
        self.scene.cycles.seed = seed
        path = self.workdir / f"shadow{self.count:03d}.exr"
        self.scene.render.filepath = str(path)
        start = time.perf_counter()
        bpy.ops.render.render(write_still=True)
        return time.perf_counter() - start, load_image_pixels(path)


def covered(image):
    """Pixels fully covered by an object (alpha 1)."""
    return image[..., 3] > 0.999


def mean_deviation(image, reference, mask):
    """Mean |image − reference| over ``mask`` and RGB, relative to the reference's mean."""
    a = image[mask][:, :3].astype(np.float64)
    b = reference[mask][:, :3].astype(np.float64)
    return float(np.abs(a - b).mean() / b.mean())
