"""`python -m benchmarks.bench_compile`: what Apply costs EEVEE's first render (its shader
compiles), against the same scene without the add-on.

``bench_eevee_default``'s scene (a plain 4-vertex floor, a cube, a UV sphere, a Suzanne under
forest.exr), rendered by EEVEE twice in a fresh process with an empty shader cache (its own
``XDG_CACHE_HOME``: Mesa's and Blender's caches both live there), for each of: no add-on
applied; the Default Apply (Keep BSDF with Shadows: the bake, then the transfer's nodes);
Keep BSDF alone. The first render includes the compiles, the second is the frame itself; the
variants run interleaved, ``--rounds`` times. Writes its fragment of benchmarks/REPORT.md
("compile").
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

VARIANTS = ("none", "default", "keep_bsdf")
LABELS = {"none": "no add-on (EEVEE's own world lighting)",
          "default": "Default Apply (Keep BSDF with Shadows)",
          "keep_bsdf": "Keep BSDF",
          "keep_bsdf_no_maps": "Keep BSDF, no reflection maps (a diagnostic)"}


def one(variant, folder):
    """In this (fresh) process: the scene, ``variant`` applied, two EEVEE renders; a dict."""
    import bpy

    from sh_lighting import api
    from sh_lighting.blender.data import compat
    from sh_lighting.blender.shading import materials

    from .bench_eevee_default import build_scene
    from .bench_real_scene import _render

    path = Path(bpy.utils.system_resource("DATAFILES", path="studiolights/world")) / "forest.exr"
    build_scene(path)
    scene = bpy.context.scene
    eevee = compat.eevee_engine_id()
    scene.render.engine = eevee
    bake = 0.0
    if variant == "default":
        applied = api.apply_with_shadows(scene, mode="AUTO", report=lambda text: None)
        bake = applied.info.seconds if applied.info else 0.0
        assert applied.lit, "the Default lit nothing through the transfer"
    elif variant in ("keep_bsdf", "keep_bsdf_no_maps"):
        if variant == "keep_bsdf_no_maps":  # no glossy rays of the world: no reflection maps
            scene.world.cycles_visibility.glossy = False
        materials.apply_to_materials(materials.materials_of(scene.objects), scene, "KEEP_BSDF")
    first, _ = _render(scene, Path(folder) / f"{variant}_1.exr", eevee, 16)
    second, _ = _render(scene, Path(folder) / f"{variant}_2.exr", eevee, 16)
    return {"variant": variant, "first": first, "second": second, "bake": bake}


def run_one(variant):
    """``one`` in a fresh Blender process with an empty shader cache; (dict, peak RSS MB)."""
    with tempfile.TemporaryDirectory() as cache, tempfile.TemporaryDirectory() as folder:
        env = dict(os.environ, XDG_CACHE_HOME=cache)
        code = ("import json, resource, sys; from benchmarks.bench_compile import one; "
                f"r = one({variant!r}, {folder!r}); "
                "r['rss'] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024; "
                "print('RESULT ' + json.dumps(r))")
        done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                              text=True, check=False)
    lines = [line for line in done.stdout.splitlines() if line.startswith("RESULT ")]
    if done.returncode or not lines:
        raise RuntimeError(f"{variant}: {done.stderr[-2000:]}")
    return json.loads(lines[-1][len("RESULT "):])


def section(rows, load, elapsed):
    lines = ["## EEVEE's first render after Apply: the shader compiles", "",
             f"`python -m benchmarks.bench_compile` (bench_eevee_default's scene, forest.exr, "
             f"64×40 px, EEVEE 16 samples; each row a fresh process with an empty shader cache, "
             f"the variants interleaved; load average {load}; {elapsed:.0f} s in all). First: "
             "the first render after Apply, its shader compiles included; second: the next "
             "render (the frame itself); compile = first − second; × none: the first render "
             "over the same round's without the add-on.", "",
             "| round | variant | first render | second | compile | × none | bake | peak RSS |",
             "|---|---|---|---|---|---|---|---|"]
    for index, by_variant in enumerate(rows, 1):
        base = by_variant["none"]["first"]
        for variant in VARIANTS:
            r = by_variant[variant]
            lines.append(f"| {index} | {LABELS[variant]} | {r['first']:.1f} s | "
                         f"{r['second']:.1f} s | {r['first'] - r['second']:.1f} s | "
                         f"{r['first'] / base:.2f}× | {r['bake']:.1f} s | {r['rss']:.0f} MB |")
    return "\n".join(lines) + "\n"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=2)
    args = parser.parse_args(argv)
    from . import fragments

    start = time.perf_counter()
    load = ", ".join(f"{v:.1f}" for v in os.getloadavg())
    rows = []
    for _ in range(args.rounds):
        rows.append({})
        for variant in VARIANTS:
            rows[-1][variant] = run_one(variant)
            print(json.dumps(rows[-1][variant]), flush=True)
    load = f"{load} at the start, " + ", ".join(f"{v:.1f}" for v in os.getloadavg()) + " at the end"
    text = section(rows, load, time.perf_counter() - start)
    print(text)
    fragments.write("compile", text)
    print("wrote the compile fragment of benchmarks/REPORT.md")


if __name__ == "__main__":
    sys.exit(main())
