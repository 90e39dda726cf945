"""`python -m benchmarks.bench_texel`: the transfer on a plain 4-vertex floor, per corner and
per texel, against Cycles' own world lighting.

The scene of ``bench_eevee_default`` (a plain 8 m floor, a cube, a UV sphere, a Suzanne) under
real HDRIs (or HDRI files, e.g. Probulator's probes), rendered at ``SIZE``; reference: Cycles
path tracing of the world, ``REFERENCE_SAMPLES``. Rows, Cycles at 64 spp: the world itself (no
add-on); Extract Lights (``LIGHTS``), then Transfer in Keep BSDF, baked
per corner ("CORNERS") and by Default ("AUTO": the floor per texel), with the lamps' bounce
(EEVEE's rows use it). Relative RMSE over the floor
and objects and over the floor's contact region, brightness, bake time. Writes its fragment of
benchmarks/REPORT.md ("texel").
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
from .bench_real_scene import _render, _rrmse, id_masks

HDRIS = ("sunrise", "forest", "courtyard")
REFERENCE_SAMPLES = 1024
SAMPLES = 64
BAKE_SAMPLES = 64
LIGHTS = 3  # Extract Lights' count (the API's default; sunrise's third is its 27° glow)
SIZE = (160, 100)  # pixels: sunrise's contact region holds 120 (22 at bench_eevee_default's)


def _row(name, image, reference, masks, seconds, bake_seconds=None):
    everything = masks["diffuse"] | masks["ground"]
    return {"method": name, "error": _rrmse(image, reference, everything),
            "objects": _rrmse(image, reference, masks["diffuse"]),
            "contact": _rrmse(image, reference, masks["contact"]),
            "bright": float(image[everything].mean() / reference[everything].mean()),
            "seconds": seconds, "bake": bake_seconds}


def hdri_path(hdri):
    """``hdri``: a file, or the name of one of Blender's studio-light HDRIs."""
    if Path(hdri).is_file():
        return Path(hdri)
    return Path(bpy.utils.system_resource("DATAFILES", path="studiolights/world")) / f"{hdri}.exr"


def measure(hdri, folder, reference_samples, eevee=False, size=SIZE):
    path = hdri_path(hdri)
    hdri = path.stem
    roles = build_scene(path, size)
    scene = bpy.context.scene
    masks = id_masks(scene, roles, folder)
    objects = [o for group in roles.values() for o in group]
    stem = Path(folder) / hdri
    _, reference = _render(scene, f"{stem}_ref.exr", "CYCLES", reference_samples, seed=7)
    floor = reference.mean(axis=2)
    masks["contact"] = masks["ground"] & (floor < 0.5 * np.median(floor[masks["ground"]]))
    seconds, image = _render(scene, f"{stem}_world.exr", "CYCLES", SAMPLES, seed=1)
    rows = [_row(f"Cycles, world, {SAMPLES} spp (no add-on)", image, reference, masks, seconds)]
    if eevee:
        seconds, image = _render(scene, f"{stem}_eevee_world.exr", compat.eevee_engine_id())
        rows.append(_row("EEVEE, world (no add-on)", image, reference, masks, seconds))
    notes = [f"contact region: {int(masks['contact'].sum())} pixels"]
    for store in ("CORNERS", "AUTO"):
        # As an artist works: Extract Lights, then the bake (which bakes the lamps' bounce
        # for EEVEE), then Apply
        lights = api.extract_lights(scene, count=LIGHTS)
        info = bake.bake_transfer(scene, objects, samples=BAKE_SAMPLES, store=store)
        notes.append(f"{store}: {info.corners} corners, {info.texels} texels "
                     f"({', '.join(info.texel_objects) or 'none'} per texel), "
                     f"{len(info.basis_seconds)} bakes, {info.seconds:.1f} s")
        transfer_apply.apply_transfer(objects, scene, "KEEP_BSDF")
        seconds, image = _render(scene, f"{stem}_{store}.exr", "CYCLES", SAMPLES, seed=2)
        label = "per corner" if store == "CORNERS" else "Default: the floor per texel"
        rows.append(_row(f"Transfer ({label}) + Extract Lights ({len(lights.lights)}), "
                         f"{SAMPLES} spp", image, reference, masks, seconds, info.seconds))
        if eevee and store == "AUTO":
            seconds, image = _render(scene, f"{stem}_eevee_{store}.exr",
                                     compat.eevee_engine_id())
            rows.append(_row(f"EEVEE Transfer ({label}, the lamps' bounce baked) + Extract "
                             f"Lights ({len(lights.lights)})", image, reference, masks, seconds,
                             info.seconds))
        materials.remove_from_materials(materials.materials_of(objects))
        api.compute_from_world(scene)  # deletes the extracted lights
        for obj in objects:
            bake.remove_transfer(obj)
    for row in rows:
        print(f"{hdri}: {row}", flush=True)
    return rows, notes


