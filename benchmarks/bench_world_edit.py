"""`python -m benchmarks.bench_world_edit`: Edit World in Cycles, with the lighting edited and
not, under three real HDRIs.

The real scene of ``bench_real_scene`` (ground, box, Suzanne, a glossy sphere) under
sunrise.exr, forest.exr and courtyard.exr of Blender's studio lights. Two lightings: the world
as it is, and an edited one (``edit``: a gain of 1.2 on L10, band 1 turned 10° about z). The
reference of each is Cycles path tracing of its world at ``REFERENCE_SAMPLES`` (the edited one:
the World Edit world, whose change matches the designed one to 0.86 % of E in the tests).
Rows: Blender's own world lighting and Edit World at 16 and 64 spp, and Keep BSDF at 64 spp,
each against its lighting's reference: relative RMSE over the diffuse objects and ground, the
glossy sphere and the shadowed ground, brightness, time. Writes its fragment of
benchmarks/REPORT.md ("world_edit").
"""

import argparse
import math
import os
import sys
import tempfile
import time
from pathlib import Path

import bpy
import numpy as np

from sh_lighting import api
from sh_lighting.blender.data import scene_data
from sh_lighting.blender.shading import materials

from . import fragments
from .bench_real_scene import _render, _row, build_scene, id_masks

HDRIS = ("sunrise", "forest", "courtyard")
REFERENCE_SAMPLES = 512
GAIN = 1.2  # on L10
TURN = 10.0  # degrees, band 1 about z (the clamp adds 1.5-4 % of the light on these HDRIs)
EDIT = f"L10 × {GAIN}, band 1 turned {TURN:.0f}° about z"


def edit(scene):
    """The edited lighting: a gain of ``GAIN`` on L10 and band 1 turned ``TURN``° about z (the
    channels of L1-1 ∝ y and L11 ∝ x rewritten), read live by every mode at render time."""
    scene["sh_L10_gain"] = GAIN
    c = scene_data.get_channels(scene)
    a = math.radians(TURN)
    y, x = c[1].copy(), c[3].copy()
    c[3], c[1] = math.cos(a) * x - math.sin(a) * y, math.sin(a) * x + math.cos(a) * y
    scene["sh_L1m1"], scene["sh_L11"] = list(c[1]), list(c[3])
    scene.update_tag()


# (name, Apply mode or None, samples) of each lighting; the unedited one has Blender's own
# world lighting too (the edited world exists only through World Edit)
METHODS = {
    "unedited": [("Cycles, world (no add-on), 16 spp", None, 16),
                 ("Cycles, world (no add-on), 64 spp", None, 64),
                 ("Cycles Edit World (default), 16 spp", "WORLD", 16),
                 ("Cycles Edit World (default), 64 spp", "WORLD", 64),
                 ("Cycles Keep BSDF, 64 spp", "KEEP_BSDF", 64)],
    "edited": [("Cycles Edit World (default), 16 spp", "WORLD", 16),
               ("Cycles Edit World (default), 64 spp", "WORLD", 64),
               ("Cycles Keep BSDF, 64 spp", "KEEP_BSDF", 64)],
}


