"""Render a world as Cycles sees it into an equirectangular float image, leaving no trace.

For worlds the reader cannot read (Sky Texture, gradients, mixes): a panoramic camera at the
origin in a temporary scene with a copy of the world renders the radiance arriving from every
direction in Blender's equirect convention (u = 0.5 − atan2(y, x)/2π, docs/reference.md §3),
box filter, no denoising or clamping; the EXR is read back and everything temporary removed.
Pixels around a sun smaller than a pixel are rendered again up to 16× finer and averaged back
by solid angle (``core.supersample``). What camera rays see is captured. Details:
docs/modules.md.
"""

import math
import os
import re
import shutil
import tempfile
import time

import bpy
import numpy as np

from ...core.supersample import average_fine_rows, hot_region
from ..data import compat
from ..data.node_links import is_world_edit
from .images import load_image_pixels

#: Samples per pixel: enough for the box filter to average a texel well (a constant world is
#: exact with any count, since no objects means no noise).
DEFAULT_SAMPLES = 16

#: Refinement: at most this many times finer, and at most this many pixels rendered.
REFINE_FACTOR = 16
REFINE_PIXELS = 1 << 16

# Camera rotation (XYZ Euler) that puts +X at the image centre and +Z up.
CAMERA_ROTATION = (math.pi / 2.0, 0.0, -math.pi / 2.0)


CAPTURE_PREFIX = "sh_lighting_capture_"
# A capture folder without a process id (made by earlier versions) is stale after this long.
STALE_SECONDS = 3600.0


class CaptureError(RuntimeError):
    """The world could not be rendered; the message says why and what to do."""


def _running(pid):
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # another user's process: it runs
        return True
    return True


def remove_stale_captures(folder=None, now=None):
    """Delete the capture folders killed runs left in ``folder`` (the system temp folder):
    those whose process id is no longer running, and id-less ones (earlier versions) older
    than STALE_SECONDS. Returns the paths removed; a folder that cannot be removed is left."""
    folder = tempfile.gettempdir() if folder is None else folder
    now = time.time() if now is None else now
    removed = []
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return removed
    for entry in entries:
        if not entry.name.startswith(CAPTURE_PREFIX) or not entry.is_dir(follow_symlinks=False):
            continue
        pid = re.match(r"(\d+)_", entry.name[len(CAPTURE_PREFIX):])
        try:
            stale = (not _running(int(pid[1])) if pid else
                     now - entry.stat(follow_symlinks=False).st_mtime > STALE_SECONDS)
            if stale and int(pid[1] if pid else -1) != os.getpid():
                shutil.rmtree(entry.path)
                removed.append(entry.path)
        except OSError:
            continue
    return removed


def _set_cycles(scene):
    try:
        scene.render.engine = "CYCLES"
    except TypeError:
        raise CaptureError(
            "capturing the world needs the Cycles render engine, which is not available: "
            "enable the Cycles add-on (Preferences > Add-ons > Cycles Render Engine)"
        ) from None


def _configure(scene, samples, frame):
    render = scene.render
    render.resolution_percentage = 100
    render.pixel_aspect_x = render.pixel_aspect_y = 1.0
    render.use_border = False
    render.use_motion_blur = False
    render.film_transparent = False
    render.dither_intensity = 0.0
    render.use_compositing = False
    render.use_sequencer = False
    render.use_persistent_data = False
    render.use_file_extension = False
    scene.frame_current = frame

    settings = render.image_settings
    settings.file_format = "OPEN_EXR"
    settings.color_mode = "RGBA"
    settings.color_depth = "32"
    settings.exr_codec = "ZIP"

    view = scene.view_settings
    view.view_transform = "Standard"
    view.look = "None"
    view.exposure = 0.0
    view.gamma = 1.0
    view.use_curve_mapping = False

    cycles = scene.cycles
    cycles.device = "CPU"
    cycles.samples = samples
    cycles.use_adaptive_sampling = False
    cycles.use_denoising = False
    cycles.pixel_filter_type = "BOX"
    cycles.filter_width = 1.0
    cycles.sample_clamp_direct = 0.0
    cycles.sample_clamp_indirect = 0.0
    cycles.seed = 0
    cycles.use_animated_seed = False
    cycles.film_exposure = 1.0


def _render(scene, path, width, height, border=None):
    """Render ``scene`` at width × height (or the ``border`` crop of it) and read it back.

    ``border``: (column0, column1, row0, row1) in pixels, rows top to bottom, ends excluded.
    """
    render = scene.render
    render.resolution_x, render.resolution_y = width, height
    render.use_border = render.use_crop_to_border = border is not None
    if border is not None:
        column0, column1, row0, row1 = border
        # Blender floors border × size to pixels: aim at pixel centres of the edges.
        render.border_min_x = (column0 + 0.5) / width
        render.border_max_x = (column1 + 0.5) / width
        render.border_min_y = (height - row1 + 0.5) / height
        render.border_max_y = (height - row0 + 0.5) / height
    if os.path.exists(path):
        os.remove(path)
    try:
        result = bpy.ops.render.render(write_still=True, scene=scene.name)
    except RuntimeError as error:
        raise CaptureError(f"Cycles could not render the world: {error}") from None
    if "FINISHED" not in result or not os.path.isfile(path):
        raise CaptureError(
            "Cycles did not render the world (is another render running?): "
            "wait for it to finish and try again"
        )
    try:
        return load_image_pixels(path)
    except ValueError as error:
        raise CaptureError(f"the captured world could not be read back: {error}") from None


