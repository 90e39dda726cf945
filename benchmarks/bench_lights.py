"""SH + extracted lights against path tracing, for a sphere on a ground plane with shadows.

``python -m benchmarks.bench_lights [--hdri sunrise] [--size 48] [--no-eevee]`` writes its
fragment of benchmarks/REPORT.md ("lights"). Scene: ``shadow_scene`` (white diffuse sphere on a
white plane, a bundled HDRI as the world); reference: Cycles path tracing at
``REFERENCE_SAMPLES``; compared at a few sample counts: path tracing, SH + k lights (k = 0:
plain SH; Keep BSDF, so the lights cast shadows), EEVEE's own. Error: mean |image − reference|
/ mean reference over the objects' pixels; headline: the time path tracing needs for the same
error over the SH render's (its error fitted by a power law).
"""

import argparse
from tempfile import TemporaryDirectory

import bpy
import numpy as np

from sh_lighting import api
from sh_lighting.blender.data import compat
from sh_lighting.blender.design import lights
from sh_lighting.blender.shading import materials
from sh_lighting.core import project_equirect

from . import fragments
from .shadow_scene import ShadowScene, covered, mean_deviation

REFERENCE_SAMPLES = 1024
PATH_SAMPLES = (1, 4, 16, 64, 256)
SH_SAMPLES = (1, 4, 16, 64)
LIGHT_COUNTS = (0, 1, 2)
REPEATS = 2  # each render this many times, the shortest time kept (the machine is shared)


def run(hdri, size, eevee, log=print):
    """The rows (method, samples, seconds, error); each configuration is rendered in each of
    ``REPEATS`` rounds (all configurations per round, so load changes spread over all of
    them) and its shortest time kept."""
    from tests.conftest import bundled_hdri_dir

    times, errors = {}, {}
    with TemporaryDirectory() as work:
        s = ShadowScene(bundled_hdri_dir() / f"{hdri}.exr", size, work)
        s.scene.render.use_persistent_data = True  # time the sampling, not the scene export
        s.render(1)  # warm-up
        _, reference = s.render(REFERENCE_SAMPLES, seed=99)
        mask = covered(reference)
        coeffs = project_equirect(s.hdri_pixels())
        mats = [obj.data.materials[0] for obj in (s.sphere, s.plane)]

        def measure(what, sample_counts):
            for samples in sample_counts:
                seconds, image = s.render(samples)
                key = (what, samples)
                times[key] = min(times.get(key, seconds), seconds)
                errors[key] = mean_deviation(image, reference, mask)
                log(what, samples, f"{seconds:.2f} s", f"{100 * errors[key]:.2f} %")

        for _ in range(REPEATS):
            lights.remove_lights(s.scene)
            materials.remove_from_materials(mats)
            measure("path tracing", PATH_SAMPLES)
            api.set_coefficients(s.scene, coeffs)
            materials.apply_to_materials(mats, s.scene, mode="KEEP_BSDF")
            for count in LIGHT_COUNTS:
                info = lights.extract_lights(s.scene, count) if count else None
                if count and len(info.lights) < count:
                    log(f"only {len(info.lights)} light(s) found for k = {count}")
                measure(f"SH + {count} light(s)" if count else "plain SH", SH_SAMPLES)
        rows = [(what, n, times[what, n], errors[what, n]) for what, n in times]
        if eevee:
            lights.remove_lights(s.scene)
            materials.remove_from_materials(mats)
            s.world.sun_threshold = 10.0
            s.scene.render.engine = compat.eevee_engine_id()
            s.scene.eevee.taa_render_samples = 16
            try:
                for attempt in ("first", "second"):
                    seconds, image = s.render(16)  # EEVEE's first render compiles shaders
                    rows.append((f"EEVEE, world sun threshold 10 ({attempt} render)", 16,
                                 seconds, mean_deviation(image, reference, mask)))
                    log(*rows[-1])
            except RuntimeError as error:
                log(f"EEVEE did not run: {error}")
    bpy.ops.wm.read_factory_settings(use_empty=True)
    return rows


def path_tracing_fit(rows):
    """Path tracing's error e(n) = a n^b (least squares in log-log) and time t(n) = t0 + t1 n
    (least squares) as functions of its sample count n: (b, time at error, function)."""
    path = [(n, t, e) for w, n, t, e in rows if w == "path tracing"]
    n, t, e = (np.array(v, dtype=float) for v in zip(*path))
    b, log_a = np.polyfit(np.log(n), np.log(e), 1)
    t1, t0 = np.polyfit(n, t, 1)

    def seconds_at(error):
        samples = np.exp((np.log(error) - log_a) / b)
        return float(t0 + t1 * samples), float(samples)

    return b, seconds_at


def equal_error_ratios(rows, what):
    """For each row of ``what``: (samples, seconds, error, path tracing's samples and seconds
    at that error, their time ratio)."""
    _, seconds_at = path_tracing_fit(rows)
    out = []
    for w, n, t, e in rows:
        if w == what:
            needed, samples = seconds_at(e)
            out.append((n, t, e, samples, needed, needed / t))
    return out


def section(rows, hdri, size):
    lines = [f"## SH + extracted lights vs path tracing (sphere on a ground plane, "
             f"{hdri} HDRI)", "",
             f"`python -m benchmarks.bench_lights` ({size}×{size} px, Cycles CPU, 2 shared "
             f"cores; reference: path tracing at {REFERENCE_SAMPLES} samples; error = mean "
             "|image − reference| / mean reference over the objects' pixels). SH renders use "
             "Apply mode KEEP_BSDF, so the extracted Sun lights cast shadows.", "",
             "| method | samples | seconds | error |", "|---|---:|---:|---:|"]
    lines += [f"| {w} | {n} | {t:.2f} | {100 * e:.2f} % |" for w, n, t, e in rows]
    lines.append("")
    slope, _ = path_tracing_fit(rows)
    lines.append(f"Equal error: path tracing's error fitted as e ∝ n^{slope:.2f} of its sample "
                 "count n and its time as t0 + t1 n; for each SH render, the time path tracing "
                 "needs for the same error over the SH render's time (> 1: SH is faster).")
    lines += ["", "| method | samples | error | path tracing samples at that error | "
              "time ratio |", "|---|---:|---:|---:|---:|"]
    for what in sorted({r[0] for r in rows if r[0].startswith(("SH", "plain"))}):
        lines += [f"| {what} | {n} | {100 * e:.2f} % | {pn:.1f} | **{ratio:.2f}×** |"
                  for n, _, e, pn, _, ratio in equal_error_ratios(rows, what)]
    return "\n".join(lines)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hdri", default="sunrise")
    parser.add_argument("--size", type=int, default=48)
    parser.add_argument("--no-eevee", action="store_true")
    args = parser.parse_args()
    rows = run(args.hdri, args.size, not args.no_eevee)
    text = section(rows, args.hdri, args.size)
    fragments.write("lights", text)
    print(text)


if __name__ == "__main__":
    main()
