"""`python -m benchmarks.bench_eevee_default`: which Apply mode EEVEE should use by default.

A scene as an artist makes it: a plain 4-vertex 8 m floor, a cube, a UV sphere and a Suzanne
(Principled, base 0.8, roughness 0.5, metallic 0) under real HDRIs of Blender's studio lights,
rendered tiny. Two lightings: the world as it is, and an edited one (``bench_world_edit.edit``:
a gain of 1.2 on L10, band 1 turned 10° about z). Reference: Cycles path tracing of that lighting's world (World
Edit in Cycles, which renders the unedited world bit for bit), ``REFERENCE_SAMPLES``. Each
EEVEE candidate (EEVEE's own world lighting, World Edit, Keep BSDF) against it: relative RMSE
over the floor and objects, over the floor's contact region (below half the floor's median in
the reference), and brightness (mean ÷ the reference's). Writes its fragment of
benchmarks/REPORT.md ("eevee_default").
"""

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

import bpy
import numpy as np
from mathutils import Vector

from sh_lighting import api
from sh_lighting.blender.data import compat
from sh_lighting.blender.shading import materials

from tests.blender_scenes import environment_world

from . import fragments
from .bench_real_scene import _principled, _render, _rrmse, id_masks
from .bench_world_edit import EDIT, edit
from .render_bench import _settings

HDRIS = ("sunrise", "forest", "courtyard")
REFERENCE_SAMPLES = 1024
EEVEE_SAMPLES = 16
SIZE = (64, 40)


