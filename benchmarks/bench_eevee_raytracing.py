"""`python -m benchmarks.bench_eevee_raytracing`: would EEVEE's own Raytracing give the
lamps' bounce that EEVEE Transfer + Lights lacks?

Item 3 of "Right by default (2/2)": EEVEE Transfer + Extract Lights is dark where the extracted
Suns' light bounces (sunrise 0.91). EEVEE's Raytracing (Render Properties, off by default;
screen-space, Fast GI for the rest) bounces what the screen shows, lamps included. Measured on
``bench_texel``'s scene against Cycles path tracing of the world: EEVEE's own world and EEVEE
Transfer (the Default: the floor per texel; baked before Extract Lights (2), so without the
lamps' bounce the bake now adds, ``transfer.bounce``), each with Raytracing off and on,
each rendered twice (the second is the frame without its compiles). Writes its fragment of
benchmarks/REPORT.md ("eevee_raytracing").
"""

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

import bpy
import numpy as np

from sh_lighting import api
from sh_lighting.blender.data import compat
from sh_lighting.blender.shading import materials
from sh_lighting.blender.transfer import apply as transfer_apply
from sh_lighting.blender.transfer import bake

from . import fragments
from .bench_eevee_default import EEVEE_SAMPLES, build_scene
from .bench_real_scene import _render, id_masks
from .bench_texel import BAKE_SAMPLES, HDRIS, LIGHTS, _row

REFERENCE_SAMPLES = 512


def _eevee(scene, folder, name, raytracing):
    """(first render s, second render s, image) in EEVEE with Raytracing on or off."""
    scene.eevee.use_raytracing = raytracing
    engine = compat.eevee_engine_id()
    first, _ = _render(scene, Path(folder) / f"{name}_1.exr", engine)
    second, image = _render(scene, Path(folder) / f"{name}_2.exr", engine)
    scene.eevee.use_raytracing = False
    return first, second, image


def measure(hdri, folder, reference_samples):
    path = Path(bpy.utils.system_resource("DATAFILES", path="studiolights/world")) / f"{hdri}.exr"
    roles = build_scene(path)
    scene = bpy.context.scene
    masks = id_masks(scene, roles, folder)
    objects = [o for group in roles.values() for o in group]
    _, reference = _render(scene, Path(folder) / f"{hdri}_ref.exr", "CYCLES", reference_samples,
                           seed=7)
    floor = reference.mean(axis=2)
    masks["contact"] = masks["ground"] & (floor < 0.5 * np.median(floor[masks["ground"]]))
    rows = []

    def add(label, raytracing):
        first, second, image = _eevee(scene, folder, f"{hdri}_{len(rows)}", raytracing)
        row = _row(label, image, reference, masks, second)
        row.update(raytracing=raytracing, first=first)
        rows.append(row)
        print(f"{hdri}: {row}", flush=True)

    for raytracing in (False, True):
        add("EEVEE, world (no add-on)", raytracing)
    info = bake.bake_transfer(scene, objects, samples=BAKE_SAMPLES, store="AUTO")
    lights = api.extract_lights(scene, count=LIGHTS)
    transfer_apply.apply_transfer(objects, scene, "KEEP_BSDF")
    for raytracing in (False, True):
        add(f"EEVEE Transfer + Extract Lights ({len(lights.lights)})", raytracing)
    materials.remove_from_materials(materials.materials_of(objects))
    return rows, info.seconds


def section(results, load, elapsed, reference_samples):
    lines = [
        "## EEVEE's Raytracing for the lamps' bounce", "",
        f"`python -m benchmarks.bench_eevee_raytracing` (bench_texel's scene; reference Cycles "
        f"path tracing of the world, {reference_samples} spp; EEVEE {EEVEE_SAMPLES} samples, "
        f"Raytracing off (Blender's default) and on; the transfer baked at {BAKE_SAMPLES} "
        f"samples, the floor per texel; load average {load}; {elapsed:.0f} s in all). Error: "
        "relative RMSE over the floor and objects, and over the floor's contact region; "
        "bright: mean ÷ the reference's; frame: the second of two renders in a row; first: "
        "the first, its shader compiles included.", "",
        "| HDRI | method | Raytracing | error | contact err | bright | frame | first |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for hdri, (rows, _bake_seconds) in results.items():
        for r in rows:
            lines.append(f"| {hdri} | {r['method']} | {'on' if r['raytracing'] else 'off'} | "
                         f"{r['error']:.1%} | {r['contact']:.1%} | {r['bright']:.3f} | "
                         f"{r['seconds']:.1f} s | {r['first']:.1f} s |")
    return "\n".join(lines) + "\n"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hdris", nargs="*", default=list(HDRIS))
    parser.add_argument("--reference-samples", type=int, default=REFERENCE_SAMPLES)
    parser.add_argument("--no-write", action="store_true", help="print only")
    args = parser.parse_args(argv)
    started, load = time.perf_counter(), ", ".join(f"{v:.1f}" for v in os.getloadavg())
    results = {}
    with tempfile.TemporaryDirectory() as folder:
        for hdri in args.hdris:
            results[hdri] = measure(hdri, folder, args.reference_samples)
    load += " at the start, " + ", ".join(f"{v:.1f}" for v in os.getloadavg()) + " at the end"
    text = section(results, load, time.perf_counter() - started, args.reference_samples)
    print(text)
    if not args.no_write:
        fragments.write("eevee_raytracing", text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
