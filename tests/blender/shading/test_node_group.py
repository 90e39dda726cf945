"""The "SH Irradiance" node group renders eq. 13 exactly, live, on a farm, and in EEVEE.

Pixel checks: ``blender_scenes.check_against_core`` (every covered pixel against the core's
``irradiance(coeffs, normal) / π`` at that pixel's normal, from a multilayer EXR render).
"""

import json
import os
import subprocess
import sys
import textwrap
import time
from math import pi

import bpy
import numpy as np
import pytest

from benchmarks.render_bench import add_camera
from blender_files import SCRIPT
from blender_scenes import (
    black_world,
    check_against_core,
    environment_world,
    read_exr,
    render,
    setup_render,
    unpack,
)
from sh_lighting.blender.data import compat, gain_packs, scene_data
from sh_lighting.blender.shading import materials, nodes
from sh_lighting.core import irradiance, project_equirect, reference_irradiance

pytestmark = pytest.mark.blender

# Non-trivial lighting in Blender axes: every term present, colours differ, E > 0 everywhere.
COEFFS = np.array(
    [
        [2.0, 1.8, 1.6],  # L00
        [0.30, -0.20, 0.10],  # L1-1
        [0.60, 0.50, 0.20],  # L10
        [-0.40, 0.25, 0.35],  # L11
        [0.20, -0.15, 0.05],  # L2-2
        [-0.10, 0.20, 0.15],  # L2-1
        [0.25, 0.10, -0.20],  # L20
        [0.15, -0.25, 0.10],  # L21
        [-0.20, 0.10, 0.30],  # L22
    ]
)
RELATIVE_TOLERANCE = 1e-4


def add_object(kind, material):
    if kind == "sphere":
        bpy.ops.mesh.primitive_uv_sphere_add(radius=1.0, segments=48, ring_count=24)
    else:
        bpy.ops.mesh.primitive_monkey_add(size=2.0)
    obj = bpy.context.object
    bpy.ops.object.shade_smooth()
    obj.data.materials.append(material)
    return obj


def sh_scene(kind="sphere", size=64, engine="CYCLES", coeffs=COEFFS):
    """Factory scene: one object whose Principled material (white) gets the SH group."""
    scene = bpy.context.scene
    material = bpy.data.materials.new("White")
    compat.ensure_node_tree(material).nodes["Principled BSDF"].inputs[
        "Base Color"
    ].default_value = (1.0, 1.0, 1.0, 1.0)
    add_object(kind, material)
    result = materials.apply_to_materials([material], scene, mode="EMISSION")
    assert result.changed == [material.name] and not result.skipped, result
    scene_data.store(scene, coeffs, SCRIPT)
    add_camera(scene, (3.0, -4.0, 2.5))
    black_world(scene)
    setup_render(scene, size, engine)
    return scene


# ---------------------------------------------------------------- the group itself


def test_group_is_native_reused_and_complete():
    group = nodes.ensure_node_group()
    assert group.bl_idname == "ShaderNodeTree" and group.name == "SH Irradiance"
    kinds = {node.bl_idname for node in group.nodes}
    assert not kinds & {"ShaderNodeScript"}, "no OSL: must run in EEVEE and on GPUs"
    attributes = [n for n in group.nodes if n.bl_idname == "ShaderNodeAttribute"]
    # Nine coefficients and the gains in three packs: 12 lookups (EEVEE's compile is steep
    # in their number: 18 took 25x as long, benchmarks/REPORT.md "compile")
    assert sorted(a.attribute_name for a in attributes) == sorted(
        scene_data.PROPERTY_NAMES + gain_packs.PACK_NAMES
    )
    assert {a.attribute_type for a in attributes} == {"VIEW_LAYER"}
    sockets = [(s.name, s.in_out, s.socket_type) for s in group.interface.items_tree]
    assert sockets == [
        ("Irradiance", "OUTPUT", "NodeSocketColor"),
        ("Diffuse", "OUTPUT", "NodeSocketColor"),
        ("Shader", "OUTPUT", "NodeSocketShader"),
        ("Normal", "INPUT", "NodeSocketVector"),
        ("Albedo", "INPUT", "NodeSocketColor"),
    ]
    count = len(group.nodes)
    group.nodes.remove(attributes[0])  # a hand edit is repaired, nothing duplicated
    again = nodes.ensure_node_group()
    assert again == group and len(bpy.data.node_groups) == 1 and len(again.nodes) == count
    group.name = "Renamed"  # found by its marker, not its name
    assert nodes.ensure_node_group() == group and len(bpy.data.node_groups) == 1


