"""`python -m benchmarks.bench_sizes [--max-width 16384]`: every stage of an HDRI's way
through the add-on at 1K-16K, in time and memory, against the floor for that stage.

Maps (smooth sky, a small very bright sun, a sharp window) as float EXR and 8-bit PNG; each
(size, format, stage) in a fresh subprocess (its own peak RSS; tracemalloc inside). Stages:
decode (Blender's load: the floor), readback (floor: decode), projection, error estimate,
Extract Lights (2), specular cube, .gltf writing (floor: one ``pixels.sum()``, in
alternation); memory floor: the decoded image (H × W × 4 float32). Times: the minimum of
``REPEATS`` runs. Writes its fragment of benchmarks/REPORT.md ("sizes") and sizes.png.
"""

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

import numpy as np

from benchmarks import fragments

HERE = Path(__file__).resolve().parent
WIDTHS = (1024, 2048, 4096, 8192, 16384)
FORMATS = ("exr", "png")
STAGES = ("decode", "readback", "projection", "estimate", "lights", "cube", "write")
REPEATS = 3


def sky(height, width):
    """The benchmark map, float32 RGBA, rows top to bottom (built row block by row block)."""
    from sh_lighting.core.equirect import column_centres, row_centres

    px = np.ones((height, width, 4), dtype=np.float32)
    phi = column_centres(width).astype(np.float32)[None, :]
    rng = np.random.default_rng(0)
    for r0 in range(0, height, 256):
        theta = row_centres(height)[r0 : r0 + 256, None].astype(np.float32)
        st, ct = np.sin(theta), np.cos(theta)
        sx, sy, sz = np.array([0.5, 0.3, 0.81]) / np.linalg.norm([0.5, 0.3, 0.81])  # unit: the
        dot = st * np.cos(phi) * sx + st * np.sin(phi) * sy + ct * sz  # sun is in the map
        sun = np.exp(np.minimum((dot - 1.0) / 4e-5, 0.0)) * 3e4
        up = np.clip(ct, 0.0, None)
        block = px[r0 : r0 + 256]
        for c, (base, slope, s) in enumerate(((0.2, 0.6, 1.0), (0.25, 0.8, 1.0), (0.3, 1.2, 0.9))):
            noise = 1.0 + 0.1 * rng.random(block.shape[:2], dtype=np.float32)
            block[..., c] = (base + slope * up + s * sun) * noise
    px[height // 3 : height // 3 + height // 20, width // 7 : width // 7 + width // 30, :3] = 40.0
    return px


def write_map(path, width):
    """The benchmark map of ``width`` × ``width``/2 as an EXR (float) or 8-bit sRGB PNG."""
    import bpy

    height = width // 2
    pixels = sky(height, width)
    png = path.suffix == ".png"
    if png:  # tone-mapped into [0, 1] bytes: the 8-bit file's own (sRGB-encoded) values
        np.clip(pixels[..., :3] / (1.0 + pixels[..., :3]), 0.0, 1.0, out=pixels[..., :3])
    image = bpy.data.images.new("bench", width, height, float_buffer=not png, alpha=True)
    image.pixels.foreach_set(pixels[::-1].ravel())
    del pixels
    scene = bpy.data.scenes.new("bench")
    settings = scene.render.image_settings
    if png:
        settings.file_format, settings.color_mode, settings.color_depth = "PNG", "RGB", "8"
        settings.compression = 15
    else:
        settings.file_format, settings.color_mode = "OPEN_EXR", "RGBA"
        settings.color_depth, settings.exr_codec = "32", "ZIP"
    image.save_render(str(path), scene=scene)
    bpy.data.scenes.remove(scene)
    bpy.data.images.remove(image)


def _min_time(function, repeats):
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        best = min(best, time.perf_counter() - start)
    return best


def measure(path, stage, repeats=REPEATS):
    """One stage on one file, in this process: {"time", "floor", "traced", "rss"} (s, s, bytes,
    bytes). Run it in a fresh process (``--measure``) so that "rss" is its own peak."""
    import bpy

    from sh_lighting.blender.world import images

    def load():
        image = bpy.data.images.load(str(path), check_existing=False)
        start = time.perf_counter()
        image.size[:]  # reading the values makes Blender decode the file
        return image, time.perf_counter() - start

    decode = float("inf")
    for _ in range(repeats if stage == "decode" else 1):
        image, seconds = load()
        decode = min(decode, seconds)
        if stage == "decode":
            bpy.data.images.remove(image)
    if stage == "decode":
        return {"time": decode, "floor": decode, "traced": 0, "rss": _rss()}
    tracemalloc.start()
    if stage == "readback":
        start = time.perf_counter()
        pixels = images.linear_pixels(image)
        seconds = time.perf_counter() - start
        return {"time": seconds, "floor": decode, "traced": tracemalloc.get_traced_memory()[1],
                "rss": _rss()}
    pixels = images.linear_pixels(image)
    bpy.data.images.remove(image)
    work = _stage_function(stage, pixels, path)
    floor = times = float("inf")
    if stage == "projection":
        work()  # warm-up (the cached weights, the thread pool)
    tracemalloc.reset_peak()
    for _ in range(repeats):  # in alternation with the floor
        floor = min(floor, _min_time(pixels.sum, 1))
        times = min(times, _min_time(work, 1))
    return {"time": times, "floor": floor, "traced": tracemalloc.get_traced_memory()[1],
            "rss": _rss()}


def _stage_function(stage, pixels, path):
    from sh_lighting.core.irradiance import bounded_error_estimate, error_estimate
    from sh_lighting.core.lights import extract_lights
    from sh_lighting.core.projection import project_equirect
    from sh_lighting.formats.gltf import gltf_text, specular_cube

    coeffs = project_equirect(pixels)
    out = Path(path).with_suffix(".gltf")
    made = bounded_error_estimate(pixels, coeffs, 256)["downsample"] if stage == "lights" else None
    return {
        "projection": lambda: project_equirect(pixels),
        "estimate": lambda: error_estimate(pixels, coeffs, 256),
        # what `compute --lights 2` adds (``hdri.hdri_lights``): the projection and the
        # estimate's downsample reused, no copy of the rest
        "lights": lambda: extract_lights(pixels, 2, coefficients=coeffs, keep_rest=False,
                                         downsample=made),
        "cube": lambda: specular_cube(pixels),
        "write": lambda: out.write_text(gltf_text(coeffs, pixels), encoding="utf-8"),
    }[stage]


def _rss():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024  # Linux: KiB


def run(max_width, folder, stages=STAGES):
    rows = []
    for width in (w for w in WIDTHS if w <= max_width):
        for fmt in FORMATS:
            path = folder / f"sky_{width}.{fmt}"
            start = time.perf_counter()
            subprocess.run([sys.executable, "-m", "benchmarks.bench_sizes", "--write",
                            str(path), str(width)], check=True, cwd=HERE.parent)
            print(f"wrote {path.name} ({path.stat().st_size / 2**20:.0f} MB) in "
                  f"{time.perf_counter() - start:.1f} s", flush=True)
            for stage in stages:
                done = subprocess.run(
                    [sys.executable, "-m", "benchmarks.bench_sizes", "--measure", str(path),
                     stage], check=True, cwd=HERE.parent, capture_output=True, text=True)
                row = json.loads(done.stdout.strip().splitlines()[-1])
                row.update(width=width, height=width // 2, format=fmt, stage=stage)
                rows.append(row)
                print(f"{width:>6} {fmt} {stage:<10} {row['time']:8.3f} s "
                      f"({row['time'] / row['floor']:.2f}x floor) rss {row['rss'] / 2**20:.0f} MB",
                      flush=True)
            path.unlink()
    return rows


def fitted_slope(pixels, values):
    """The exponent b of values ≈ a · pixels^b (least squares in log-log)."""
    return float(np.polyfit(np.log(pixels), np.log(values), 1)[0])


def plot(rows, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax_t, ax_m) = plt.subplots(1, 2, figsize=(11, 4.2))
    slopes = {}
    for stage in STAGES:
        sel = [r for r in rows if r["stage"] == stage and r["format"] == "exr"]
        if len(sel) < 2:
            continue
        px = np.array([r["width"] * r["height"] for r in sel], float)
        t = np.array([r["time"] for r in sel])
        m = np.array([r["rss"] for r in sel]) / 2**20
        slopes[stage] = (fitted_slope(px, t), fitted_slope(px, m))
        ax_t.loglog(px, t, "o-", label=f"{stage} (slope {slopes[stage][0]:.2f})")
        ax_m.loglog(px, m, "o-", label=f"{stage} (slope {slopes[stage][1]:.2f})")
    sel = [r for r in rows if r["stage"] == "decode" and r["format"] == "exr"]
    px = np.array([r["width"] * r["height"] for r in sel], float)
    ax_m.loglog(px, px * 16 / 2**20, "k--", label="decoded image (floor)")
    ax_t.set(xlabel="pixels", ylabel="time (s)", title="time per stage (float EXR)")
    ax_m.set(xlabel="pixels", ylabel="peak RSS of the process (MB)", title="peak memory")
    for ax in (ax_t, ax_m):
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    return slopes


def section(rows, slopes, load, skipped):
    lines = ["## Sizes: each stage from 1K to 16K, against its floor", "",
             f"`python -m benchmarks.bench_sizes` ({time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}; "
             f"load average {load}; 2 shared cores). Time: the minimum of {REPEATS} runs; "
             "floor: Blender's decode of the same file (decode, readback) or one numpy pass "
             "`pixels.sum()` over the float32 RGBA pixels, in alternation (the other stages). "
             "Memory: the stage's subprocess's peak RSS (Blender, the decoded image and the "
             "stage), the stage's traced numpy peak (tracemalloc), and the decoded image's size "
             "in memory (H × W × 4 float32).", "",
             "| size | file | stage | time s | × floor | peak RSS MB | traced MB | × image |",
             "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        image = r["width"] * r["height"] * 16
        lines.append(f"| {r['width']}×{r['height']} | {r['format']} | {r['stage']} | "
                     f"{r['time']:.3f} | {r['time'] / r['floor']:.2f} | {r['rss'] / 2**20:.0f} | "
                     f"{r['traced'] / 2**20:.0f} | {r['rss'] / image:.2f} |")
    lines += ["", "Fitted slopes (log time and log peak RSS against log pixels, float EXR): "
              + "; ".join(f"{s} {a:.2f} / {b:.2f}" for s, (a, b) in slopes.items()) + ".", ""]
    compute = {}
    for r in rows:
        if r["format"] == "exr" and r["stage"] in ("decode", "readback", "projection",
                                                  "estimate", "lights"):
            compute.setdefault(r["width"], {})[r["stage"]] = r["time"]
    lines += ["`compute` of an EXR ≈ decode + readback + projection + estimate, against its "
              "floor, Blender's decode + readback; `--lights 2` adds the lights stage:", "",
              "| size | decode + readback s | `compute` s | × floor | `--lights 2` adds s | "
              "× `compute` |", "|---|---|---|---|---|---|"]
    for width, t in sorted(compute.items()):
        if len(t) == 5:
            floor = t["decode"] + t["readback"]
            c = floor + t["projection"] + t["estimate"]
            lines.append(f"| {width}×{width // 2} | {floor:.2f} | {c:.2f} | {c / floor:.2f} | "
                         f"{t['lights']:.2f} | {(c + t['lights']) / c:.2f} |")
    if skipped:
        lines += ["", f"Not run: {skipped}."]
    lines += ["", "![time and memory against pixels](sizes.png)"]
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--max-width", type=int, default=8192,
                        help="largest map width (16384: the 16K maps; about 4 GB per process)")
    parser.add_argument("--measure", nargs=2, metavar=("FILE", "STAGE"), help=argparse.SUPPRESS)
    parser.add_argument("--write", nargs=2, metavar=("FILE", "WIDTH"), help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.measure:
        print(json.dumps(measure(Path(args.measure[0]), args.measure[1])))
        return
    if args.write:
        write_map(Path(args.write[0]), int(args.write[1]))
        return
    load = ", ".join(f"{v:.1f}" for v in os.getloadavg())
    with tempfile.TemporaryDirectory(prefix="sh_bench_sizes_") as folder:
        rows = run(args.max_width, Path(folder))
    load = f"{load} at the start, " + ", ".join(f"{v:.1f}" for v in os.getloadavg()) + " at the end"
    slopes = plot(rows, HERE / "sizes.png")
    skipped = "" if args.max_width >= 16384 else (
        "16384×8192 (pass --max-width 16384: each of its processes holds Blender's 2 GB decode "
        "and the 2 GB readback, and the run takes several more minutes on the shared machine)")
    text = section(rows, slopes, load, skipped)
    fragments.write("sizes", text)
    (HERE / "sizes.json").write_text(json.dumps(rows, indent=1), encoding="utf-8")
    print(text)


if __name__ == "__main__":
    main()
