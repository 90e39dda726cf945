"""The measurement tables two tests assert bounds on, printed in full (`make bench`).

``python -m benchmarks.bench_tables``: the 9-term irradiance error against brute force of the
8 HDRIs inside bpy (tests/blender/world/test_hdri_error.py asserts docs/reference.md §2's
bounds) and the float32 rounding of each evaluation order of eq. 13
(tests/core/test_stability.py). The measuring functions are the tests', so the table and the
assertion cannot drift apart.
"""

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT / "tests"), str(ROOT / "tests" / "core")]

import test_stability  # noqa: E402
from blender import test_hdri_error  # noqa: E402
from conftest import HDRI_NAMES, bundled_hdri_dir  # noqa: E402

from sh_lighting.blender.world.images import load_image_pixels  # noqa: E402


def main():
    print("9-term irradiance error against brute force, 768 normals "
          "(tests/blender/world/test_hdri_error.py)")
    folder = bundled_hdri_dir()
    for name in HDRI_NAMES:
        pixels = load_image_pixels(folder / f"{name}.exr")
        mean, worst = test_hdri_error.hdri_error(pixels)
        print("  " + test_hdri_error.error_line(name, pixels, mean, worst))
    print()
    print(test_stability.evaluation_table(test_stability.measure_evaluation_errors()))


if __name__ == "__main__":
    main()