# ---------------------------------------------------------------- (a) (b) pixel checks


@pytest.mark.parametrize("kind", ["sphere", "suzanne"])
def test_render_matches_eq13_then_follows_edits(kind, tmp_path):
    scene = sh_scene(kind, size=96 if kind == "suzanne" else 64)
    rgb, alpha, normal = render(scene, tmp_path / "a.exr")
    check_against_core(rgb, alpha, normal, COEFFS, f"Cycles {kind}")
    if kind != "sphere":
        return
    # (b) edit one coefficient, render again, no rebuild: pixels follow the prediction.
    edited = COEFFS.copy()
    edited[2] = [-0.5, 0.9, 0.0]
    scene["sh_L10"] = list(edited[2])
    rgb2, alpha2, normal2 = render(scene, tmp_path / "b.exr")
    assert np.abs(rgb2 - rgb)[alpha2 > 0.999].max() > 0.1, "edit did not reach the render"
    check_against_core(rgb2, alpha2, normal2, edited, "Cycles sphere after editing L10")
    # A linked Normal (here −2 × the shading normal: normalised inside) and a coloured albedo.
    tree = bpy.data.materials["White"].node_tree
    (group_node,) = materials.added_nodes(bpy.data.materials["White"])
    geometry = tree.nodes.new("ShaderNodeNewGeometry")
    flip = tree.nodes.new("ShaderNodeVectorMath")
    flip.operation = "SCALE"
    flip.inputs["Scale"].default_value = -2.0
    tree.links.new(geometry.outputs["Normal"], flip.inputs[0])
    tree.links.new(flip.outputs["Vector"], group_node.inputs["Normal"])
    tree.links.remove(group_node.inputs["Albedo"].links[0])  # the group's own Albedo value
    group_node.inputs["Albedo"].default_value = (0.5, 0.25, 1.0, 1.0)
    rgb3, alpha3, normal3 = render(scene, tmp_path / "c.exr")
    check_against_core(
        rgb3, alpha3, -normal3, edited, "Cycles sphere, linked normal", albedo=(0.5, 0.25, 1.0)
    )


def test_keyframed_coefficient_renders_per_frame(tmp_path):
    scene = sh_scene("sphere", size=48)
    values = {1: [0.6, 0.5, 0.2], 2: [-0.7, 0.1, 0.9]}
    for frame, value in values.items():
        scene["sh_L10"] = value
        scene.keyframe_insert(data_path='["sh_L10"]', frame=frame)
    scene["sh_L10"] = [9.0, 9.0, 9.0]  # overwritten by the animation when a frame is set
    frames = {}
    for frame, value in values.items():
        scene.frame_set(frame)
        expected = COEFFS.copy()
        expected[2] = value
        frames[frame] = render(scene, tmp_path / f"frame{frame}.exr")
        check_against_core(*frames[frame], expected, f"Cycles sphere, frame {frame}")
    assert np.abs(frames[1][0] - frames[2][0]).max() > 0.1


# ---------------------------------------------------------------- (d) farm


FARM_SCRIPT = textwrap.dedent(
    """
    import importlib.util, sys
    import bpy
    assert importlib.util.find_spec("sh_lighting") is None, "the add-on must not be importable"
    bpy.ops.wm.open_mainfile(filepath=sys.argv[1])
    scene = bpy.context.scene
    scene.render.filepath = sys.argv[2]
    bpy.ops.render.render(write_still=True)
    print("addons:", sorted(bpy.context.preferences.addons.keys()))
    assert "sh_lighting" not in sys.modules
    """
)


