"""Light from a photograph: Match Photo's error against noise, hidden ball and the prior.

    .venv/bin/python -m benchmarks.bench_photo

writes its section of benchmarks/REPORT.md (between the ``<!-- bench_photo -->`` markers,
the rest untouched) and benchmarks/photo_error.png (matplotlib, installed by ``make bench``).
Scenes: benchmarks/photo_scene.py (a grey ball, albedo 0.18, Diffuse BSDF, Cycles 96 px,
32 spp). Measured:

* a world that is exactly nine terms, rendered orthographic to EXR, with Gaussian noise of σ
  (a fraction of each pixel) added: the fit's error on the seen normals and over all normals
  against the world's nine terms, with the whole ball seen and with a quarter hidden;
* courtyard (bundled with Blender) rendered at 85 mm to an 8-bit sRGB PNG: per prior, the
  error on the seen normals (up to one scale) against the nine-term limit there (the best
  nine-term fit to the world's true irradiance on those normals) and over all normals.

Errors: RMS of E over normals and channels, divided by its mean (``core.photo.relative_rms``).
"""

import os
import re
import time
from pathlib import Path
from tempfile import TemporaryDirectory

import bpy
import numpy as np

from sh_lighting.blender.photo import camera_of
from sh_lighting.blender.world.images import load_image_pixels
from sh_lighting.core.downsample import block_downsample
from sh_lighting.core.irradiance import irradiance, reference_irradiance
from sh_lighting.core.photo import PRIORS, best_nine_term_error, fit_photo, relative_rms
from sh_lighting.core.photo import scaled_error
from sh_lighting.core.projection import project_equirect
from sh_lighting.core.sh import spread_normals

from .photo_scene import (
    SAMPLES,
    SIZE,
    circle_of,
    grey_ball_scene,
    linear,
    render_exr,
    render_png,
    sh_world_pixels,
    write_float_exr,
)

REPORT = Path(__file__).with_name("REPORT.md")
PLOT = Path(__file__).with_name("photo_error.png")
NOISES = (0.0, 0.01, 0.02, 0.05, 0.1, 0.2)
BEGIN, END = "<!-- bench_photo -->", "<!-- /bench_photo -->"


