"""What fitting the SH node group to the lighting saves: nodes, Cycles time, EEVEE compile.

`python -m benchmarks.bench_nodes`: for the presets of the 8 HDRIs bundled with Blender and
the paper's 3 Figure-2 probes (presets/*.json), plus three synthetic lightings where fitting
removes terms (ambient only, a grey sky, ambient and one coloured direction), the full group
(all nine terms, RGB, no clamp) and the fitted one (``fitting.fitted_spec`` at the default
tolerance and Clamp = Auto) are built (``nodes.build_node_group``) into the material of a
sphere and compared:

* nodes: the group's node count;
* Cycles: render time of a 128² frame at 64 samples on the CPU, median of 3 after a warm-up;
* EEVEE: the first render (64², 1 sample) of a fresh material, shader compile included.
  EEVEE caches compiled shaders by their code, and socket values are not part of the code, so
  each fresh material gets a code of its own: j = 1, 2, 3 extra Vector Math nodes after the
  group (the same for the full and the fitted group); the median of the three. A layout is
  measured once, where it first appears (later rows show "="). With software OpenGL (llvmpipe)
  one group's compile can be below the noise of a render, and "first − second render" does
  not isolate it either; a material holding several copies of the group, to amplify the
  compile, can take too long to compile under llvmpipe.

Takes minutes; run it on a quiet machine.
"""

import statistics
import time
from pathlib import Path

import bpy
import numpy as np

from sh_lighting.blender import compat, fitting, nodes, scene_data
from sh_lighting.core import pruning
from sh_lighting.core.presets import read_preset

ROOT = Path(__file__).resolve().parent.parent
HDRI_PRESETS = ("city", "courtyard", "forest", "interior", "night", "studio", "sunrise", "sunset")
FIGURE2_PRESETS = ("grace_cathedral", "eucalyptus_grove", "st_peters_basilica")
CYCLES_SIZE, CYCLES_SAMPLES, CYCLES_REPEATS = 128, 64, 3
EEVEE_SIZE = 64
EEVEE_VARIANTS = 3


def synthetic_cases():
    ambient = np.zeros((9, 3))
    ambient[0] = (1.2, 1.1, 1.0)
    sky = np.zeros((9, 3))
    sky[0], sky[2], sky[6] = 1.5, 0.8, 0.3  # grey: brighter above, darker at the horizon
    sun = np.zeros((9, 3))
    sun[0], sun[3] = (1.0, 0.9, 0.8), (0.5, 0.4, 0.2)  # ambient + a coloured direction, +X
    return [("ambient (synthetic)", ambient), ("grey sky (synthetic)", sky),
            ("ambient+dir (synthetic)", sun)]


def cases():
    found = []
    for name in HDRI_PRESETS + FIGURE2_PRESETS:
        coeffs, _metadata = read_preset(ROOT / "presets" / f"{name}.json")
        found.append((name, coeffs))
    return found + synthetic_cases()


def setup_scene():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    bpy.ops.mesh.primitive_uv_sphere_add(radius=1.0, segments=48, ring_count=24)
    sphere = bpy.context.object
    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    scene.collection.objects.link(camera)
    camera.location = (0.0, -4.0, 0.0)
    camera.rotation_euler = (1.5707963, 0.0, 0.0)
    scene.camera = camera
    world = bpy.data.worlds.new("Black")
    background = compat.ensure_node_tree(world).nodes["Background"]
    background.inputs["Strength"].default_value = 0.0
    scene.world = world
    scene.render.resolution_percentage = 100
    scene.render.film_transparent = True
    scene.cycles.device = "CPU"
    scene.cycles.samples = CYCLES_SAMPLES
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.use_denoising = False
    scene.eevee.taa_render_samples = 1
    return scene, sphere


def material_with(group, name, extra=0):
    """Group → ``extra`` Vector Math Add nodes → Emission → Material Output; without a group,
    a constant Emission.
    """
    material = bpy.data.materials.new(name)
    tree = compat.ensure_node_tree(material)
    tree.nodes.clear()
    emission = tree.nodes.new("ShaderNodeEmission")
    output = tree.nodes.new("ShaderNodeOutputMaterial")
    tree.links.new(emission.outputs["Emission"], output.inputs["Surface"])
    if group is None:
        return material
    node = tree.nodes.new("ShaderNodeGroup")
    node.node_tree = group
    socket = node.outputs["Diffuse"]
    for _ in range(extra):
        add = tree.nodes.new("ShaderNodeVectorMath")
        add.operation = "ADD"
        tree.links.new(socket, add.inputs[0])
        socket = add.outputs[0]
    tree.links.new(socket, emission.inputs["Color"])
    return material