def test_saved_blend_renders_the_same_without_the_addon(tmp_path):
    """With a keyframed gain: the gains reach the render through their packs' drivers,
    which Blender evaluates without the add-on (and without Python)."""
    scene = sh_scene("sphere", size=48)
    for frame, value in ((1, 0.5), (5, 3.0)):
        scene["sh_L10_gain"] = value
        scene.keyframe_insert(data_path='["sh_L10_gain"]', frame=frame)
    for curve in compat.action_fcurves(scene):
        for point in curve.keyframe_points:
            point.interpolation = "LINEAR"
    scene.frame_set(3)  # s = 1.75 exactly
    expected = COEFFS.copy()
    expected[2] *= 1.75
    rgb, alpha, normal = render(scene, tmp_path / "local.exr")
    check_against_core(rgb, alpha, normal, expected, "local render, keyed gain 1.75")
    blend = tmp_path / "farm.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend), copy=True)
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    env["HOME"] = str(tmp_path)
    farm = tmp_path / "farm"
    farm.mkdir()
    done = subprocess.run(
        [sys.executable, "-c", FARM_SCRIPT, str(blend), str(farm / "farm.exr")],
        cwd=farm,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    rgb_farm, alpha_farm, normal_farm = unpack(read_exr(farm / "farm.exr"))
    assert np.array_equal(alpha_farm, alpha)
    assert np.abs(rgb_farm - rgb).max() < 1e-6, "farm render differs from the local one"
    check_against_core(rgb_farm, alpha_farm, normal_farm, expected, "farm render (no add-on)")


# ---------------------------------------------------------------- (e) EEVEE, once

EEVEE_TOLERANCE = 2e-3


@pytest.mark.slow
def test_eevee_render_matches_eq13(tmp_path):
    scene = sh_scene("sphere", size=64, engine=compat.eevee_engine_id())
    scene.eevee.taa_render_samples = 1
    scene.render.filter_size = 0.0
    start = time.perf_counter()
    rgb, alpha, normal = render(scene, tmp_path / "eevee.exr")
    seconds = time.perf_counter() - start
    print(f"\nEEVEE render: {seconds:.1f} s")
    check_against_core(rgb, alpha, normal, COEFFS, "EEVEE sphere", tolerance=EEVEE_TOLERANCE)


# ---------------------------------------------------------------- (f) apply / remove


def link_set(material):
    return {
        (
            link.from_node.name,
            link.from_socket.identifier,
            link.to_node.name,
            link.to_socket.identifier,
            bool(link.is_muted),
        )
        for link in material.node_tree.links
    }


def node_set(material):
    return {(node.name, node.bl_idname) for node in material.node_tree.nodes}


def make_test_materials():
    """Materials covering the cases apply/remove must handle; returns {key: material}."""
    made = {}

    textured = bpy.data.materials.new("Textured")
    tree = compat.ensure_node_tree(textured)
    bsdf = tree.nodes["Principled BSDF"]
    texture = tree.nodes.new("ShaderNodeTexChecker")
    bump = tree.nodes.new("ShaderNodeBump")
    tree.links.new(texture.outputs["Color"], bsdf.inputs["Base Color"])
    tree.links.new(texture.outputs["Fac"], bump.inputs["Height"])
    tree.links.new(bump.outputs["Normal"], bsdf.inputs["Normal"])
    made["textured"] = textured

    diffuse = bpy.data.materials.new("Diffuse, two outputs, reroute")
    tree = compat.ensure_node_tree(diffuse)
    tree.nodes.remove(tree.nodes["Principled BSDF"])
    bsdf = tree.nodes.new("ShaderNodeBsdfDiffuse")
    bsdf.inputs["Color"].default_value = (0.2, 0.4, 0.6, 1.0)
    reroute = tree.nodes.new("NodeReroute")
    tree.links.new(bsdf.outputs["BSDF"], reroute.inputs[0])
    tree.links.new(reroute.outputs[0], tree.nodes["Material Output"].inputs["Surface"])
    tree.nodes["Material Output"].target = "CYCLES"
    eevee_output = tree.nodes.new("ShaderNodeOutputMaterial")
    eevee_output.target = "EEVEE"
    link = tree.links.new(bsdf.outputs["BSDF"], eevee_output.inputs["Surface"])
    link.is_muted = True
    made["diffuse"] = diffuse

    no_output = bpy.data.materials.new("No output")
    tree = compat.ensure_node_tree(no_output)
    tree.nodes.remove(tree.nodes["Material Output"])
    made["no_output"] = no_output

    emission = bpy.data.materials.new("Emission only")
    tree = compat.ensure_node_tree(emission)
    tree.nodes.remove(tree.nodes["Principled BSDF"])
    glow = tree.nodes.new("ShaderNodeEmission")
    tree.links.new(glow.outputs["Emission"], tree.nodes["Material Output"].inputs["Surface"])
    made["emission"] = emission
    return made


def test_apply_and_remove_restore_exactly():
    scene = bpy.context.scene
    made = make_test_materials()
    before = {key: (link_set(m), node_set(m)) for key, m in made.items()}
    mats = list(made.values())

    for _ in range(2):  # applying twice refreshes, never stacks
        changed, skipped = materials.apply_to_materials(mats + [None, mats[0]], scene, mode="EMISSION")
        assert changed == [made["textured"].name, made["diffuse"].name]
        reasons = dict(skipped)
        assert set(reasons) == {made["no_output"].name, made["emission"].name, "(empty slot)"}
        assert "no Material Output" in reasons[made["no_output"].name]
        assert "no diffuse base colour" in reasons[made["emission"].name]
        assert "ShaderNodeEmission" in reasons[made["emission"].name]
    assert len(bpy.data.node_groups) == 1

    for key in ("no_output", "emission"):
        assert (link_set(made[key]), node_set(made[key])) == before[key], f"{key} was modified"

    textured = made["textured"].node_tree
    (node,) = materials.added_nodes(made["textured"])
    assert node.node_tree == nodes.ensure_node_group()
    scale = node.inputs["Albedo"].links[0].from_node  # colour × weight, the colour linked
    assert scale.inputs[0].links[0].from_node.bl_idname == "ShaderNodeTexChecker"
    assert node.inputs["Normal"].links[0].from_node.bl_idname == "ShaderNodeBump"
    surface = textured.nodes["Material Output"].inputs["Surface"]
    assert surface.links[0].from_socket == node.outputs["Shader"]

    diffuse = made["diffuse"]
    (node,) = materials.added_nodes(diffuse)
    assert not node.inputs["Normal"].is_linked
    scale = node.inputs["Albedo"].links[0].from_node  # colour × weight
    held = scale.inputs[0].links[0].from_node  # the colour, now on a node feeding the BSDF too
    assert held.bl_idname == "ShaderNodeRGB"
    assert tuple(held.outputs[0].default_value) == pytest.approx((0.2, 0.4, 0.6, 1.0))
    assert diffuse.node_tree.nodes["Diffuse BSDF"].inputs["Color"].links[0].from_node == held
    outputs = [n for n in diffuse.node_tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial"]
    assert all(o.inputs["Surface"].links[0].from_node == node for o in outputs)
    json.loads(node[materials.NODE_MARKER])  # the record is plain JSON in the .blend

    changed, skipped = materials.remove_from_materials(mats)
    assert changed == [made["textured"].name, made["diffuse"].name]
    assert all("not applied" in reason for _, reason in skipped) and len(skipped) == 2
    for key, material in made.items():
        assert (link_set(material), node_set(material)) == before[key], f"{key} not restored"
    assert not any(materials.is_applied(m) for m in mats)


def test_remove_refuses_when_the_original_node_is_gone():
    scene = bpy.context.scene
    material = make_test_materials()["textured"]
    materials.apply_to_materials([material], scene, mode="EMISSION")
    material.node_tree.nodes.remove(material.node_tree.nodes["Principled BSDF"])
    links, names = link_set(material), node_set(material)
    changed, skipped = materials.remove_from_materials([material])
    assert changed == [] and "'Principled BSDF' no longer exists" in skipped[0][1]
    assert (link_set(material), node_set(material)) == (links, names), "half-modified"


def test_failed_apply_is_rolled_back(monkeypatch):
    made = make_test_materials()
    before = {key: (link_set(m), node_set(m)) for key, m in made.items()}
    wrong = bpy.data.node_groups.new("Not a shader group", "GeometryNodeTree")
    monkeypatch.setattr(materials, "ensure_node_group", lambda: wrong)
    changed, skipped = materials.apply_to_materials(made.values(), bpy.context.scene,
                                                    mode="EMISSION")
    assert changed == []
    reasons = dict(skipped)
    assert "left unchanged" in reasons[made["textured"].name]
    assert "not a shader node group" in reasons[made["diffuse"].name]
    for key, material in made.items():
        assert (link_set(material), node_set(material)) == before[key], f"{key} half-modified"


# ---------------------------------------------------------------- (g) vs Cycles path tracing


def load_equirect(path):
    """(pixels rows top to bottom float32 (H, W, 4), the bpy image)."""
    image = bpy.data.images.load(str(path), check_existing=True)
    width, height = image.size
    pixels = np.empty(width * height * 4, np.float32)
    image.pixels.foreach_get(pixels)
    return pixels.reshape(height, width, 4)[::-1], image


@pytest.mark.slow
def test_sh_render_vs_path_traced_hdri(tmp_path, hdri_dir):
    pixels, image = load_equirect(hdri_dir / "forest.exr")
    coeffs = project_equirect(pixels)
    scene = bpy.context.scene

    # Path-traced reference: white Diffuse BSDF under the HDRI.
    environment_world(scene, image, 1.0, name="HDRI")
    traced_material = bpy.data.materials.new("Traced")
    tree = compat.ensure_node_tree(traced_material)
    tree.nodes.remove(tree.nodes["Principled BSDF"])
    bsdf = tree.nodes.new("ShaderNodeBsdfDiffuse")
    bsdf.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    tree.links.new(bsdf.outputs["BSDF"], tree.nodes["Material Output"].inputs["Surface"])
    sphere = add_object("sphere", traced_material)
    add_camera(scene, (3.0, -4.0, 2.5))
    setup_render(scene, size=48, samples=1024)
    scene.cycles.sample_clamp_direct = 0.0
    scene.cycles.sample_clamp_indirect = 0.0
    scene.cycles.max_bounces = 1  # a convex sphere never sees itself
    start = time.perf_counter()
    traced, alpha, normal = render(scene, tmp_path / "traced.exr")
    traced_seconds = time.perf_counter() - start

    # SH render of the same sphere, same camera; emission only, so the world adds nothing.
    sh_material = bpy.data.materials.new("SH")
    compat.ensure_node_tree(sh_material).nodes["Principled BSDF"].inputs[
        "Base Color"
    ].default_value = (1.0, 1.0, 1.0, 1.0)
    assert materials.apply_to_materials([sh_material], scene, mode="EMISSION").changed == ["SH"]
    sphere.data.materials[0] = sh_material
    scene_data.store(scene, coeffs, SCRIPT)
    scene.cycles.samples = 1
    sh, alpha_sh, normal_sh = render(scene, tmp_path / "sh.exr")

    covered = (alpha > 0.999) & (alpha_sh > 0.999)
    n = normal_sh[covered]
    assert np.abs(normal[covered] - n).max() < 1e-3, "both renders must see the same normals"
    exact = reference_irradiance(pixels, n) / pi  # eq. 1: what the path tracer converges to
    nine = irradiance(coeffs, n) / pi  # eq. 13
    t, s = traced[covered], sh[covered]

    def mean_rel(a, b):
        return float(np.mean(np.abs(a - b)) / np.mean(b))

    predicted = mean_rel(nine, exact)  # the 9-term error the core predicts
    rendered = mean_rel(s, t)  # SH render vs path tracer
    noise = mean_rel(t, exact)  # path tracer vs eq. 1 (Monte Carlo + texture filtering)
    residual = float(np.mean(np.abs((s - t) - (nine - exact))) / np.mean(exact))
    report = (
        f"forest.exr, {covered.sum()} pixels, path tracing {traced_seconds:.1f} s: "
        f"9-term error predicted {predicted:.4f}, SH render vs path traced {rendered:.4f}, "
        f"path traced vs eq. 1 {noise:.4f}, residual after the predicted error {residual:.4f}"
    )
    print("\n" + report)
    assert mean_rel(s, nine) < 1e-4, report  # the SH render is eq. 13
    assert noise < 0.01, report  # the path tracer converged to eq. 1
    assert abs(rendered - predicted) <= noise + 0.002, report
    assert residual <= 1.5 * noise + 0.002, report


def test_gains_added_for_an_old_file_go_through_scene_data():
    """Review: ensure_node_group wrote missing gains directly, without their UI data
    or a tag; now through scene_data.add_missing_gains."""
    scene = bpy.context.scene
    scene_data.store(scene, COEFFS, SCRIPT)
    for name in scene_data.GAIN_NAMES:
        del scene[name]  # a file from before the gains
    nodes.ensure_node_group()
    assert all(scene[name] == 1.0 for name in scene_data.GAIN_NAMES)
    ui = scene.id_properties_ui(scene_data.GAIN_NAMES[0]).as_dict()
    assert ui.get("description") == scene_data.gain_description(0)