def error_table(photo, scene, noises, prior="mirror", seed=5):
    """{"full"|"quarter": {noise: (seen error, all-normal error, condition)}} of the photo of
    the nine-term world (``photo_scene.LIGHT``, scene camera orthographic) with noise added."""
    pixels = linear(photo)
    camera = camera_of(scene.camera, scene)
    truth = project_equirect(sh_world_pixels())
    everywhere = spread_normals(512)
    rng = np.random.default_rng(seed)
    hidden = np.ones(pixels.shape[:2], dtype=bool)
    hidden[SIZE // 2:, SIZE // 2:] = False  # the lower right quarter
    table = {}
    for name, mask in (("full", None), ("quarter", hidden)):
        table[name] = {}
        for noise in noises:
            noisy = pixels * (1.0 + noise * rng.standard_normal(pixels.shape))
            fit = fit_photo(noisy, circle_of("ORTHO"), camera, prior=prior, mask=mask)
            table[name][noise] = (
                relative_rms(irradiance(fit.coefficients, fit.normals),
                             irradiance(truth, fit.normals)),
                relative_rms(irradiance(fit.coefficients, everywhere),
                             irradiance(truth, everywhere)),
                fit.condition)
    return table


def prior_table(photo, hdri, scene):
    """{prior: (seen error, nine-term limit there, all-normal error, fit)} of the photo."""
    pixels = load_image_pixels(hdri)[..., :3].astype(np.float64)
    small = block_downsample(pixels, 4)[0]
    world = project_equirect(pixels)
    everywhere = spread_normals(512)
    camera = camera_of(scene.camera, scene)
    photo_pixels = load_image_pixels(photo)
    clipped = (photo_pixels[..., :3] >= 1.0).any(axis=-1)
    rows = {}
    for prior in PRIORS:
        fit = fit_photo(photo_pixels, circle_of("PERSP"), camera, prior=prior, clip=clipped)
        normals = fit.normals[::3]
        truth = reference_irradiance(small, normals)
        rows[prior] = (scaled_error(irradiance(fit.coefficients, normals), truth)[0],
                       best_nine_term_error(normals, truth),
                       scaled_error(irradiance(fit.coefficients, everywhere),
                                    irradiance(world, everywhere))[0], fit)
    return rows


def measure(folder):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    world = write_float_exr(Path(folder) / "sh_world.exr", sh_world_pixels())
    scene, _ = grey_ball_scene(world)
    start = time.perf_counter()
    exr = render_exr(scene, Path(folder) / "sh_photo.exr")
    seconds = time.perf_counter() - start
    noise = error_table(exr, scene, NOISES)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    hdri = Path(bpy.utils.system_resource("DATAFILES", path="studiolights/world")) / "courtyard.exr"
    scene, _ = grey_ball_scene(hdri, "PERSP")
    png = render_png(scene, Path(folder) / "courtyard.png")
    return noise, prior_table(png, str(hdri), scene), seconds


def section(noise, priors, seconds):
    load = os.getloadavg()[0]
    lines = [BEGIN, "## Light from a photograph (Match Photo, issue 25)", "",
             f"Measured by `python -m benchmarks.bench_photo` (load average {load:.1f}; one "
             f"{SIZE} px, {SAMPLES} spp Cycles render took {seconds:.1f} s). Errors: RMS of "
             "E(n) over normals and channels / its mean. Tests: tests/blender/test_photo.py "
             "asserts these within bounds.", "",
             "**Exact nine-term world, EXR, orthographic, prior mirror; added noise σ per "
             "pixel.** Seen: on the normals the photo sees; all: over the sphere, against the "
             "world's nine terms.", "",
             "| σ | seen, full ball | all, full ball | seen, quarter hidden | all, quarter "
             "hidden | condition full / quarter |", "|---|---|---|---|---|---|"]
    for s in noise["full"]:
        f, q = noise["full"][s], noise["quarter"][s]
        lines.append(f"| {100 * s:.0f} % | {100 * f[0]:.2f} % | {100 * f[1]:.1f} % | "
                     f"{100 * q[0]:.2f} % | {100 * q[1]:.1f} % | {f[2]:.0f} / {q[2]:.0f} |")
    lines += ["", "**Courtyard (bundled), 8-bit sRGB PNG, 85 mm: per prior.** Seen: up to one "
              "scale, against the world's true irradiance (eq. 1) on the seen normals; the "
              "limit is the best nine-term fit there (the issue's bound: 1.25× it).", "",
              "| prior | seen | nine-term limit | ratio | all normals vs the world's nine "
              "terms | prior weight | residual (noise) |", "|---|---|---|---|---|---|---|"]
    for prior, (seen, limit, everywhere, fit) in priors.items():
        lines.append(f"| {prior} | {100 * seen:.2f} % | {100 * limit:.2f} % | "
                     f"{seen / limit:.2f} | {100 * everywhere:.1f} % | {fit.prior_weight:.3g} |"
                     f" {100 * fit.residual:.1f} % ({100 * fit.noise:.1f} %) |")
    fit = priors["none"][3]
    lines += ["", f"Poorly constrained by one photo (σ/σ_max < 0.1): {', '.join(fit.weak_terms)}"
              f" (condition {fit.condition:.0f}). A prior fills the unseen side but cannot "
              "know it: here the world's back is darker than its front, so mirror and "
              "ambient are further from the world over all normals than the plain fit, "
              "while the seen side stays within the bound. ![](photo_error.png)", END]
    return "\n".join(lines)


def plot(noise):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axes = plt.subplots(1, 2, figsize=(9, 3.5))
    for name, style in (("full", "-o"), ("quarter", "--s")):
        sigmas = sorted(noise[name])
        for k, ax in enumerate(axes):
            ax.plot([100 * s for s in sigmas], [100 * noise[name][s][k] for s in sigmas],
                    style, label=f"{name} ball" if name == "full" else "a quarter hidden")
    for ax, title in zip(axes, ("on the seen normals", "over all normals")):
        ax.set_xlabel("added noise σ per pixel (%)")
        ax.set_ylabel("error of E (% of its mean)")
        ax.set_title(title)
        ax.legend()
    figure.tight_layout()
    figure.savefig(PLOT, dpi=100)


def main():
    with TemporaryDirectory() as folder:
        noise, priors, seconds = measure(folder)
    text = section(noise, priors, seconds)
    report = REPORT.read_text(encoding="utf-8")
    pattern = re.compile(re.escape(BEGIN) + ".*?" + re.escape(END), re.S)
    report = pattern.sub(lambda _: text, report) if pattern.search(report) else (
        report.rstrip("\n") + "\n\n" + text + "\n")
    REPORT.write_text(report, encoding="utf-8")
    print(text)
    try:
        plot(noise)
    except ImportError:
        print("matplotlib is not installed: no plot (make bench installs it)")


if __name__ == "__main__":
    main()
