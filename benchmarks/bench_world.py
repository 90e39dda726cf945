"""Cost of reading a world image beyond Blender's own decoding of it.

`python -m benchmarks.bench_world`: a synthetic 4096×2048 float OpenEXR world (written to a
temporary folder, removed afterwards) is loaded the way the add-on meets it: Blender decodes
the file on first pixel access (the user pays that whenever Blender shows or renders the
world), then ``world_coefficients`` reads the pixels back (``Image.pixels.foreach_get``) and
projects them. Target: that rest costs at most 25% of the decode. Medians of several runs,
each on a freshly loaded image; the decode is timed by reading the values of ``Image.size``,
which makes Blender load the file (``image.size`` alone returns a lazy array and does not).
"""

import os
import shutil
import tempfile
import time

import bpy
import numpy as np

from sh_lighting.blender.world.images import image_pixels
from sh_lighting.blender.world.reader import world_coefficients
from sh_lighting.core.equirect import texel_directions
from sh_lighting.core.projection import project_equirect
from tests.blender_scenes import environment_world

WIDTH, HEIGHT = 4096, 2048
REPEATS = 5
TARGET = 0.25


def write_exr(path, pixels, depth):
    """Top-to-bottom float ``pixels`` → a ``depth``-bit ("16"/"32") RGBA ZIP OpenEXR."""
    height, width = pixels.shape[:2]
    image = bpy.data.images.new("bench", width, height, float_buffer=True, alpha=True)
    image.pixels.foreach_set(np.ascontiguousarray(pixels[::-1]).ravel())
    scene = bpy.data.scenes.new("bench")
    settings = scene.render.image_settings
    settings.file_format, settings.color_mode = "OPEN_EXR", "RGBA"
    settings.color_depth, settings.exr_codec = depth, "ZIP"
    image.save_render(path, scene=scene)
    bpy.data.scenes.remove(scene)
    bpy.data.images.remove(image)


def synthetic_sky(height, width):
    """A smooth sky with a small, very bright sun: an HDRI's typical range, float32 RGBA."""
    d = texel_directions(height, width)
    sun = np.exp((d @ np.array([0.5, 0.3, 0.81]) - 1.0) / 4e-5) * 3e4
    pixels = np.ones((height, width, 4), dtype=np.float32)
    sky = np.clip(d[..., 2], 0.0, None)
    pixels[..., 0] = 0.2 + 0.6 * sky + sun
    pixels[..., 1] = 0.25 + 0.8 * sky + sun
    pixels[..., 2] = 0.3 + 1.2 * sky + 0.9 * sun
    return pixels


def time_once(path):
    """(decode, readback, projection, world_coefficients) seconds on a freshly loaded image."""
    image = bpy.data.images.load(path, check_existing=False)
    world = environment_world(bpy.context.scene, image, name="bench")

    start = time.perf_counter()
    width, height = image.size  # reading the values (not just .size) decodes the file
    decode = time.perf_counter() - start
    assert (width, height) == (WIDTH, HEIGHT) and image.has_data and image.is_float

    start = time.perf_counter()
    coeffs, info = world_coefficients(bpy.context.scene)
    rest = time.perf_counter() - start
    assert info.source == "image" and np.isfinite(coeffs).all()

    start = time.perf_counter()
    pixels = image_pixels(image)
    readback = time.perf_counter() - start
    start = time.perf_counter()
    project_equirect(pixels)
    projection = time.perf_counter() - start

    bpy.context.scene.world = None
    bpy.data.worlds.remove(world)
    bpy.data.images.remove(image)
    return decode, readback, projection, rest


def main():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    directory = tempfile.mkdtemp(prefix="sh_lighting_bench_")
    try:
        pixels = synthetic_sky(HEIGHT, WIDTH)
        print(f"{WIDTH}×{HEIGHT} RGBA OpenEXR (ZIP), medians of {REPEATS} runs, milliseconds")
        print(f"{'file':>9} {'decode':>8} {'readback':>9} {'project':>8} {'rest':>7} {'ratio':>6}")
        ratios = {}
        for depth in ("32", "16"):
            path = os.path.join(directory, f"world{depth}.exr")
            write_exr(path, pixels, depth)
            time_once(path)  # warm-up: file cache, numpy and BLAS threads
            runs = np.array([time_once(path) for _ in range(REPEATS)])
            decode, readback, projection, rest = np.median(runs, axis=0)
            ratios[depth] = rest / decode
            print(
                f"{depth + '-bit':>9} {1e3 * decode:8.0f} {1e3 * readback:9.0f} "
                f"{1e3 * projection:8.0f} {1e3 * rest:7.0f} {ratios[depth]:6.2f}"
            )
        verdict = "meets" if ratios["32"] <= TARGET else "misses"
        print(
            f"rest / decode = {ratios['32']:.2f} on the 32-bit float EXR: {verdict} the target "
            f"of {TARGET:.2f} (rest = world_coefficients: pixel readback + projection)"
        )
    finally:
        shutil.rmtree(directory, ignore_errors=True)


if __name__ == "__main__":
    main()
