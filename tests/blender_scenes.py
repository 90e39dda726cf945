"""Scenes, worlds, renders and operator stand-ins the Blender tests share (one copy each).

Renders: every pixel check renders colour and the Normal pass together into a multilayer EXR
(read by a small reader for uncompressed scanline EXR, since ``bpy.data.images`` cannot give
the passes of a multilayer file) and compares each covered pixel with the core's
``irradiance(coeffs, normal) / π`` at that pixel's normal.
"""

import inspect
import math
import struct
import subprocess
import sys
import types
from math import pi
from pathlib import Path

import bpy
import numpy as np

from sh_lighting.blender.data import compat
from sh_lighting.core import irradiance
from sh_lighting.core.equirect import texel_directions

RELATIVE_TOLERANCE = 1e-4

# ---------------------------------------------------------------- EXR reading


def read_exr(path):
    """{channel name: (H, W) float32, rows top to bottom} of an uncompressed scanline EXR.

    Handles single- and multi-part files (Blender writes one part per pass), half and float
    channels. Blender is asked for ``exr_codec = 'NONE'`` so no decompression is needed.
    """
    data = Path(path).read_bytes()
    assert data[:4] == b"\x76\x2f\x31\x01", f"{path} is not an OpenEXR file"
    flags = struct.unpack_from("<I", data, 4)[0]
    multipart = bool(flags & 0x1000)
    assert not flags & 0x200, "tiled EXR not supported"
    pos, headers = 8, []
    while True:
        header = {}
        while data[pos] != 0:
            end = data.index(b"\0", pos)
            name = data[pos:end].decode()
            end2 = data.index(b"\0", end + 1)
            size = struct.unpack_from("<i", data, end2 + 1)[0]
            header[name] = data[end2 + 5 : end2 + 5 + size]
            pos = end2 + 5 + size
        pos += 1
        headers.append(header)
        if not multipart or data[pos] == 0:
            pos += 1 if multipart else 0
            break
    parts = []
    for header in headers:
        assert header["compression"][0] == 0, "only uncompressed EXR is read here"
        raw, p, channels = header["channels"], 0, []
        while raw[p] != 0:
            end = raw.index(b"\0", p)
            channels.append((raw[p:end].decode(), struct.unpack_from("<i", raw, end + 1)[0]))
            p = end + 17
        x0, y0, x1, y1 = struct.unpack("<4i", header["dataWindow"])
        parts.append((channels, x1 - x0 + 1, y1 - y0 + 1, y0))
    out, tables = {}, []
    for channels, width, height, _ in parts:
        out.update({name: np.zeros((height, width), np.float32) for name, _ in channels})
        tables.append(struct.unpack_from(f"<{height}Q", data, pos))
        pos += 8 * height
    for (channels, width, _, y0), offsets in zip(parts, tables):
        for offset in offsets:
            p = offset + (4 if multipart else 0)
            y, _size = struct.unpack_from("<ii", data, p)
            p += 8
            for name, pixel_type in channels:
                row = np.frombuffer(data, {1: "<f2", 2: "<f4"}[pixel_type], width, p)
                out[name][y - y0] = row
                p += row.nbytes
    return out


# ---------------------------------------------------------------- scene helpers


def black_world(scene):
    world = bpy.data.worlds.new("Black")
    background = compat.ensure_node_tree(world).nodes["Background"]
    background.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    background.inputs["Strength"].default_value = 0.0
    scene.world = world


def setup_render(scene, size=64, engine="CYCLES", samples=1):
    """Exact-pixel settings: tiny filter, no denoising/dithering, Standard view, float EXR."""
    scene.render.engine = engine
    scene.render.resolution_x = scene.render.resolution_y = size
    scene.render.resolution_percentage = 100
    scene.render.dither_intensity = 0.0
    scene.render.film_transparent = True
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    scene.cycles.samples = samples
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.use_denoising = False
    scene.cycles.filter_width = 0.01
    scene.cycles.device = "CPU"
    settings = scene.render.image_settings
    if hasattr(settings, "media_type"):  # 5.0: multilayer is a media type
        settings.media_type = "MULTI_LAYER_IMAGE"
    settings.file_format = "OPEN_EXR_MULTILAYER"
    settings.color_depth = "32"
    settings.exr_codec = "NONE"
    scene.view_layers[0].use_pass_normal = True


def render(scene, path):
    """Render the current frame to ``path``; (rgb, alpha, unit normal), rows top to bottom."""
    scene.render.filepath = str(path)
    bpy.ops.render.render(write_still=True)
    return unpack(read_exr(path), scene.view_layers[0].name)


def render_without_the_add_on(blend, out):
    """Render ``blend``'s current frame to ``out`` in a fresh Python process that never
    imports the add-on; its rgb (rows top to bottom). Fails if the process does, or names
    sh_lighting in its output."""
    code = (
        "import bpy; bpy.ops.wm.open_mainfile(filepath=%r); "
        "bpy.context.scene.render.filepath = %r; bpy.ops.render.render(write_still=True)"
        % (str(blend), str(out))
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                            timeout=600, cwd=str(Path(out).parent))
    assert result.returncode == 0, result.stderr[-2000:]
    assert "sh_lighting" not in result.stdout + result.stderr
    return unpack(read_exr(out))[0]