def build_scene(hdri_path, size=SIZE):
    """The scene (module docstring) in a fresh Blender; returns {role: [objects]}."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    environment_world(scene, str(hdri_path), name="HDRI")
    grey = _principled("Grey", Base_Color=(0.8, 0.8, 0.8, 1.0), Roughness=0.5)
    bpy.ops.mesh.primitive_plane_add(size=8.0)
    floor = bpy.context.object
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(-1.4, 0.4, 0.5))
    cube = bpy.context.object
    bpy.ops.mesh.primitive_uv_sphere_add(radius=0.5, location=(1.4, 0.3, 0.5))
    bpy.ops.object.shade_smooth()
    sphere = bpy.context.object
    bpy.ops.mesh.primitive_monkey_add(size=1.0, location=(0.0, 0.0, 0.5))
    bpy.ops.object.shade_smooth()
    monkey = bpy.context.object
    roles = {"ground": [floor], "diffuse": [cube, sphere, monkey], "glossy": []}
    for obj in (floor, cube, sphere, monkey):
        obj.data.materials.append(grey)
    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    scene.collection.objects.link(camera)
    camera.location = (0.0, -5.5, 2.6)
    camera.rotation_euler = (Vector((0.0, 0.2, 0.35)) - camera.location).to_track_quat(
        "-Z", "Y").to_euler()
    camera.data.lens = 35.0
    scene.camera = camera
    _settings(scene, size[0], "CYCLES")
    scene.render.resolution_x, scene.render.resolution_y = size
    scene.render.film_transparent = False
    scene.cycles.max_bounces = 4
    scene.eevee.taa_render_samples = EEVEE_SAMPLES
    api.compute_from_world(scene)
    return roles


def _row(name, image, reference, masks, seconds):
    everything = masks["diffuse"] | masks["ground"]
    return {"method": name, "diffuse": _rrmse(image, reference, everything),
            "contact": _rrmse(image, reference, masks["contact"]),
            "bright": float(image[everything].mean() / reference[everything].mean()),
            "seconds": seconds}


def measure(hdri, folder, reference_samples):
    path = Path(bpy.utils.system_resource("DATAFILES", path="studiolights/world")) / f"{hdri}.exr"
    roles = build_scene(path)
    scene = bpy.context.scene
    masks = id_masks(scene, roles, folder)
    mats = materials.materials_of(scene.objects)
    eevee = compat.eevee_engine_id()
    results, notes = {}, []
    for lighting in ("unedited", "edited"):
        if lighting == "edited":
            edit(scene)
        clamping = api.edit_world(scene)
        if clamping is not None and clamping.share > 0:
            notes.append(f"{lighting}: World Edit's clamp adds {clamping.share:.2%} of the "
                         f"light; the clamped world's nine terms differ from the designed by "
                         f"{clamping.difference:.2%} of L00")
        stem = Path(folder) / f"{hdri}_{lighting}"
        _, reference = _render(scene, f"{stem}_ref.exr", "CYCLES", reference_samples, seed=7)
        floor = reference.mean(axis=2)
        masks["contact"] = masks["ground"] & (floor < 0.5 * np.median(floor[masks["ground"]]))
        rows = []
        seconds, image = _render(scene, f"{stem}_cw.exr", "CYCLES", 64, seed=1)
        rows.append(_row("Cycles World Edit (default), 64 spp", image, reference, masks,
                         seconds))
        seconds, image = _render(scene, f"{stem}_ew.exr", eevee, EEVEE_SAMPLES)
        rows.append(_row("EEVEE World Edit", image, reference, masks, seconds))
        api.remove_world_edit(scene)
        if lighting == "unedited":
            seconds, image = _render(scene, f"{stem}_cy.exr", "CYCLES", 64, seed=1)
            rows.append(_row("Cycles, world, 64 spp (no add-on)", image, reference, masks,
                             seconds))
            seconds, image = _render(scene, f"{stem}_eo.exr", eevee, EEVEE_SAMPLES)
            rows.append(_row("EEVEE, world (no add-on)", image, reference, masks, seconds))
        materials.apply_to_materials(mats, scene, "KEEP_BSDF")
        seconds, image = _render(scene, f"{stem}_ek.exr", eevee, EEVEE_SAMPLES)
        rows.append(_row("EEVEE Keep BSDF", image, reference, masks, seconds))
        materials.remove_from_materials(mats)
        results[lighting] = rows
        for row in rows:
            print(f"{hdri} {lighting}: {row}", flush=True)
    return results, notes


def section(results, notes, load, elapsed, reference_samples):
    lines = ["## EEVEE's default Apply: World Edit or Keep BSDF", "",
             f"`python -m benchmarks.bench_eevee_default` ({SIZE[0]}×{SIZE[1]} px; reference: "
             f"Cycles path tracing of the lighting's world, {reference_samples} spp, max 4 "
             f"bounces; EEVEE {EEVEE_SAMPLES} samples, its defaults otherwise; load average "
             f"{load}; {elapsed:.0f} s in all, times include EEVEE's shader compiles and so "
             "compare only within a run). A plain 4-vertex 8 m floor, a cube, a UV sphere and "
             "a Suzanne (Principled, base 0.8, roughness 0.5). Two lightings: the world as it "
             f"is, and edited ({EDIT}); the "
             "reference of the edited one is Cycles path tracing of the edited world. Error: "
             "relative RMSE over the floor and objects, and over the floor's contact region "
             "(below half the floor's median in the reference); bright: mean ÷ the "
             "reference's.", ""]
    for hdri, by_lighting in results.items():
        lines += [f"**{hdri}.exr**", "",
                  "| lighting | method | error | contact err | bright | time |",
                  "|---|---|---|---|---|---|"]
        for lighting, rows in by_lighting.items():
            for r in rows:
                lines.append(f"| {lighting} | {r['method']} | {r['diffuse']:.1%} | "
                             f"{r['contact']:.1%} | {r['bright']:.3f} | {r['seconds']:.1f} s |")
        lines.append("")
        lines += [f"- {note}" for note in notes.get(hdri, ())]
        if notes.get(hdri):
            lines.append("")
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hdri", action="append", choices=HDRIS,
                        help="only this HDRI (repeatable; default: all)")
    parser.add_argument("--reference-samples", type=int, default=REFERENCE_SAMPLES)
    args = parser.parse_args(argv)
    start = time.perf_counter()
    load = ", ".join(f"{v:.1f}" for v in os.getloadavg())
    with tempfile.TemporaryDirectory() as folder:
        results, notes = {}, {}
        for hdri in args.hdri or HDRIS:
            results[hdri], notes[hdri] = measure(hdri, folder, args.reference_samples)
    load = f"{load} at the start, " + ", ".join(f"{v:.1f}" for v in os.getloadavg()) + " at the end"
    text = section(results, notes, load, time.perf_counter() - start, args.reference_samples)
    print(text)
    fragments.write("eevee_default", text)
    print("wrote the eevee_default fragment of benchmarks/REPORT.md")


if __name__ == "__main__":
    sys.exit(main())