def timed_render(scene):
    start = time.perf_counter()
    bpy.ops.render.render()
    return time.perf_counter() - start


def use(scene, sphere, material, engine, size):
    sphere.data.materials.clear()
    sphere.data.materials.append(material)
    scene.render.engine = engine
    scene.render.resolution_x = scene.render.resolution_y = size


def cycles_time(scene, sphere, material):
    use(scene, sphere, material, "CYCLES", CYCLES_SIZE)
    timed_render(scene)  # warm-up: scene and shader sync
    return statistics.median(timed_render(scene) for _ in range(CYCLES_REPEATS))


def eevee_first_render(scene, sphere, group):
    """Median over fresh variants of the first render (shader compile included)."""
    first = []
    for extra in range(1, EEVEE_VARIANTS + 1):
        material = material_with(group, f"{group.name} eevee {extra}", extra)
        use(scene, sphere, material, compat.eevee_engine_id(), EEVEE_SIZE)
        first.append(timed_render(scene))
    return statistics.median(first)


def layout_key(spec):
    return (tuple(spec.terms), spec.scalar, spec.clamp)


def describe(spec):
    if spec == nodes.FULL_SPEC:
        return "all 9, RGB"
    missing = [pruning.COEFFICIENT_NAMES[i] for i in range(9) if i not in spec.terms]
    text = f"{len(spec.terms)} term" + ("s" if len(spec.terms) != 1 else "")
    if 0 < len(missing) <= 3:
        text += f" (−{' '.join(missing)})"
    return text + (", grey" if spec.scalar else ", RGB") + (", clamp" if spec.clamp else "")


def main():
    started = time.perf_counter()
    scene, sphere = setup_scene()
    use(scene, sphere, material_with(None, "Plain"), compat.eevee_engine_id(), EEVEE_SIZE)
    print(f"EEVEE start-up (first render of a plain emission): {timed_render(scene):.1f} s")
    eevee = {}
    ratios = []
    header = (
        f"{'lighting':<24} {'fitted group':<30} {'nodes':>9} {'Cycles ms':>13} "
        f"{'EEVEE 1st render s':>19}"
    )
    print(f"{'':<24} {'':<30} {'full fit':>9} {'full  fit':>13} {'full':>9} {'fit':>9}")
    print(header)
    for index, (name, coeffs) in enumerate(cases()):
        scene_data.set_coefficients(scene, coeffs)
        fit = fitting.fitted_spec([scene])
        fitted = nodes.GroupSpec(fit.terms, fit.scalar, fit.clamp)
        result = {}
        for label, spec in (("full", nodes.FULL_SPEC), ("fit", fitted)):
            group = nodes.build_node_group(spec, f"{label} {index}")
            material = material_with(group, f"{label} {index}")
            seconds = cycles_time(scene, sphere, material)
            key = layout_key(spec)
            if key in eevee:
                compile_text = "="
            else:
                eevee[key] = eevee_first_render(scene, sphere, group)
                compile_text = f"{eevee[key]:.2f}"
            result[label] = (len(group.nodes), 1e3 * seconds, compile_text)
        (n_full, t_full, e_full), (n_fit, t_fit, e_fit) = result["full"], result["fit"]
        ratios.append(t_fit / t_full)
        print(
            f"{name:<24} {describe(fitted):<30} {n_full:>4} {n_fit:>4} {t_full:>6.0f} "
            f"{t_fit:>6.0f} {e_full:>9} {e_fit:>9}",
            flush=True,
        )
    print(f"Cycles time fitted / full: geometric mean {np.exp(np.mean(np.log(ratios))):.2f}")
    print(
        f"Cycles: {CYCLES_SIZE}² at {CYCLES_SAMPLES} samples, median of {CYCLES_REPEATS}; EEVEE "
        f"first render of a fresh material at {EEVEE_SIZE}², compile included (noise ~0.3 s), "
        f"once per layout ('=' already measured). "
        f"Total {time.perf_counter() - started:.0f} s."
    )


if __name__ == "__main__":
    main()
