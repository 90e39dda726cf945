"""`make bench`: speed of project_equirect as a ratio to one numpy pass over the same pixels.

These machines are noisy, so each size is timed several times in one run and the medians are
compared: `pixels.sum()` over the same float32 RGBA array is the yardstick. Target (issue 2):
at most 3.0× at 4096×2048, with float64 accumulation and exactness kept.
"""

import time

import numpy as np

from sh_lighting.core import project_equirect

SIZES = ((512, 1024), (2048, 4096), (4096, 8192))
REPEATS = 7


def median_seconds(function, repeats=REPEATS):
    function()  # warm-up: page faults, BLAS threads
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return float(np.median(times))


def main():
    rng = np.random.default_rng(0)
    print(f"{'size':>11} {'sum() ms':>9} {'project ms':>11} {'ratio':>6}")
    for h, w in SIZES:
        pixels = rng.random((h, w, 4), dtype=np.float32)
        base = median_seconds(pixels.sum)
        proj = median_seconds(lambda: project_equirect(pixels))
        print(f"{w:>5}x{h:<5} {1000 * base:9.1f} {1000 * proj:11.1f} {proj / base:6.2f}")


if __name__ == "__main__":
    main()