def _refine(scene, camera, path, coarse):
    """Re-render the block around the capture's hot texels finer and average it back in place."""
    height, width = coarse.shape[:2]
    region = hot_region(coarse)
    if region is None:
        return
    row0, row1, start, count = region
    factor = min(REFINE_FACTOR, int(math.sqrt(REFINE_PIXELS / ((row1 - row0) * count))))
    if factor < 2:
        return
    # Turn the camera about +Z by whole columns so that the block does not cross the seam:
    # turned by 2πk/W, the capture's column j shows the unturned column j − k.
    shift = -start % width
    camera.rotation_euler[2] = CAMERA_ROTATION[2] + 2.0 * math.pi * shift / width
    border = (0, count * factor, row0 * factor, row1 * factor)
    fine = _render(scene, path, width * factor, height * factor, border)
    expected = ((row1 - row0) * factor, count * factor)
    if fine.shape[:2] != expected:
        raise CaptureError(
            f"the refining render has shape {fine.shape[:2]} instead of {expected}: "
            "pass refine=False to capture without refining"
        )
    columns = (start + np.arange(count)) % width
    coarse[row0:row1, columns] = average_fine_rows(fine, factor, row0, height)


def _without_edits(world):
    """Mute the World Edit nodes of ``world`` (a copy): a muted group passes its Color input
    through, so the capture is the world as it is without the designed change."""
    tree = world.node_tree
    for node in tree.nodes if tree is not None else ():
        if is_world_edit(node):
            node.mute = True


def capture_world(world, width=256, samples=DEFAULT_SAMPLES, frame=None, refine=True,
                  edits=False):
    """Render ``world`` with Cycles: a (width/2, width, 4) float32 equirect array, rows top down.

    ``frame``: the frame to evaluate an animated world at (default: the current scene's).
    ``refine``: re-render the block around very bright, small features (a sun) up to
    ``REFINE_FACTOR`` times finer and average it back (``core.supersample``).
    ``edits``: render its World Edit too (by default the world is captured without it).
    Raises CaptureError when the world cannot be rendered. Leaves ``bpy.data`` as it found it.
    """
    if world is None:
        raise CaptureError("there is no world to capture: assign a world to the scene")
    width = int(width)
    if width < 4 or width % 2:
        raise CaptureError(f"capture width must be an even number of at least 4, got {width}")
    samples = int(samples)
    if samples < 1:
        raise CaptureError(f"capture samples must be at least 1, got {samples}")
    height = width // 2
    if frame is None:
        frame = bpy.context.scene.frame_current if bpy.context.scene else 1

    had_render_result = {image.name for image in bpy.data.images if image.type == "RENDER_RESULT"}
    remove_stale_captures()
    directory = tempfile.mkdtemp(prefix=f"{CAPTURE_PREFIX}{os.getpid()}_")
    path = os.path.join(directory, "world.exr")
    scene = camera_data = camera = copy = None
    try:
        copy = world.copy()
        if not edits:
            _without_edits(copy)
        scene = bpy.data.scenes.new("SH Lighting Capture")
        scene.world = copy
        if hasattr(copy, "cycles"):
            copy.cycles.sampling_method = "NONE"
        visibility = getattr(copy, "cycles_visibility", None)
        if visibility is not None and not visibility.camera:
            # Cycles' update callback tags the *context* scene's world: make that the copy.
            with bpy.context.temp_override(scene=scene):
                visibility.camera = True
        _set_cycles(scene)
        _configure(scene, samples, frame)
        camera_data = bpy.data.cameras.new("SH Lighting Capture")
        compat.set_equirectangular_panorama(camera_data)
        camera = bpy.data.objects.new("SH Lighting Capture", camera_data)
        camera.location = (0.0, 0.0, 0.0)
        camera.rotation_mode = "XYZ"
        camera.rotation_euler = CAMERA_ROTATION
        scene.collection.objects.link(camera)
        scene.camera = camera
        scene.render.filepath = path
        pixels = _render(scene, path, width, height)
        if refine:
            _refine(scene, camera, path, pixels)
        return pixels
    finally:
        if scene is not None:
            bpy.data.scenes.remove(scene)
        if camera is not None:
            bpy.data.objects.remove(camera)
        if camera_data is not None:
            bpy.data.cameras.remove(camera_data)
        if copy is not None:
            bpy.data.worlds.remove(copy)
        for image in list(bpy.data.images):
            if image.type == "RENDER_RESULT" and image.name not in had_render_result:
                bpy.data.images.remove(image)
        shutil.rmtree(directory, ignore_errors=True)
