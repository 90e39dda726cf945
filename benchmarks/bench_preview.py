"""Cost of refreshing the Design panel's irradiance preview after an edit.

`python -m benchmarks.bench_preview`: a 128×128 irradiance sphere computed by the core
(``irradiance_sphere_image``, negative light shown) and copied into a ``bpy.utils.previews``
image (``previews.to_preview``: flip to bottom-first rows, ``image_pixels_float.foreach_set``).
Each run uses new coefficients (an edit), as the panel does; medians of many runs, after one
warm-up call that fills the core's per-size cache of normals and basis values (timed apart).
Target: under 50 ms, so that an edit redraws the panel without a visible pause.
"""

import statistics
import time

import bpy
import bpy.utils.previews
import numpy as np

from sh_lighting.blender.ui.previews import IRRADIANCE_SIZE, to_preview
from sh_lighting.core import preview as core_preview
from sh_lighting.core.preview import irradiance_sphere_image

RUNS = 200
TARGET = 0.050


def lighting(rng):
    """Random (9, 3) coefficients with a positive ambient term."""
    coeffs = rng.normal(scale=0.3, size=(9, 3))
    coeffs[0] = rng.uniform(1.0, 2.0, 3)
    return coeffs


def main():
    rng = np.random.default_rng(0)
    pcoll = bpy.utils.previews.new()
    try:
        preview = pcoll.new("bench")
        core_preview.sphere_normals.cache_clear()  # a cold start: normals and basis values
        core_preview._sphere_basis.cache_clear()
        start = time.perf_counter()
        to_preview(preview, irradiance_sphere_image(lighting(rng), IRRADIANCE_SIZE,
                                                    show_negative=True))
        first = time.perf_counter() - start

        core_times, transfer_times = [], []
        for _ in range(RUNS):
            coeffs = lighting(rng)
            t0 = time.perf_counter()
            image = irradiance_sphere_image(coeffs, IRRADIANCE_SIZE, show_negative=True)
            t1 = time.perf_counter()
            to_preview(preview, image)
            t2 = time.perf_counter()
            core_times.append(t1 - t0)
            transfer_times.append(t2 - t1)
    finally:
        bpy.utils.previews.remove(pcoll)

    totals = [a + b for a, b in zip(core_times, transfer_times, strict=True)]
    total = statistics.median(totals)
    size = f"{IRRADIANCE_SIZE}×{IRRADIANCE_SIZE}"
    print(f"irradiance preview {size}, median of {RUNS} runs (Blender {bpy.app.version_string})")
    print(f"  core image:          {1e3 * statistics.median(core_times):7.2f} ms")
    print(f"  to ImagePreview:     {1e3 * statistics.median(transfer_times):7.2f} ms")
    print(f"  total:               {1e3 * total:7.2f} ms  (target < {1e3 * TARGET:.0f} ms: "
          f"{'met' if total < TARGET else 'MISSED'})")
    print(f"  first call (caches): {1e3 * first:7.2f} ms")
    return 0 if total < TARGET else 1


if __name__ == "__main__":
    raise SystemExit(main())
