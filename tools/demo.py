"""`make demo`: prefilter an HDRI into 9 RGB SH coefficients and check them against brute force.

Usage: python -m tools.demo [HDRI]   (default: the forest HDRI that ships inside bpy)

Prints the coefficients L_lm, the time of each step and the 9-term irradiance error against
the exact (brute-force) irradiance; writes the coefficients as JSON and a picture comparing
the 9-term irradiance map with the brute-force one (the paper's figure 3) under out/demo/.
"""

import json
import sys
import time
from math import pi
from pathlib import Path

import bpy
import numpy as np

from sh_lighting.blender.world.images import load_image_pixels
from sh_lighting.core.sh import coefficient_table
from sh_lighting.core import (
    COEFFICIENT_NAMES,
    irradiance,
    project_equirect,
    reference_irradiance,
    texel_directions,
)
from sh_lighting.core.irradiance import relative_error, total_power
from sh_lighting.core.preview import linear_to_srgb
from tools.png import write_png

OUT = Path(__file__).resolve().parent.parent / "out" / "demo"
MAP_SIZE = (32, 64)  # irradiance maps compared with brute force (rows, columns)


def timed(label, timings, function, *args):
    start = time.perf_counter()
    result = function(*args)
    timings.append((label, time.perf_counter() - start))
    return result


def thumbnail(pixels, shape):
    """The (H, W, ≥3) map point-sampled at the texel centres of a ``shape`` (rows, columns) map."""
    rows = ((np.arange(shape[0]) + 0.5) * pixels.shape[0] / shape[0]).astype(int)
    cols = ((np.arange(shape[1]) + 0.5) * pixels.shape[1] / shape[1]).astype(int)
    return pixels[np.ix_(rows, cols)][..., :3].astype(np.float64)


def comparison_picture(hdri, sh_map, brute_map, scale=4):
    """HDRI | 9-term | brute force | 10× difference; the maps show a white diffuse surface."""
    peak = brute_map.max()
    gap = np.ones((sh_map.shape[0], 2, 3))
    error = np.abs(sh_map - brute_map) * 10.0
    panels = [hdri / np.percentile(hdri, 99), gap, sh_map / peak, gap, brute_map / peak, gap,
              error / peak]
    picture = linear_to_srgb(np.concatenate(panels, axis=1))
    return np.repeat(np.repeat(picture, scale, axis=0), scale, axis=1)


def main(argv):
    default = Path(bpy.utils.system_resource("DATAFILES", path="studiolights/world")) / "forest.exr"
    path = Path(argv[0]) if argv else default
    timings = []
    pixels = timed("load image (decode + readback)", timings, load_image_pixels, path)
    coeffs = timed("project to 9 SH coefficients", timings, project_equirect, pixels)
    print(f"HDRI: {path} ({pixels.shape[1]}x{pixels.shape[0]})")
    print("Lighting coefficients L_lm (Blender world axes, z up):\n")
    print("\n".join(coefficient_table(coeffs)))

    normals = texel_directions(*MAP_SIZE).reshape(-1, 3)
    at = f"at {len(normals)} normals"
    sh_map = timed(f"evaluate E(n) by eq. 13 {at}", timings, irradiance, coeffs, normals)
    brute = timed(f"brute-force E(n) {at}", timings, reference_irradiance, pixels, normals)
    mean, largest = relative_error(sh_map, brute, total_power(coeffs))
    print("\nTimings:")
    for label, seconds in timings:
        print(f"  {label:42s} {1000 * seconds:9.1f} ms")
    print(
        "\n9-term irradiance error, as a fraction of the total light ∫L dω (the paper's measure):\n"
        f"  mean {100 * mean:.2f} %, max {100 * largest:.2f} % "
        "(paper: under 1 % mean and 5 % max for natural light probes; 9.4 % worst case)"
    )

    OUT.mkdir(parents=True, exist_ok=True)
    stem = path.stem
    result = {"hdri": str(path), "frame": "blender_world_z_up", "order": list(COEFFICIENT_NAMES),
              "coefficients": coeffs.tolist()}
    (OUT / f"{stem}_coefficients.json").write_text(json.dumps(result, indent=2))
    picture = comparison_picture(
        thumbnail(pixels, MAP_SIZE),
        sh_map.reshape(MAP_SIZE + (3,)) / pi,
        brute.reshape(MAP_SIZE + (3,)) / pi,
    )
    write_png(OUT / f"{stem}_irradiance.png", picture)
    print(f"\nWrote {OUT / (stem + '_coefficients.json')}")
    print(f"Wrote {OUT / (stem + '_irradiance.png')}: HDRI | 9-term | brute force | 10x difference")


if __name__ == "__main__":
    main(sys.argv[1:])
