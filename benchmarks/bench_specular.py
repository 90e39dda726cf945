"""Cost of the glTF environment's specular cube (core.specular via gltf_environment).

`python -m benchmarks.bench_specular`: for equirect images of several sizes, the time of
``specular_cube`` (64² × 6 faces, 4 levels: the export's default) and of the whole .gltf text
(cube, RGBD, PNG, base64), each timed in alternation with ``project_equirect`` of the same
pixels (the 9 coefficients) and reported with the median per-pair ratio.
"""

import numpy as np

from benchmarks.bench_prefilter import paired_times
from sh_lighting.core import project_equirect
from sh_lighting.formats.gltf import gltf_text, specular_cube

SIZES = ((512, 1024), (1024, 2048), (2048, 4096))
REPEATS = 5


def main():
    rng = np.random.default_rng(0)
    coeffs = rng.normal(size=(9, 3))
    columns = (("size", 11), ("project ms", 11), ("cube ms", 8), ("ratio", 6),
               ("gltf ms", 8), ("ratio", 6))
    print(" ".join(f"{name:>{width}}" for name, width in columns))
    for h, w in SIZES:
        pixels = rng.random((h, w, 3), dtype=np.float32)
        base, cube, ratio = paired_times(lambda: project_equirect(pixels),
                                         lambda: specular_cube(pixels), REPEATS)
        _b, text, text_ratio = paired_times(lambda: project_equirect(pixels),
                                            lambda: gltf_text(coeffs, pixels), REPEATS)
        print(f"{w:>5}x{h:<5} {1000 * base:11.1f} {1000 * cube:8.0f} {ratio:6.1f} "
              f"{1000 * text:8.0f} {text_ratio:6.1f}")


if __name__ == "__main__":
    main()
