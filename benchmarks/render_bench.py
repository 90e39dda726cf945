"""Renders for `python -m benchmarks.report`: a white diffuse sphere under an HDRI.

The same sphere (albedo 1, orthographic camera) by Cycles path tracing of the HDRI world at
several sample counts, by the "SH Irradiance" group (Emission of albedo · E / π, eq. 13) at
1 sample without the world, and optionally by EEVEE (the group, and its own world lighting).
Exact-pixel float EXRs; the world texture is 'Closest', so the truth of each pixel is
``reference_irradiance(hdri, n) / π`` at its shading normal n (from an extra render of
(n + 1)/2): exact for a convex sphere.
"""

import time
from math import pi
from pathlib import Path

import bpy
import numpy as np
from mathutils import Vector

from sh_lighting.blender.data import compat, scene_data
from sh_lighting.blender.shading import materials
from sh_lighting.blender.world.images import load_image_pixels
from sh_lighting.core import project_equirect, reference_irradiance
from tests.blender_scenes import environment_world

CAMERA_LOCATION = (3.0, -4.0, 2.5)
ORTHO_SCALE = 2.3
EEVEE_NATIVE_SAMPLES = 16


def add_camera(scene, location=CAMERA_LOCATION, ortho_scale=ORTHO_SCALE):
    """An orthographic camera at ``location`` looking at the origin, made the scene's camera
    (also used by tests/blender/shading/test_node_group.py)."""
    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    camera.data.type = "ORTHO"
    camera.data.ortho_scale = ortho_scale
    scene.collection.objects.link(camera)
    camera.location = location
    camera.rotation_euler = (-Vector(location)).to_track_quat("-Z", "Y").to_euler()
    scene.camera = camera
    return camera


def _settings(scene, size, engine):
    scene.render.engine = engine
    scene.render.resolution_x = scene.render.resolution_y = size
    scene.render.resolution_percentage = 100
    scene.render.dither_intensity = 0.0
    scene.render.film_transparent = True
    scene.render.filter_size = 0.0  # EEVEE's pixel filter
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    cycles = scene.cycles
    cycles.device = "CPU"
    cycles.use_adaptive_sampling = False
    cycles.use_denoising = False
    cycles.filter_width = 0.01
    cycles.sample_clamp_direct = 0.0
    cycles.sample_clamp_indirect = 0.0
    cycles.max_bounces = 1  # a convex sphere never sees itself
    settings = scene.render.image_settings
    if hasattr(settings, "media_type"):  # 5.0
        settings.media_type = "IMAGE"
    settings.file_format = "OPEN_EXR"
    settings.color_mode = "RGBA"
    settings.color_depth = "32"
    settings.exr_codec = "NONE"


def _material(name, kind):
    """'diffuse': white Diffuse BSDF; 'normal': Emission (n + 1)/2; 'sh': the SH group."""
    material = bpy.data.materials.new(name)
    tree = compat.ensure_node_tree(material)
    output = tree.nodes["Material Output"]
    bsdf = tree.nodes["Principled BSDF"]
    if kind == "sh":
        bsdf.inputs["Base Color"].default_value = (1.0, 1.0, 1.0, 1.0)
        return material  # materials.apply_to_materials wires the group in later
    tree.nodes.remove(bsdf)
    if kind == "diffuse":
        node = tree.nodes.new("ShaderNodeBsdfDiffuse")
        node.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
        tree.links.new(node.outputs["BSDF"], output.inputs["Surface"])
        return material
    geometry = tree.nodes.new("ShaderNodeNewGeometry")
    encode = tree.nodes.new("ShaderNodeVectorMath")
    encode.operation = "MULTIPLY_ADD"
    encode.inputs[1].default_value = (0.5, 0.5, 0.5)
    encode.inputs[2].default_value = (0.5, 0.5, 0.5)
    tree.links.new(geometry.outputs["Normal"], encode.inputs[0])
    emission = tree.nodes.new("ShaderNodeEmission")
    tree.links.new(encode.outputs["Vector"], emission.inputs["Color"])
    tree.links.new(emission.outputs["Emission"], output.inputs["Surface"])
    return material