def section(results, load, elapsed, reference_samples, size):
    lines = [
        "## Transfer on a plain floor: per corner and per texel", "",
        f"`python -m benchmarks.bench_texel` (the scene of `bench_eevee_default`: a plain "
        f"4-vertex 8 m floor, a cube, a UV sphere, a Suzanne; reference Cycles path tracing of "
        f"the world, {reference_samples} spp; {size[0]} × {size[1]} pixels; Cycles at "
        f"{SAMPLES} spp, the bake at "
        f"{BAKE_SAMPLES}; load average {load}; {elapsed:.0f} s in all). Error: relative RMSE "
        "over the floor and objects, over the objects alone (the cube, sphere and Suzanne: the "
        "issue's diffuse-object error), and over the floor's contact region (below half the "
        "floor's median in the reference); bright: mean ÷ the reference's; contact ×: the "
        "contact error over Cycles' own world's (goal ≤ 1.25 in Cycles); EEVEE "
        f"{EEVEE_SAMPLES} samples, its times include shader compiles.", "",
    ]
    for hdri, (rows, notes) in results.items():
        base = rows[0]["contact"]
        lines += [f"**{hdri}**", "",
                  "| method | error | objects err | contact err | contact × | bright | render "
                  "| bake |",
                  "|---|---|---|---|---|---|---|---|"]
        for r in rows:
            bake_time = "" if r["bake"] is None else f"{r['bake']:.1f} s"
            lines.append(f"| {r['method']} | {r['error']:.1%} | {r['objects']:.1%} | "
                         f"{r['contact']:.1%} | "
                         f"{r['contact'] / base:.2f} | {r['bright']:.3f} | "
                         f"{r['seconds']:.1f} s | {bake_time} |")
        lines += [""] + [f"- {note}" for note in notes] + [""]
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hdris", nargs="*", default=list(HDRIS),
                        help="names of Blender's studio-light HDRIs, or HDRI files")
    parser.add_argument("--reference-samples", type=int, default=REFERENCE_SAMPLES)
    parser.add_argument("--eevee", action="store_true",
                        help="also EEVEE rows (its own world, Transfer by Default)")
    parser.add_argument("--size", nargs=2, type=int, default=list(SIZE), metavar=("W", "H"),
                        help="render size in pixels")
    parser.add_argument("--no-write", action="store_true", help="print only")
    args = parser.parse_args(argv)
    started, load = time.perf_counter(), ", ".join(f"{v:.1f}" for v in os.getloadavg())
    results = {}
    with tempfile.TemporaryDirectory() as folder:
        for hdri in args.hdris:
            results[hdri_path(hdri).name] = measure(hdri, folder, args.reference_samples,
                                                    args.eevee, tuple(args.size))
    load += " at the start, " + ", ".join(f"{v:.1f}" for v in os.getloadavg()) + " at the end"
    text = section(results, load, time.perf_counter() - started, args.reference_samples,
                   args.size)
    print(text)
    if not args.no_write:
        fragments.write("texel", text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
