"""A grey ball photographed in Cycles: the scene the Match Photo tests and bench share.

A unit ball at the origin (smooth UV sphere, Diffuse BSDF of albedo 0.18: no specular), the
world an equirect image (or a chrome ball's mirror-ball image), the scene camera at −Y looking
along +Y: orthographic (the ball's radius SIZE / ORTHO_SCALE pixels) or 85 mm at DISTANCE_85;
``turn_camera`` puts it on the other side (+Y looking along −Y) for a second photo.
Exact-pixel render settings (no denoising, no dithering, Standard view, a 0.01 px filter:
each pixel is its centre's ray). The world and the render settings are the tests' (one copy,
tests/blender_scenes.py); EXRs are written by tests/blender_files.py.
"""

import bpy
import numpy as np

from sh_lighting.blender.data import compat
from sh_lighting.blender.world.images import load_image_pixels
from sh_lighting.core.equirect import texel_directions
from sh_lighting.core.sh import sh_basis
from tests.blender_scenes import environment_world, setup_render

LIGHT = 0.5 * np.array(
    [[3.0, 2.5, 2.0], [0.5, 0.4, 0.2], [1.1, 1.0, 0.9], [-0.4, -0.2, 0.0], [0.2, 0.1, 0.0],
     [0.0, -0.2, 0.1], [0.3, 0.3, 0.2], [0.1, 0.1, 0.3], [-0.2, 0.0, 0.2]]
)  # non-negative radiance everywhere (min 0.049)
SIZE = 96
ORTHO_SCALE = 2.2  # the unit ball's radius is SIZE / 2.2 = 43.6 px
DISTANCE_85 = 5.5  # the 85 mm camera's distance: the ball's radius is ~40 px
SAMPLES = 32  # measured: 2.4 % noise per pixel on the nine-term world, 10 % under courtyard
ALBEDO = 0.18


def sh_world_pixels():
    """A 256×128 equirect map whose radiance is exactly the nine terms LIGHT (Blender axes)."""
    return (sh_basis(texel_directions(128, 256)) @ LIGHT).astype(np.float32)


def grey_ball_scene(world_path, projection="ORTHO", strength=1.0, samples=SAMPLES,
                    world_projection="EQUIRECTANGULAR"):
    """(scene, the ball's material) in the current (empty) file; see the module docstring.
    ``world_projection``: the Environment Texture's, "MIRROR_BALL" for a chrome ball's."""
    scene = bpy.context.scene
    environment_world(scene, str(world_path), strength, projection=world_projection,
                      name="Photo world")
    bpy.ops.mesh.primitive_uv_sphere_add(segments=96, ring_count=48, radius=1.0)
    ball = bpy.context.object
    bpy.ops.object.shade_smooth()
    material = bpy.data.materials.new("Grey ball")
    mtree = compat.ensure_node_tree(material)
    for node in list(mtree.nodes):
        if node.type != "OUTPUT_MATERIAL":
            mtree.nodes.remove(node)
    diffuse = mtree.nodes.new("ShaderNodeBsdfDiffuse")
    diffuse.inputs["Color"].default_value = (ALBEDO, ALBEDO, ALBEDO, 1.0)
    mtree.links.new(diffuse.outputs[0], mtree.nodes["Material Output"].inputs["Surface"])
    ball.data.materials.append(material)
    data = bpy.data.cameras.new("Photo camera")
    data.type = projection
    data.ortho_scale = ORTHO_SCALE
    data.lens, data.sensor_width, data.sensor_fit = 85.0, 36.0, "AUTO"
    camera = bpy.data.objects.new("Photo camera", data)
    scene.collection.objects.link(camera)
    camera.location = (0.0, -(DISTANCE_85 if projection == "PERSP" else 5.0), 0.0)
    camera.rotation_euler = (np.pi / 2, 0.0, 0.0)
    scene.camera = camera
    setup_render(scene, SIZE, samples=samples)
    scene.render.film_transparent = False  # the photo shows the world around the ball
    scene.view_layers[0].use_pass_normal = False
    return scene, material


def turn_camera(scene):
    """The scene camera moved to the ball's other side: at +Y looking along −Y, z up."""
    camera = scene.camera
    camera.location = (0.0, -camera.location[1], 0.0)
    camera.rotation_euler = (np.pi / 2, 0.0, np.pi - camera.rotation_euler[2])
    bpy.context.view_layer.update()


def circle_of(projection):
    """The ball's circle (cx, cy, r) in pixels."""
    if projection == "ORTHO":
        return (SIZE / 2, SIZE / 2, SIZE / ORTHO_SCALE)
    # on the axis: tan(angular radius) · f / (sensor / SIZE) pixels
    return (SIZE / 2, SIZE / 2, np.tan(np.arcsin(1.0 / DISTANCE_85)) * 85.0 / (36.0 / SIZE))


def _render(scene, path, file_format, depth):
    settings = scene.render.image_settings
    if hasattr(settings, "media_type"):  # 5.0
        settings.media_type = "IMAGE"
    settings.file_format, settings.color_mode, settings.color_depth = file_format, "RGB", depth
    if file_format == "OPEN_EXR":
        settings.exr_codec = "ZIP"
    scene.render.filepath = str(path)
    bpy.ops.render.render(write_still=True)
    return str(path)


def render_exr(scene, path):
    """Render to a 32-bit EXR at ``path``; returns the path."""
    return _render(scene, path, "OPEN_EXR", "32")


def render_png(scene, path, depth="8"):
    """Render to an sRGB PNG (Standard view) of ``depth`` bits at ``path``; returns the path."""
    return _render(scene, path, "PNG", depth)


def linear(path):
    """The image at ``path`` as Blender renders it, float64 (H, W, 3), rows top to bottom."""
    return load_image_pixels(path)[..., :3].astype(np.float64)
