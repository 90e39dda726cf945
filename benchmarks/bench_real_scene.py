"""`python -m benchmarks.bench_real_scene`: every Apply mode in a real scene.

A 40 m ground, a box and a Suzanne (diffuse, base 0.8, roughness 0.5) and a glossy sphere
(metallic 0.8, roughness 0.5) under sunrise.exr and forest.exr; each method of ``METHODS``
(and ``TRANSFER_METHODS``, with and without Extract Lights) renders it, compared with Cycles
path tracing of the world (``REFERENCE_SAMPLES``): relative RMSE over the diffuse objects, the
glossy sphere and the shadowed ground (below half the ground's median in the reference),
brightness, time; EEVEE frame times also warm. Writes its fragment of benchmarks/REPORT.md
("real_scene"); ``--only`` replaces the rows of the methods run and keeps the others.
"""

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

import bpy
import bmesh  # noqa: I001 (after bpy: the bpy module provides it)
import numpy as np
from mathutils import Vector

from sh_lighting import api
from sh_lighting.blender.data import compat
from sh_lighting.blender.shading import materials
from sh_lighting.blender.transfer import apply as transfer_apply
from sh_lighting.blender.transfer import bake
from sh_lighting.blender.world.images import load_image_pixels

from tests.blender_scenes import environment_world

from . import fragments
from .render_bench import _settings

HERE = Path(__file__).resolve().parent
HDRIS = ("sunrise", "forest")
REFERENCE_SAMPLES = 512
EEVEE_SAMPLES = 16
TRANSFER_SAMPLES = 64  # the bake's default: E noise about 1.4 % per corner (REPORT.md)
LIGHTS = 2  # Extract Lights' count, as in the Apply modes' table


def _principled(name, **inputs):
    material = bpy.data.materials.new(name)
    bsdf = compat.ensure_node_tree(material).nodes["Principled BSDF"]
    for key, value in inputs.items():
        bsdf.inputs[key.replace("_", " ")].default_value = value
    return material


def _grid_lines(half, fine_half, step, growth=1.25):
    """Coordinates from -half to half: every ``step`` within ±fine_half, then steps growing by
    ``growth`` out to the edge."""
    inner = np.linspace(-fine_half, fine_half, int(round(2 * fine_half / step)) + 1)
    outer, position, width = [], fine_half, step
    while position < half - 1e-6:
        width *= growth
        position = min(position + width, half)
        outer.append(position)
    outer = np.array(outer)
    return np.concatenate([-outer[::-1], inner, outer])


def _ground(size=40.0, fine_half=4.0, step=0.12):
    """The ground plane (``size`` m square) as a grid, ``step`` m apart within ±fine_half of
    the objects: rendered as a plane, and fine enough for the transfer's per-corner shadows."""
    xs = _grid_lines(size / 2, fine_half, step)
    ys = xs + 0.3  # the objects stand around y = 0.3
    ys[0], ys[-1] = -size / 2, size / 2
    bm = bmesh.new()
    verts = [[bm.verts.new((x, y, 0.0)) for x in xs] for y in ys]
    for j in range(len(ys) - 1):
        for i in range(len(xs) - 1):
            bm.faces.new((verts[j][i], verts[j][i + 1], verts[j + 1][i + 1], verts[j + 1][i]))
    mesh = bpy.data.meshes.new("Ground")
    bm.to_mesh(mesh)
    bm.free()
    ground = bpy.data.objects.new("Ground", mesh)
    bpy.context.scene.collection.objects.link(ground)
    return ground


