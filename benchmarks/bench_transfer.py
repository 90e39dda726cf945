"""Transfer: bake error against bake samples, bake seconds per 10k vertices, and
Cycles at equal error (transfer at 1 sample against path tracing). Writes its fragments of
benchmarks/REPORT.md (``fragments``: "transfer", "transfer_equal_error").
Run: ``python -m benchmarks.bench_transfer [--eevee]``, or
``--equal-error [--size N]`` for the equal-error comparison alone (160 px by default).

Scene (tests/transfer_scenes.py): a 4 m ground in 24 × 24 quads and a 1 m box (6 × 6 quads a
face) on it, grey diffuse 0.8, under a world emitting exactly Σ L_lm Y_lm (grey LIGHTING),
so the nine terms hold exactly and every error is the transfer's (noise, per-corner
interpolation) or the reference's noise.
"""

import os
import sys
import tempfile
import time
from pathlib import Path

import bpy
import numpy as np

sys.path[:0] = [str(Path(__file__).resolve().parents[1] / "tests")]
import blender_scenes as scenes  # noqa: E402
import transfer_scenes as ts  # noqa: E402
from benchmarks import fragments  # noqa: E402
from sh_lighting.blender.transfer import bake  # noqa: E402

TMP = Path(tempfile.mkdtemp(prefix="bench_transfer_"))


def load():
    return "/".join(f"{x:.2f}" for x in os.getloadavg())


def scene_for(ground_cuts=24, box_cuts=5, size=64):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    ground, box = ts.ground_and_box(ground_cuts, box_cuts)
    ts.camera(scene)
    ts.store_lighting(scene)
    ts.sh_world(scene)
    scenes.setup_render(scene, size=size, samples=16)
    return scene, ground, box


def timed_render(scene, name, samples):
    scene.cycles.samples = samples
    began = time.perf_counter()
    rgb, alpha, _ = scenes.render(scene, TMP / f"{name}.exr")
    return rgb, alpha, time.perf_counter() - began


def corner_irradiance(objects):
    """E = Σ T_lm L_lm per corner (grey LIGHTING), all objects concatenated."""
    rows = []
    for obj in objects:
        t = np.array([[d.color[0] for d in obj.data.color_attributes[n].data]
                      for n in bake.ATTRIBUTE_NAMES])
        rows.append(ts.LIGHTING @ t)
    return np.concatenate(rows)


def main(eevee=False):
    lines = ["## Transfer (precomputed radiance transfer)", ""]
    lines.append(f"`python -m benchmarks.bench_transfer`, {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, "
                 f"load average at start {load()} (2 cores, shared: times are inflated).")
    lines.append("Scene: 4 m ground (24 × 24 quads) and a 1 m box (6 × 6 quads per face), grey "
                 "diffuse 0.8, world emitting exactly Σ L_lm Y_lm; 64 × 64 px; error = relative "
                 "RMSE over object pixels.")
    lines.append("")

    scene, ground, box = scene_for()
    reference, alpha, ref_seconds = timed_render(scene, "reference", 4096)
    mask = np.repeat((alpha > 0.999)[..., None], 3, axis=-1)
    path_traced = []
    for spp in (16, 64, 256, 1024):
        rgb, _, seconds = timed_render(scene, f"pt{spp}", spp)
        path_traced.append((spp, ts.relative_rmse(rgb, reference, mask), seconds))

    # Per bake quality: bake with the diffuse material (the bounce), render the transfer.
    diffuse = ground.material_slots[0].material
    transfer = ts.transfer_material()
    render_rows, reference_e = [], None
    for samples in (512, 4, 16, 64, 128):
        ts.use_material([ground, box], diffuse)
        info = bake.bake_transfer(scene, [ground, box], samples=samples)
        e = corner_irradiance([ground, box])
        if reference_e is None:
            reference_e = e
        ts.use_material([ground, box], transfer)
        rgb, _, seconds = timed_render(scene, f"transfer{samples}", 1)
        corner_error = float(np.sqrt(np.mean((e - reference_e) ** 2))
                             / np.sqrt(np.mean(reference_e ** 2)))
        render_rows.append((samples, info.seconds, corner_error,
                            ts.relative_rmse(rgb, reference, mask),
                            rgb[mask].mean() / reference[mask].mean(), seconds))
    render_rows.sort()

    lines += ["### Error against bake samples", "",
              "| bake samples | bake s (2 objects, 843 vertices, 3168 corners) | E per corner vs 512-sample bake | render (1 spp) vs path tracing 4096 spp | brightness | render s |",
              "|---|---|---|---|---|---|"]
    for samples, seconds, corner_error, error, bright, render_s in render_rows:
        ce = "—" if samples == 512 else f"{100 * corner_error:.2f} %"
        lines.append(f"| {samples} | {seconds:.1f} | {ce} | {100 * error:.2f} % | {bright:.4f} | {render_s:.2f} |")
    lines.append("")
    transfer_error = render_rows[2][3]  # 64 samples
    transfer_seconds = render_rows[2][5]
    lines += ["### Cycles at equal error", "",
              "| method | samples | error vs 4096 spp | render s |", "|---|---|---|---|"]
    lines.append(f"| transfer (Emission Only, bake 64 samples) | 1 | {100 * transfer_error:.2f} % | {transfer_seconds:.2f} |")
    for spp, error, seconds in path_traced:
        lines.append(f"| path tracing | {spp} | {100 * error:.2f} % | {seconds:.2f} |")
    lines.append(f"| path tracing (the reference) | 4096 | — | {ref_seconds:.2f} |")
    lines.append("")

    # Bake seconds per 10k vertices at the default quality.
    scene, ground, box = scene_for(100, 5)
    info = bake.bake_transfer(scene, [ground, box], samples=bake.DEFAULT_SAMPLES)
    per_10k = info.seconds / info.vertices * 1e4
    lines += ["### Bake time", "",
              f"{info.vertices} vertices ({info.corners} corners) at {info.samples} samples: "
              f"{info.seconds:.1f} s = **{per_10k:.1f} s per 10k vertices** "
              f"({info.seconds / info.corners * 4e4:.1f} s per 40k corners); per basis function "
              + ", ".join(f"{s:.1f}" for s in info.basis_seconds) + " s.", ""]

    if eevee:
        scene, ground, box = scene_for()
        reference_c, alpha, _ = timed_render(scene, "reference_e", 2048)
        mask = np.repeat((alpha > 0.999)[..., None], 3, axis=-1)
        bake.bake_transfer(scene, [ground, box], samples=64)
        ts.use_material([ground, box], ts.transfer_material())
        for engine in ("BLENDER_EEVEE_NEXT", "BLENDER_EEVEE"):
            try:
                scene.render.engine = engine
                break
            except TypeError:
                continue
        scene.eevee.taa_render_samples = 1
        began = time.perf_counter()
        rgb, _, _ = scenes.render(scene, TMP / "eevee.exr")
        seconds = time.perf_counter() - began
        lines += ["### EEVEE", "",
                  f"Transfer, Emission Only, EEVEE ({scene.render.engine}, 1 sample, software GL): "
                  f"{100 * ts.relative_rmse(rgb, reference_c, mask):.2f} % against Cycles path "
                  f"tracing 2048 spp, brightness {rgb[mask].mean() / reference_c[mask].mean():.4f}, "
                  f"{seconds:.1f} s (first shader compile included).", ""]
    fragments.write("transfer", "\n".join(lines))
    print("\n".join(lines))