def unpack(channels, layer="ViewLayer"):
    rgb = np.stack([channels[f"{layer}.Combined.{c}"] for c in "RGB"], axis=-1)
    alpha = channels[f"{layer}.Combined.A"]
    normal = np.stack([channels[f"{layer}.Normal.{c}"] for c in "XYZ"], axis=-1).astype(float)
    length = np.linalg.norm(normal, axis=-1, keepdims=True)
    return rgb, alpha, normal / np.where(length > 0, length, 1.0)


def check_against_core(
    rgb, alpha, normal, coeffs, what, tolerance=RELATIVE_TOLERANCE, albedo=(1.0, 1.0, 1.0)
):
    """Every covered pixel = albedo irradiance(coeffs, normal) / π; returns the max error."""
    covered = alpha > 0.999
    assert covered.sum() > 0.25 * alpha.size, f"{what}: object covers too few pixels"
    predicted = np.asarray(albedo) * irradiance(coeffs, normal[covered]) / pi
    low, high = predicted.min(axis=0), predicted.max(axis=0)
    assert (low > 0.05 * high).all(), f"{what}: test lighting should stay well above 0"
    relative = np.abs(rgb[covered] - predicted) / np.abs(predicted)
    worst = float(relative.max())
    print(f"\n{what}: {covered.sum()} pixels, max relative error {worst:.3g}")
    assert worst < tolerance, (
        f"{what}: max relative error {worst:.3g} over {covered.sum()} pixels "
        f"(mean {relative.mean():.3g}) exceeds {tolerance}"
    )
    return worst




# ---------------------------------------------------------------- worlds

H, W = 64, 128  # world maps: texels of 2.8°
SKY = np.array([0.6, 0.7, 0.9])
GROUND = np.array([0.25, 0.2, 0.15])
SUN_RGB = np.array([1.0, 0.85, 0.6])
SUN_RADIANCE = 2000.0
SUN_IMAGE_DIRECTION = np.array([0.5, -0.4, 0.6]) / np.linalg.norm([0.5, -0.4, 0.6])
SUN_RADIUS = np.radians(4.0)
EULER = (0.3, -0.2, 1.1)
STRENGTH = 1.5


def new_world(name):
    """A world with its default Background → World Output tree (4.2 needs use_nodes)."""
    world = bpy.data.worlds.new(name)
    compat.ensure_node_tree(world)
    return world


def environment_world(scene, image, strength=1.0, rotation=None, *,
                      projection="EQUIRECTANGULAR", interpolation="Linear", name="Env"):
    """``scene``'s world: [Texture Coordinate → Mapping →] Environment Texture → Background →
    World Output. ``image``: an Image, a file path (loaded), or None (a texture without one)."""
    world = new_world(name)
    tree = world.node_tree
    background = tree.nodes["Background"]
    background.inputs["Strength"].default_value = strength
    texture = tree.nodes.new("ShaderNodeTexEnvironment")
    if isinstance(image, (str, Path)):
        image = bpy.data.images.load(str(image))
    texture.image = image
    texture.projection = projection
    texture.interpolation = interpolation
    tree.links.new(texture.outputs["Color"], background.inputs["Color"])
    if rotation is not None:
        add_mapping(world, rotation)
    scene.world = world
    return world


def add_mapping(world, rotation):
    tree = world.node_tree
    texture = next(n for n in tree.nodes if n.type == "TEX_ENVIRONMENT")
    coordinates = tree.nodes.new("ShaderNodeTexCoord")
    mapping = tree.nodes.new("ShaderNodeMapping")
    mapping.inputs["Rotation"].default_value = rotation
    tree.links.new(coordinates.outputs["Generated"], mapping.inputs["Vector"])
    tree.links.new(mapping.outputs["Vector"], texture.inputs["Vector"])


def sky_map(height=H, width=W):
    """Constant sky over constant ground: the ring around the sun is all sky, so the texels
    an extracted light takes out get exactly the sky's value back."""
    d = texel_directions(height, width)
    return np.where(d[..., 2:] > 0.0, SKY, GROUND).astype(np.float32)


def disc_mask(height=H, width=W):
    return texel_directions(height, width) @ SUN_IMAGE_DIRECTION > math.cos(SUN_RADIUS)


def sunny_map(sky=None):
    """``sky_map`` plus a disc of SUN_RADIANCE · SUN_RGB: (pixels float32, disc mask)."""
    sky = sky_map() if sky is None else sky
    disc = disc_mask()
    return (sky + disc[..., None] * SUN_RADIANCE * SUN_RGB).astype(np.float32), disc




# ---------------------------------------------------------------- operators without the UI


class Recorder:
    """Stands in for the operator instance when calling ``execute`` directly: keeps reports
    and takes the operator's properties as attributes."""

    def __init__(self, **props):
        self.reports = []
        self.__dict__.update(props)

    def report(self, kind, message):
        self.reports.append((set(kind), message))


def bound(cls, **props):
    """A ``Recorder`` with ``props`` standing in for an instance of the operator ``cls``: its
    own methods and text attributes (and its mixins') bound to it."""
    recorder = Recorder(**props)
    for klass in reversed(cls.__mro__):
        if klass.__module__.startswith("sh_lighting"):
            for name, value in vars(klass).items():
                if name in props or name.startswith("__"):
                    continue
                if inspect.isfunction(value):
                    setattr(recorder, name, types.MethodType(value, recorder))
                elif isinstance(value, str):
                    setattr(recorder, name, value)
    return recorder


def run_execute(cls, **props):
    """``cls.execute`` on ``bound(cls, **props)``: (result, [(kinds, message)])."""
    recorder = bound(cls, **props)
    return cls.execute(recorder, bpy.context), recorder.reports
