"""The tiny scene the farm and command-line tests render, and the sky of their preset.

A grey (albedo 0.5) sphere seen by an orthographic camera, in a world of one constant colour
WORLD (or an HDRI, the command line's), rendered by Cycles into 32-bit EXRs (no denoising, no
dithering, Standard view, pixel filter 0.01: exact pixels). The preset is a constant sky of
radiance SKY, for which the 9-term lighting is exact, so a frame of the applied file shows
ALBEDO * SKY at the centre of the sphere (lit by the preset, not by the world). Self-contained
(numpy, and bpy when building): test_real_blender runs it in a real Blender.
"""

import math

import numpy as np

SKY = (0.2, 0.5, 1.5)
WORLD = (0.05, 0.1, 0.02)
ALBEDO = 0.5
SIZE = (32, 16)
SKY_COEFFICIENTS = np.zeros((9, 3))
SKY_COEFFICIENTS[0] = 2.0 * math.sqrt(math.pi) * np.array(SKY)  # L00 of a constant sky


def build_scene(path, hdri=None, samples=1):
    """Write the scene to ``path`` (a new .blend) and leave Blender with an empty file; its
    world the colour WORLD, or the image ``hdri`` as an Environment Texture."""
    import bpy  # before bmesh, which only imports inside Blender

    import bmesh

    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    mesh = bpy.data.meshes.new("Ball")
    bm = bmesh.new()
    bmesh.ops.create_uvsphere(bm, u_segments=32, v_segments=16, radius=1.0)
    bm.to_mesh(mesh)
    bm.free()
    mesh.shade_smooth()
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

    world = bpy.data.worlds.new("Plain" if hdri is None else "Sky")
    if world.node_tree is None:
        world.use_nodes = True
    tree = world.node_tree
    background = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeBackground")
    if hdri is None:
        background.inputs["Color"].default_value = (*WORLD, 1.0)
    else:
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
    render.filter_size = 0.01
    render.image_settings.file_format = "OPEN_EXR"
    render.image_settings.color_depth = "32"
    scene.view_settings.view_transform = "Standard"
    scene.cycles.samples = samples
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.use_denoising = False
    scene.cycles.device = "CPU"
    bpy.ops.wm.save_as_mainfile(filepath=str(path), copy=True)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    return path


def read_exr(path):
    """(H, W, 4) float32 pixels of an EXR, rows top to bottom (read with bpy)."""
    import bpy

    image = bpy.data.images.load(str(path))
    try:
        width, height = image.size
        pixels = np.empty(width * height * 4, np.float32)
        image.pixels.foreach_get(pixels)
    finally:
        bpy.data.images.remove(image)
    return pixels.reshape(height, width, 4)[::-1]