def equal_error(size=160, ground_cuts=64, box_cuts=8, repeats=2):
    """Transfer at 1 spp against path tracing at a few sample counts, at a size where a
    render is not all overhead and with a mesh dense enough for ~1 % interpolation error.

    The renders are interleaved (path tracing at each count, then the transfer, ``repeats``
    times; each time the best of its repeats), so the load hits both alike. Equal error:
    path tracing's error fitted as a / √spp, its time as t0 + t1 · spp (least squares), at
    the spp giving the transfer's error."""
    scene, ground, box = scene_for(ground_cuts, box_cuts, size)
    diffuse = ground.material_slots[0].material
    reference, alpha, ref_seconds = timed_render(scene, "equal_reference", 2048)
    mask = np.repeat((alpha > 0.999)[..., None], 3, axis=-1)
    info = bake.bake_transfer(scene, [ground, box], samples=64)
    transfer = ts.transfer_material()
    counts = (16, 32, 64, 128, 256)
    errors, times = {}, {}
    for _ in range(repeats):
        for spp in (*counts, 1):
            ts.use_material([ground, box], transfer if spp == 1 else diffuse)
            rgb, _, seconds = timed_render(scene, f"equal{spp}", spp)
            errors[spp] = ts.relative_rmse(rgb, reference, mask)
            times[spp] = min(seconds, times.get(spp, np.inf))
    spp = np.array(counts, float)
    a = float(np.exp(np.mean(np.log([errors[n] for n in counts]) + 0.5 * np.log(spp))))
    t1, t0 = np.polyfit(spp, [times[n] for n in counts], 1)
    equal = (a / errors[1]) ** 2
    equal_seconds = t0 + t1 * equal
    lines = [f"### Transfer at equal error, {size} × {size} px", "",
             f"`python -m benchmarks.bench_transfer --equal-error --size {size}`: "
             f"{size} × {size} px, ground {ground_cuts} × {ground_cuts} quads, {info.vertices} "
             f"vertices, bake {info.seconds:.1f} s, reference 2048 spp {ref_seconds:.1f} s, "
             f"renders interleaved, best of {repeats}; load at the end {load()}:", "",
             "| method | spp | error | render s |", "|---|---|---|---|",
             f"| transfer (bake 64 samples) | 1 | {100 * errors[1]:.2f} % | {times[1]:.2f} |"]
    lines += [f"| path tracing | {n} | {100 * errors[n]:.2f} % | {times[n]:.2f} |" for n in counts]
    lines += ["", f"Path tracing fitted: error {100 * a:.1f} % / √spp, time {t0:.2f} s + "
              f"{1000 * t1:.1f} ms · spp; the transfer's {100 * errors[1]:.2f} % at {equal:.0f} "
              f"spp, {equal_seconds:.2f} s: **{equal_seconds / times[1]:.1f}×** the transfer's "
              f"{times[1]:.2f} s (bake {info.seconds:.1f} s = {info.seconds / equal_seconds:.1f} "
              "such path-traced frames)."]
    fragments.write("transfer_equal_error", "\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    if "--equal-error" in sys.argv:
        size = int(sys.argv[sys.argv.index("--size") + 1]) if "--size" in sys.argv else 160
        equal_error(size)
    else:
        main(eevee="--eevee" in sys.argv)