def build_scene(hdri_path, size):
    """The scene (module docstring) in a fresh Blender; returns {role: [objects]}."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    environment_world(scene, str(hdri_path), name="HDRI")
    diffuse = _principled("Diffuse", Base_Color=(0.8, 0.8, 0.8, 1.0), Roughness=0.5)
    glossy = _principled("Glossy", Base_Color=(0.8, 0.8, 0.8, 1.0), Roughness=0.5,
                         Metallic=0.8)
    roles = {"ground": [_ground()], "diffuse": [], "glossy": []}
    bpy.ops.mesh.primitive_cube_add(size=1.2, location=(-1.6, 0.4, 0.6))
    box = bpy.context.object
    bm = bmesh.new()
    bm.from_mesh(box.data)
    bmesh.ops.subdivide_edges(bm, edges=bm.edges[:], cuts=7, use_grid_fill=True)
    bm.to_mesh(box.data)
    bm.free()
    roles["diffuse"].append(box)
    bpy.ops.mesh.primitive_monkey_add(size=1.4, location=(0.2, 0.0, 0.75))
    bpy.ops.object.shade_smooth()
    roles["diffuse"].append(bpy.context.object)
    bpy.ops.mesh.primitive_uv_sphere_add(radius=0.7, segments=48, ring_count=24,
                                         location=(1.9, 0.2, 0.7))
    bpy.ops.object.shade_smooth()
    roles["glossy"].append(bpy.context.object)
    for role, objects in roles.items():
        for obj in objects:
            obj.data.materials.append(glossy if role == "glossy" else diffuse)
    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    scene.collection.objects.link(camera)
    camera.location = (0.0, -7.5, 3.6)
    camera.rotation_euler = (Vector((0.2, 0.0, 0.5)) - camera.location).to_track_quat(
        "-Z", "Y").to_euler()
    camera.data.lens = 35.0
    scene.camera = camera
    _settings(scene, size, "CYCLES")
    scene.render.film_transparent = False
    scene.cycles.max_bounces = 4
    scene.eevee.taa_render_samples = EEVEE_SAMPLES
    api.compute_from_world(scene)
    return roles


def _render(scene, path, engine, samples=1, seed=0):
    scene.render.engine = engine
    scene.cycles.samples = samples
    scene.cycles.seed = seed
    scene.render.filepath = str(path)
    start = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    return time.perf_counter() - start, load_image_pixels(path)[..., :3].astype(np.float64)


def id_masks(scene, roles, folder):
    """{role: bool (H, W)} from one Cycles render of each role in an emission colour."""
    saved = {obj.name: list(obj.data.materials) for objs in roles.values() for obj in objs}
    world = scene.world
    scene.world = None
    colours = {"ground": (1, 0, 0), "diffuse": (0, 1, 0), "glossy": (0, 0, 1)}
    for role, objects in roles.items():
        material = bpy.data.materials.new(f"ID {role}")
        tree = compat.ensure_node_tree(material)
        emission = tree.nodes.new("ShaderNodeEmission")
        emission.inputs["Color"].default_value = (*colours[role], 1.0)
        tree.links.new(emission.outputs[0], tree.nodes["Material Output"].inputs["Surface"])
        for obj in objects:
            obj.data.materials[0] = material
    _, image = _render(scene, Path(folder) / "ids.exr", "CYCLES")
    for objects in roles.values():
        for obj in objects:
            obj.data.materials[0] = saved[obj.name][0]
    scene.world = world
    return {role: image[..., index] > 0.999 for index, role in enumerate(colours)}


# Each method: (name, engine, Apply mode or None, samples, Emission Sampling forced or None).
METHODS = [
    ("Cycles, world, 16 spp (no add-on)", "CYCLES", None, 16, None),
    ("Cycles, world, 64 spp (no add-on)", "CYCLES", None, 64, None),
    ("EEVEE, world (no add-on)", "EEVEE", None, EEVEE_SAMPLES, None),
    ("Cycles Keep BSDF, 16 spp (Emission Sampling None)", "CYCLES", "KEEP_BSDF", 16, None),
    ("Cycles Keep BSDF, 16 spp (Emission Sampling Auto)", "CYCLES", "KEEP_BSDF", 16, "AUTO"),
    ("Cycles Keep BSDF, 64 spp", "CYCLES", "KEEP_BSDF", 64, None),
    ("EEVEE Keep BSDF (default)", "EEVEE", "KEEP_BSDF", EEVEE_SAMPLES, None),
    ("Cycles Emission Only, 1 spp", "CYCLES", "EMISSION", 1, None),
    ("EEVEE Emission Only", "EEVEE", "EMISSION", EEVEE_SAMPLES, None),
    ("Cycles Edit World (default), 16 spp", "CYCLES", "WORLD", 16, None),
    ("Cycles Edit World (default), 64 spp", "CYCLES", "WORLD", 64, None),
]
# Edit World with Extract Lights' lamps: (name, samples, lights); the world no longer emits
# what the lamps do
WORLD_LIGHTS_METHODS = [
    (f"Cycles Edit World + Extract Lights ({LIGHTS}), 64 spp", 64, LIGHTS),
]


def _rrmse(image, reference, mask):
    if not mask.any():
        return float("nan")
    difference = image[mask] - reference[mask]
    return float(np.sqrt(np.mean(difference ** 2)) / reference[mask].mean())


def _chosen(methods, only):
    """The entries of ``methods`` whose name contains one of the substrings ``only`` (all
    when None)."""
    return [m for m in methods if only is None or any(part in m[0] for part in only)]


def measure(hdri, size, folder, only=None):
    path = Path(bpy.utils.system_resource("DATAFILES", path="studiolights/world")) / f"{hdri}.exr"
    roles = build_scene(path, size)
    scene = bpy.context.scene
    masks = id_masks(scene, roles, folder)
    _, reference = _render(scene, Path(folder) / f"{hdri}_ref.exr", "CYCLES",
                           REFERENCE_SAMPLES, seed=7)
    ground = reference.mean(axis=2)
    lit = ground[masks["ground"]]
    masks["shadowed"] = masks["ground"] & (ground < 0.5 * np.median(lit))
    all_mats = materials.materials_of(scene.objects)
    rows = []
    for index, (name, engine, mode, samples, sampling) in enumerate(METHODS):
        if (name, engine, mode, samples, sampling) not in _chosen(METHODS, only):
            continue
        if mode == "WORLD":
            api.edit_world(scene)
        elif mode is not None:
            materials.apply_to_materials(all_mats, scene, mode)
            if sampling is not None:
                for material in all_mats:
                    material.cycles.emission_sampling = sampling
        engine_id = compat.eevee_engine_id() if engine == "EEVEE" else "CYCLES"
        seconds, image = _render(scene, Path(folder) / f"{hdri}_{index}.exr", engine_id,
                                 samples, seed=index)
        if mode == "WORLD":
            api.remove_world_edit(scene)
        elif mode is not None:
            materials.remove_from_materials(all_mats)
        rows.append(_row(name, image, reference, masks, seconds))
        print(f"{hdri}: {name}: {rows[-1]}", flush=True)
    for index, (name, samples, count) in enumerate(_chosen(WORLD_LIGHTS_METHODS, only)):
        api.extract_lights(scene, count=count)
        api.edit_world(scene)
        seconds, image = _render(scene, Path(folder) / f"{hdri}_w{index}.exr", "CYCLES",
                                 samples, seed=200 + index)
        api.remove_world_edit(scene)
        api.compute_from_world(scene)  # deletes the extracted lights
        rows.append(_row(name, image, reference, masks, seconds))
        print(f"{hdri}: {name}: {rows[-1]}", flush=True)
    if not _chosen(TRANSFER_METHODS, only):
        return rows, []
    transfer, notes = transfer_rows(scene, roles, reference, masks, folder, hdri, only)
    return rows + transfer, notes


def _row(name, image, reference, masks, seconds):
    diffuse = masks["diffuse"] | masks["ground"]
    return {
        "method": name, "diffuse": _rrmse(image, reference, diffuse),
        "glossy": _rrmse(image, reference, masks["glossy"]),
        "shadowed": _rrmse(image, reference, masks["shadowed"]),
        "bright": float(image[diffuse].mean() / reference[diffuse].mean()),
        "seconds": seconds,
    }


# Transfer rows: (name, engine, Apply mode, samples, Extract Lights count). Emission Only
# receives no lamps, so it is shown without them.
TRANSFER_METHODS = [
    ("Cycles TRANSFER Emission Only, 1 spp", "CYCLES", "EMISSION", 1, 0),
    ("EEVEE TRANSFER Keep BSDF", "EEVEE", "KEEP_BSDF", EEVEE_SAMPLES, 0),
    (f"EEVEE TRANSFER Keep BSDF + Extract Lights ({LIGHTS})", "EEVEE", "KEEP_BSDF",
     EEVEE_SAMPLES, LIGHTS),
    (f"Cycles TRANSFER Keep BSDF + Extract Lights ({LIGHTS}), 16 spp", "CYCLES", "KEEP_BSDF",
     16, LIGHTS),
    (f"Cycles TRANSFER Keep BSDF + Extract Lights ({LIGHTS}), 64 spp", "CYCLES", "KEEP_BSDF",
     64, LIGHTS),
]


def transfer_rows(scene, roles, reference, masks, folder, hdri, only=None):
    """Bake the transfer of every object, render ``TRANSFER_METHODS``, then the warm EEVEE
    frame times; (rows, notes: lines for the report)."""
    objects = [obj for group in roles.values() for obj in group]
    info = bake.bake_transfer(scene, objects, samples=TRANSFER_SAMPLES)
    notes = [f"transfer bake: {info.vertices} vertices, {info.corners} corners, "
             f"{info.samples} samples, {info.seconds:.1f} s "
             f"({info.seconds / info.vertices * 1e4:.0f} s per 10k vertices)"]
    mats = materials.materials_of(objects)
    rows, lights = [], 0
    for index, (name, engine, mode, samples, count) in enumerate(TRANSFER_METHODS):
        if (name, engine, mode, samples, count) not in _chosen(TRANSFER_METHODS, only):
            continue
        if count != lights:
            if count:
                notes.append(api.extract_lights(scene, count=count).report())
            else:
                api.compute_from_world(scene)  # deletes the extracted lights
            lights = count
        transfer_apply.apply_transfer(objects, scene, mode)
        engine_id = compat.eevee_engine_id() if engine == "EEVEE" else "CYCLES"
        seconds, image = _render(scene, Path(folder) / f"{hdri}_t{index}.exr", engine_id,
                                 samples, seed=100 + index)
        materials.remove_from_materials(mats)
        rows.append(_row(name, image, reference, masks, seconds))
        print(f"{hdri}: {name}: {rows[-1]}", flush=True)
    if only is None:
        notes.append(_warm_eevee_times(scene, objects, folder, hdri, lights))
    api.compute_from_world(scene)
    for note in notes:
        print(f"NOTE {hdri}: {note}", flush=True)
    return rows, notes


def _warm_eevee_times(scene, objects, folder, hdri, lights):
    """EEVEE frame time, shaders compiled: each variant rendered twice in a row, the second
    timed; world, transfer + lights, world, transfer + lights (interleaved)."""
    times = {"world": [], "transfer": []}
    engine = compat.eevee_engine_id()
    mats = materials.materials_of(objects)
    for _ in range(2):
        for variant in times:
            if variant == "world":
                api.compute_from_world(scene)  # no lights
            else:
                if lights:
                    api.extract_lights(scene, count=lights)
                transfer_apply.apply_transfer(objects, scene, "KEEP_BSDF")
            for _repeat in range(2):
                seconds, _ = _render(scene, Path(folder) / f"{hdri}_warm.exr", engine,
                                     EEVEE_SAMPLES)
            times[variant].append(seconds)
            materials.remove_from_materials(mats)
    world, transfer = min(times["world"]), min(times["transfer"])
    return (f"EEVEE frame time, shaders compiled (second of two renders, best of 2 "
            f"interleaved): Blender's own world lighting {world:.2f} s, TRANSFER Keep BSDF + "
            f"Extract Lights ({lights}) {transfer:.2f} s ({transfer / world:.2f}×)")


def section(results, size, load, elapsed, notes=None):
    lines = ["## Real scene: every Apply mode against path tracing", "",
             f"`python -m benchmarks.bench_real_scene` ({size}×{size} px, reference: Cycles "
             f"path tracing of the world at {REFERENCE_SAMPLES} spp, max 4 bounces; load "
             f"average {load}; {elapsed:.0f} s in all). Ground 40 m, a box and a Suzanne "
             "(base 0.8, roughness 0.5), a sphere of metallic 0.8, roughness 0.5. Error: "
             "relative RMSE over the diffuse objects and ground, the glossy sphere, and the "
             "shadowed ground (below half the ground's median in the reference); bright: mean "
             "over the diffuse pixels ÷ the reference's.", ""]
    for hdri, rows in results.items():
        lines += [f"**{hdri}.exr**", "",
                  "| method | diffuse err | glossy err | shadowed err | bright | time |",
                  "|---|---|---|---|---|---|"]
        for r in rows:
            lines.append(f"| {r['method']} | {r['diffuse']:.1%} | {r['glossy']:.1%} | "
                         f"{r['shadowed']:.1%} | {r['bright']:.3f} | {r['seconds']:.1f} s |")
        lines.append("")
        lines += [f"- {note}" for note in (notes or {}).get(hdri, ())]
        if (notes or {}).get(hdri):
            lines.append("")
    return "\n".join(lines)


def merge(text, results):
    """``text`` (the fragment) with the rows of ``results`` ({hdri: rows}) in place of the rows
    of the same method in its tables (under "**{hdri}.exr**"), appending a row a table lacks;
    every other line is kept (a partial run, ``--only``)."""
    lines = text.split("\n")
    begin, end = 0, len(lines)
    for hdri, rows in results.items():
        head = next(i for i in range(begin, end) if lines[i].startswith(f"**{hdri}.exr**"))
        first = next(i for i in range(head, end) if lines[i].startswith("| method |")) + 2
        last = next(i for i in range(first, end) if not lines[i].startswith("|"))
        for r in rows:
            text = (f"| {r['method']} | {r['diffuse']:.1%} | {r['glossy']:.1%} | "
                    f"{r['shadowed']:.1%} | {r['bright']:.3f} | {r['seconds']:.1f} s |")
            match = [i for i in range(first, last) if lines[i].startswith(f"| {r['method']} |")]
            if match:
                lines[match[0]] = text
            else:
                lines.insert(last, text)
                last, end = last + 1, end + 1
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=64)
    parser.add_argument("--hdri", action="append", choices=HDRIS,
                        help="only this HDRI (repeatable; default: all)")
    parser.add_argument("--only", action="append", metavar="SUBSTRING",
                        help="only the methods whose name contains SUBSTRING (repeatable); "
                             "their rows replace those of the same name in the report, the "
                             "rest of the section is kept")
    args = parser.parse_args(argv)
    start = time.perf_counter()
    load = ", ".join(f"{v:.1f}" for v in os.getloadavg())
    with tempfile.TemporaryDirectory() as folder:
        results, notes = {}, {}
        for hdri in args.hdri or HDRIS:
            results[hdri], notes[hdri] = measure(hdri, args.size, folder, args.only)
    load_end = ", ".join(f"{v:.1f}" for v in os.getloadavg())
    print(f"load average {load} at the start, {load_end} at the end; "
          f"{time.perf_counter() - start:.0f} s", flush=True)
    if args.only or args.hdri:
        fragments.write("real_scene", merge(fragments.read("real_scene"), results))
    else:
        fragments.write("real_scene",
                        section(results, args.size, load, time.perf_counter() - start, notes))
    print("wrote the real-scene fragment of benchmarks/REPORT.md")


if __name__ == "__main__":
    sys.exit(main())
