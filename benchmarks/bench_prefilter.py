"""`make bench`: speed of project_equirect as a ratio to one numpy pass over the same pixels.

These machines are noisy and their speed drifts, so the two are timed in alternation, pair by
pair, and the median of the per-pair ratios is reported: `pixels.sum()` over the same float32
RGBA array is the yardstick. Targets: at most 3.0× at 1024×512 and 2.0× at
4096×2048, with float64 accumulation and exactness kept; a 256×128 map (a procedural world's
capture, a design preview) in under 0.3 ms, where a call's fixed cost is most of the time.
"""

import time

import numpy as np

from sh_lighting.core import project_equirect

SIZES = ((128, 256), (512, 1024), (2048, 4096), (4096, 8192))
REPEATS = 11


def paired_times(first, second, repeats=REPEATS):
    """Alternate the two calls; return their median times and the median per-pair ratio."""
    first(), second()  # warm-up: page faults, BLAS threads
    a, b = [], []
    for _ in range(repeats):
        start = time.perf_counter()
        first()
        middle = time.perf_counter()
        second()
        a.append(middle - start)
        b.append(time.perf_counter() - middle)
    ratios = np.array(b) / np.array(a)
    return float(np.median(a)), float(np.median(b)), float(np.median(ratios))


def main():
    rng = np.random.default_rng(0)
    print(f"{'size':>11} {'sum() ms':>9} {'project ms':>11} {'ratio':>6}")
    for h, w in SIZES:
        pixels = rng.random((h, w, 4), dtype=np.float32)
        repeats = max(REPEATS, 2_000_000 // (h * w))  # a small map's median needs more pairs
        base, proj, ratio = paired_times(pixels.sum, lambda: project_equirect(pixels), repeats)
        print(f"{w:>5}x{h:<5} {1000 * base:9.3f} {1000 * proj:11.3f} {ratio:6.2f}")


if __name__ == "__main__":
    main()