def measure(hdri, size, folder):
    path = Path(bpy.utils.system_resource("DATAFILES", path="studiolights/world")) / f"{hdri}.exr"
    roles = build_scene(path, size)
    scene = bpy.context.scene
    masks = id_masks(scene, roles, folder)
    mats = materials.materials_of(scene.objects)
    results, notes, references = {}, [], {}
    for lighting, methods in METHODS.items():
        if lighting == "edited":
            edit(scene)
        clamping = api.edit_world(scene)
        note = api.edit_world_report(scene, clamping)[1]
        if note:
            notes.append(f"{lighting}: {note}")
        stem = Path(folder) / f"{hdri}_{lighting}"
        _, reference = _render(scene, f"{stem}_ref.exr", "CYCLES", REFERENCE_SAMPLES, seed=7)
        api.remove_world_edit(scene)
        references[lighting] = reference
        ground = reference.mean(axis=2)
        masks["shadowed"] = masks["ground"] & (ground < 0.5 * np.median(ground[masks["ground"]]))
        rows = []
        for index, (name, mode, samples) in enumerate(methods):
            if mode == "WORLD":
                api.edit_world(scene)
            elif mode is not None:
                materials.apply_to_materials(mats, scene, mode)
            seconds, image = _render(scene, f"{stem}_{index}.exr", "CYCLES", samples,
                                     seed=index + 1)
            if mode == "WORLD":
                api.remove_world_edit(scene)
            elif mode is not None:
                materials.remove_from_materials(mats)
            rows.append(_row(name, image, reference, masks, seconds))
            print(f"{hdri} {lighting}: {rows[-1]}", flush=True)
        results[lighting] = rows
    diffuse = masks["diffuse"] | masks["ground"]
    changed = _change(references["edited"], references["unedited"], diffuse)
    notes.append(f"the edit changes the reference's diffuse pixels by {changed:.1%} (relative "
                 "RMS)")
    return results, notes


def _change(image, reference, mask):
    difference = image[mask] - reference[mask]
    return float(np.sqrt(np.mean(difference ** 2)) / reference[mask].mean())


def section(results, notes, size, load, elapsed):
    lines = ["## Edit World in Cycles: edited and unedited lighting, three HDRIs", "",
             f"`python -m benchmarks.bench_world_edit` ({size}×{size} px; the real scene of "
             "the section above: ground 40 m, a box and a Suzanne, base 0.8, roughness 0.5, a "
             "sphere of metallic 0.8, roughness 0.5; max 4 bounces; load average "
             f"{load}; {elapsed:.0f} s in all). Two lightings: the world as it is, and edited "
             f"({EDIT}). The reference of each: Cycles path tracing of its world at "
             f"{REFERENCE_SAMPLES} spp (the edited one through World Edit, which the tests "
             "check against the designed change). Error: relative RMSE over the diffuse "
             "objects and ground, the glossy sphere, and the shadowed ground (below half the "
             "ground's median in that reference); bright: mean over the diffuse pixels ÷ the "
             "reference's; ratio: diffuse error ÷ that of Blender's own world lighting at the "
             "same samples, unedited.", ""]
    for hdri, by_lighting in results.items():
        own = {r["method"].rsplit(", ", 1)[-1]: r["diffuse"] for r in by_lighting["unedited"]
               if "no add-on" in r["method"]}
        lines += [f"**{hdri}.exr**", "",
                  "| lighting | method | diffuse err | ratio | glossy err | shadowed err | "
                  "bright | time |", "|---|---|---|---|---|---|---|---|"]
        for lighting, rows in by_lighting.items():
            for r in rows:
                base = own.get(r["method"].rsplit(", ", 1)[-1])
                ratio = f"{r['diffuse'] / base:.2f}" if base else "–"
                lines.append(f"| {lighting} | {r['method']} | {r['diffuse']:.1%} | {ratio} | "
                             f"{r['glossy']:.1%} | {r['shadowed']:.1%} | {r['bright']:.3f} | "
                             f"{r['seconds']:.1f} s |")
        lines.append("")
        lines += [f"- {note}" for note in notes.get(hdri, ())]
        lines.append("")
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=64)
    parser.add_argument("--hdri", action="append", choices=HDRIS,
                        help="only this HDRI (repeatable; default: all)")
    args = parser.parse_args(argv)
    start = time.perf_counter()
    load = ", ".join(f"{v:.1f}" for v in os.getloadavg())
    with tempfile.TemporaryDirectory() as folder:
        results, notes = {}, {}
        for hdri in args.hdri or HDRIS:
            results[hdri], notes[hdri] = measure(hdri, args.size, folder)
    load = f"{load} at the start, " + ", ".join(f"{v:.1f}" for v in os.getloadavg()) + " at the end"
    text = section(results, notes, args.size, load, time.perf_counter() - start)
    print(text)
    fragments.write("world_edit", text)
    print("wrote the world_edit fragment of benchmarks/REPORT.md")


if __name__ == "__main__":
    sys.exit(main())