class SphereScene:
    """The benchmark scene in a fresh (factory) Blender; renders into ``workdir``."""

    def __init__(self, hdri_path, size, workdir):
        bpy.ops.wm.read_factory_settings(use_empty=True)
        self.scene = bpy.context.scene
        self.size = size
        self.workdir = Path(workdir)
        self.count = 0
        self.hdri = bpy.data.images.load(str(hdri_path), check_existing=False)
        self.world = environment_world(self.scene, self.hdri, interpolation="Closest",
                                       name="HDRI")
        self.materials = {kind: _material(kind, kind) for kind in ("diffuse", "normal", "sh")}
        bpy.ops.mesh.primitive_uv_sphere_add(radius=1.0, segments=64, ring_count=32)
        self.sphere = bpy.context.object
        bpy.ops.object.shade_smooth()
        self.sphere.data.materials.append(self.materials["diffuse"])
        add_camera(self.scene)
        _settings(self.scene, size, "CYCLES")

    def hdri_pixels(self):
        """The world image as the core sees it: float32 (H, W, 4), rows top to bottom."""
        return load_image_pixels(bpy.path.abspath(self.hdri.filepath))

    def use(self, kind, engine="CYCLES", samples=1, world=True):
        self.sphere.data.materials[0] = self.materials[kind]
        self.scene.world = self.world if world else None
        _settings(self.scene, self.size, engine)
        self.scene.cycles.samples = samples
        if engine != "CYCLES":
            self.scene.eevee.taa_render_samples = samples

    def set_sh(self, coeffs):
        result = materials.apply_to_materials([self.materials["sh"]], self.scene, mode="EMISSION")
        if result.changed != [self.materials["sh"].name]:
            raise RuntimeError(f"could not apply the SH group: {result}")
        scene_data.store(self.scene, coeffs, {"source": "SCRIPT"})

    def render(self, repeats=1):
        """Render ``repeats`` times; returns (the shortest time in seconds, the last image as
        RGBA float32 (size, size, 4), rows top to bottom). Cycles' fixed seed makes the
        repeats identical images; the minimum time is the least disturbed by other load."""
        times = []
        for _ in range(repeats):
            self.count += 1
            path = self.workdir / f"render{self.count:03d}.exr"
            self.scene.render.filepath = str(path)
            start = time.perf_counter()
            bpy.ops.render.render(write_still=True)
            times.append(time.perf_counter() - start)
        return min(times), load_image_pixels(path)


def mean_relative_error(rgb, truth):
    """Mean over pixels and channels of |rgb − truth| / truth."""
    return float(np.mean(np.abs(rgb - truth) / truth))


def run(hdri_path, size, sample_counts, workdir, eevee=False,
        reference_fn=reference_irradiance, log=print, repeats=1):
    """All renders of the benchmark; returns a dict of timings, errors and images.

    Each Cycles configuration is rendered ``repeats`` times and its shortest time kept.

    ``reference_fn(pixels, normals)`` gives the exact irradiance (by default
    ``reference_irradiance``).
    """
    s = SphereScene(hdri_path, size, workdir)
    out = {"size": size, "hdri": Path(hdri_path).stem, "cycles": [], "eevee": []}

    s.use("normal")
    _, normal_image = s.render()
    covered = normal_image[..., 3] > 0.999
    normals = 2.0 * normal_image[covered][:, :3].astype(np.float64) - 1.0
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    pixels = s.hdri_pixels()
    start = time.perf_counter()
    truth = reference_fn(pixels, normals) / pi
    out["reference_seconds"] = time.perf_counter() - start
    out["pixels"] = int(covered.sum())
    log(f"  ground truth at {covered.sum()} pixel normals: {out['reference_seconds']:.1f} s")

    def error_of(image):
        alpha_ok = image[..., 3][covered] > 0.999
        rgb = image[covered][:, :3].astype(np.float64)
        return mean_relative_error(rgb[alpha_ok], truth[alpha_ok])

    # SH: prefilter (timed) then one Cycles sample, world removed.
    start = time.perf_counter()
    coeffs = project_equirect(pixels)
    out["prefilter_seconds"] = time.perf_counter() - start
    s.set_sh(coeffs)
    s.use("sh", world=False)
    s.render()  # warm-up: the first render of a session pays one-off costs
    seconds, image = s.render(repeats)
    error = error_of(image)
    out["sh_cycles"] = {"seconds": seconds, "error": error, "image": image[..., :3]}
    log(f"  SH node group, Cycles 1 sample: {seconds:.2f} s, error {error:.4f}")
    s.use("sh", world=True)  # the same, with the HDRI kept as the visible background
    s.render()
    seconds, image = s.render(repeats)
    error = error_of(image)
    out["sh_cycles_world"] = {"seconds": seconds, "error": error}
    log(f"  SH node group, Cycles 1 sample, HDRI world kept: {seconds:.2f} s, error {error:.4f}")

    s.use("diffuse", samples=1)
    s.render()  # warm-up with the world
    for samples in sample_counts:
        s.use("diffuse", samples=samples)
        seconds, image = s.render(repeats)
        error = error_of(image)
        out["cycles"].append(
            {"samples": samples, "seconds": seconds, "error": error, "image": image[..., :3]}
        )
        log(f"  Cycles {samples:5d} samples: {seconds:7.2f} s, error {error:.4f}")

    if eevee:
        engine = compat.eevee_engine_id()
        runs = (
            ("sh", "SH node group", False, 1),
            ("diffuse", "own world lighting (Diffuse BSDF)", True, EEVEE_NATIVE_SAMPLES),
        )
        for kind, label, world, samples in runs:
            s.use(kind, engine=engine, samples=samples, world=world)
            for attempt in ("first", "second"):
                seconds, image = s.render()
                error = error_of(image)
                out["eevee"].append(
                    {"what": label, "samples": samples, "attempt": attempt,
                     "seconds": seconds, "error": error, "image": image[..., :3]}
                )
                log(f"  EEVEE {label}, {attempt} render: {seconds:.2f} s, error {error:.4f}")
    out["truth"] = truth
    out["covered"] = covered
    bpy.ops.wm.read_factory_settings(use_empty=True)
    return out
