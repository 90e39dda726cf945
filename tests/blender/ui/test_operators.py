"""Operators and the scripting API in background mode (no window, no UI context).

Worlds are built from tiny float EXRs written to ``tmp_path``: a constant radiance c at
strength s has the exact coefficients L00 = 2√π c s and L_lm = 0 otherwise (docs/reference.md §2).
"""

import math
import os
import re

import bpy
import numpy as np
import pytest
from blender_files import SCRIPT, WORLD, write_constant_exr, write_exr
from blender_scenes import environment_world, run_execute
from numpy.testing import assert_allclose

from sh_lighting import api
from sh_lighting.blender.data import compat, settings, scene_data
from sh_lighting.blender.shading import materials, notes
from sh_lighting.blender.ui import operators
from sh_lighting.blender.world import compute
from sh_lighting.blender.world import reader as world
from sh_lighting.blender.world.reader import WorldError

COLOUR = (0.2, 0.5, 1.5)
STRENGTH = 2.0
# The EXR holds float32 texels: the projection is exact up to float32 rounding.
FLOAT32_TOL = 1e-6
KNOWN = np.arange(27, dtype=np.float64).reshape(9, 3) / 10.0 - 1.0  # signed, some > 1




def image_world(scene, path, strength=STRENGTH):
    """Environment Texture (image at ``path``, or none) -> Background -> World Output."""
    return environment_world(scene, path, strength)


def expected_constant(rgb=COLOUR, strength=STRENGTH):
    expected = np.zeros((9, 3))
    expected[0] = 2.0 * math.sqrt(math.pi) * np.asarray(rgb) * strength
    return expected


# --- Compute from World ---------------------------------------------------------------------


def test_compute_operator_on_constant_exr_world_and_undo(addon, tmp_path):
    image_world(bpy.context.scene, write_constant_exr(tmp_path / "constant.exr", COLOUR))
    bpy.ops.ed.undo_push(message="before compute")
    # 'EXEC_DEFAULT', True: push an undo step as a button click does.
    assert bpy.ops.shlight.compute_from_world("EXEC_DEFAULT", True) == {"FINISHED"}
    scene = bpy.context.scene
    expected = expected_constant()
    assert_allclose(scene_data.get_coefficients(scene), expected, atol=FLOAT32_TOL)
    assert_allclose(scene_data.get_computed(scene), expected, atol=FLOAT32_TOL)

    bpy.ops.ed.undo()
    scene = bpy.context.scene  # undo reloads the data: fetch it again
    assert not scene_data.has_coefficients(scene)
    assert scene_data.COMPUTED_PROPERTY not in scene
    bpy.ops.ed.redo()
    assert_allclose(scene_data.get_coefficients(bpy.context.scene), expected, atol=FLOAT32_TOL)


def one_bright_texel_exr(path, height=32, width=64, row=9, column=40):
    """Black but for one white texel: nearly a directional source, whose 9-term error is
    known (docs/reference.md §2: mean |E9 − E| = 0.0307 P over the sphere, max 3/32 P)."""
    pixels = np.zeros((height, width, 3), dtype=np.float32)
    pixels[row, column] = 1000.0
    return write_exr(path, pixels)


@pytest.mark.parametrize("rotation", [None, (0.3, -0.2, 1.1)])
def test_compute_operator_reports_the_image_the_error_and_the_time(addon, tmp_path, rotation):
    """The report names the image and its world, gives the 9-term error
    against the world (a near-delta: about 3.07 % mean and at most 9.4 % max of the light,
    through a Mapping rotation and Strength 2 too) and the time."""
    path = one_bright_texel_exr(tmp_path / "one texel.exr")
    world_block = environment_world(bpy.context.scene, path, strength=2.0, rotation=rotation)
    result, reports = run_execute(operators.SHLIGHT_OT_compute_from_world)
    assert result == {"FINISHED"}
    [(kind, message)] = reports
    assert kind == {"INFO"}
    match = re.fullmatch(
        r"Computed from image '(.+)' of world '(.+)': 9-term error ([0-9.]+) % mean, "
        r"([0-9.]+) % max of the light \((\d+) normals\), in ([0-9.]+) s", message)
    assert match, message
    image, world_name, mean, largest, normals, seconds = match.groups()
    assert image == "one texel.exr" and world_name == world_block.name
    assert int(normals) == compute.REPORT_ERROR_NORMALS
    assert 2.5 <= float(mean) <= 3.6, message  # 3.07 % over the whole sphere
    assert 6.0 <= float(largest) <= 9.4, message  # 3/32 at the horizon, sampled
    assert 0.0 < float(seconds) < 60.0


def test_compute_report_of_a_capture_and_of_a_mirror_ball(addon):
    capture = world.WorldInfo(source="capture", world="Sky", elapsed=0.0, capture_width=64,
                              error=(0.0123, 0.0456), error_normals=64)
    assert compute.report(capture, 2.5) == (
        "Computed from a 64×32 Cycles capture of world 'Sky': 9-term error 1.23 % mean, "
        "4.56 % max of the light (64 normals), in 2.50 s")
    ball = world.WorldInfo(source="image", world="W", elapsed=0.0, image="ball.png",
                           projection="MIRROR_BALL")
    assert compute.report(ball, 0.01) == (
        "Computed from image 'ball.png' of world 'W': 9-term error not measured for a "
        "mirror-ball image, in 0.01 s")


def test_capture_width_comes_from_the_scene_override(addon, monkeypatch):
    widths = []

    def fake_world_coefficients(scene, capture_width=256, error_normals=0, **options):
        widths.append(capture_width)
        return KNOWN, world.WorldInfo(
            source="capture", world="fake", elapsed=0.0, capture_width=capture_width
        )

    monkeypatch.setattr(world, "world_coefficients", fake_world_coefficients)
    scene = bpy.context.scene
    scene.world = bpy.data.worlds.new("Procedural")
    assert bpy.ops.shlight.compute_from_world() == {"FINISHED"}
    scene.sh_lighting.use_capture_width = True
    scene.sh_lighting.capture_width = 64
    assert bpy.ops.shlight.compute_from_world() == {"FINISHED"}
    api.compute_from_world(scene)
    api.compute_from_world(scene, capture_width=32)
    scene.sh_lighting.capture_width = 65  # accepted by the field: rounded up, not a failure
    assert bpy.ops.shlight.compute_from_world() == {"FINISHED"}
    # 256: no add-on preferences when registered by the test fixture rather than enabled.
    assert widths == [settings.DEFAULT_CAPTURE_WIDTH, 64, 64, 32, 66]
    assert_allclose(api.get_computed(scene), KNOWN)
    assert api.get_provenance(scene) == {
        "source": "WORLD", "world": "fake", "method": "CAPTURE", "capture_width": 66,
        "working_space": "Linear Rec.709",
    }


def test_odd_capture_width_renders_a_capture(addon):
    """End to end: an odd width in the field gives a capture (of the next even width)."""
    scene = bpy.context.scene
    world_id = bpy.data.worlds.new("Plain")
    world_id.color = (0.25, 0.5, 0.75)
    compat.ensure_node_tree(world_id).nodes["Background"].inputs["Color"].default_value = (
        0.25, 0.5, 0.75, 1.0
    )
    scene.world = world_id
    scene.sh_lighting.use_capture_width = True
    scene.sh_lighting.capture_width = 17
    assert bpy.ops.shlight.compute_from_world() == {"FINISHED"}
    assert api.get_provenance(scene)["capture_width"] == 18
    assert_allclose(api.get_coefficients(scene)[0], expected_constant((0.25, 0.5, 0.75), 1.0)[0],
                    rtol=2e-3)


def test_compute_is_disabled_without_a_world(addon):
    bpy.context.scene.world = None
    assert not bpy.ops.shlight.compute_from_world.poll()
    with pytest.raises(RuntimeError, match="The scene has no world: add one"):
        bpy.ops.shlight.compute_from_world()


def test_compute_api_on_constant_exr_world(addon, tmp_path):
    scene = bpy.context.scene
    image_world(scene, write_constant_exr(tmp_path / "grey.exr", (0.75, 0.75, 0.75)), strength=0.5)
    coeffs = api.compute_from_world(scene)
    expected = expected_constant((0.75, 0.75, 0.75), 0.5)
    assert coeffs.shape == (9, 3)
    assert_allclose(coeffs, expected, atol=FLOAT32_TOL)
    assert_allclose(api.get_coefficients(scene), expected, atol=FLOAT32_TOL)
    assert_allclose(api.get_computed(scene), expected, atol=FLOAT32_TOL)
    assert scene.id_properties_ui("sh_L00").as_dict()["subtype"] == "NONE"


# --- Errors: CANCELLED, same message from operator and API, nothing changed ------------------


def no_world(scene, tmp_path):
    scene.world = None


def world_without_nodes(scene, tmp_path):
    world = bpy.data.worlds.new("No Nodes")
    compat.ensure_node_tree(world).nodes.clear()
    scene.world = world


def environment_without_image(scene, tmp_path):
    image_world(scene, None)


def missing_image_file(scene, tmp_path):
    path = write_constant_exr(tmp_path / "gone.exr", COLOUR)
    image_world(scene, path)
    os.unlink(path)


def disconnected_output(scene, tmp_path):
    world = image_world(scene, write_constant_exr(tmp_path / "constant.exr", COLOUR))
    output = next(n for n in world.node_tree.nodes if n.bl_idname == "ShaderNodeOutputWorld")
    for link in list(output.inputs["Surface"].links):
        world.node_tree.links.remove(link)


def scene_state(scene):
    """Everything an error must leave alone: custom properties and the data-block names.

    Keys that back registered properties (e.g. ``sh_lighting``, which Blender 4.2 stores as an
    ID property the first time it is read) are settings storage, not user data.
    """
    registered = scene.bl_rna.properties.keys()
    props = {key: repr(scene[key].to_list() if hasattr(scene[key], "to_list") else scene[key])
             for key in scene.keys() if key not in registered}
    data = {
        kind: sorted(item.name for item in getattr(bpy.data, kind))
        for kind in ("scenes", "worlds", "images", "objects", "cameras", "node_groups")
    }
    return props, data


@pytest.mark.parametrize(
    ("make_broken_world", "says"),
    [
        (no_world, "has no world"),
        (world_without_nodes, "has no World Output node"),
        (environment_without_image, "has no image"),
        (missing_image_file, "gone.exr' does not exist"),
        (disconnected_output, "is not connected"),
    ],
    ids=lambda v: getattr(v, "__name__", ""),
)
def test_world_errors_cancel_and_change_nothing(addon, tmp_path, make_broken_world, says):
    scene = bpy.context.scene
    make_broken_world(scene, tmp_path)
    scene_data.store(scene, KNOWN, WORLD)
    before = scene_state(scene)

    result, reports = run_execute(operators.SHLIGHT_OT_compute_from_world)
    assert result == {"CANCELLED"}
    [(kind, message)] = reports
    assert kind == {"ERROR"} and says in message
    assert scene_state(scene) == before

    with pytest.raises(RuntimeError) as raised:  # how bpy.ops surfaces an ERROR report
        bpy.ops.shlight.compute_from_world()
    # without a world the button is disabled (poll) with its own reason
    assert (message if scene.world else "The scene has no world") in str(raised.value)
    assert scene_state(scene) == before

    with pytest.raises(WorldError) as raised:
        api.compute_from_world(scene)
    assert str(raised.value) == message
    assert isinstance(raised.value, ValueError)
    assert scene_state(scene) == before
    assert_allclose(api.get_coefficients(scene), KNOWN)


# --- Editing: rows, channels, reset, keyframes ----------------------------------------------


def test_gain_scales_the_row_and_is_keyframable(addon):
    scene = bpy.context.scene
    scene_data.store(scene, KNOWN, SCRIPT)
    scene["sh_L10_gain"] = 2.5  # what the panel's Gain field of L10 writes
    expected = KNOWN.copy()
    expected[2] *= 2.5
    assert_allclose(api.get_coefficients(scene), expected)
    assert list(scene["sh_L10"]) == pytest.approx(KNOWN[2])  # the channels are unchanged
    assert scene.keyframe_insert('["sh_L10_gain"]', frame=1)
    scene["sh_L10_gain"] = -1.0  # signed
    assert scene.keyframe_insert('["sh_L10_gain"]', frame=11)
    scene.frame_set(1)
    assert_allclose(api.get_coefficients(scene), expected)
    scene.frame_set(11)
    assert api.get_coefficients(scene)[2] == pytest.approx(-KNOWN[2])
    api.set_coefficients(scene, KNOWN * 2.0)  # a write stores c = values, s = 1
    assert scene["sh_L10_gain"] == 1.0 and list(scene["sh_L10"]) == pytest.approx(2 * KNOWN[2])


def test_per_channel_edit_and_reset(addon):
    scene = bpy.context.scene
    scene_data.store(scene, KNOWN, WORLD)
    scene["sh_L10"][1] = -7.5  # what the panel's G field of L10 writes
    edited = KNOWN.copy()
    edited[2, 1] = -7.5
    assert_allclose(api.get_coefficients(scene), edited)

    api.set_coefficients(scene, KNOWN * 3.0)
    assert bpy.ops.shlight.reset() == {"FINISHED"}
    assert_allclose(api.get_coefficients(scene), KNOWN)
    assert_allclose(api.reset(scene), KNOWN)


def test_reset_is_disabled_with_a_reason_before_any_compute(addon):
    scene_data.store(bpy.context.scene, KNOWN, SCRIPT)
    assert not bpy.ops.shlight.reset.poll()
    with pytest.raises(RuntimeError, match="Nothing to reset to: run Compute from World first"):
        bpy.ops.shlight.reset()
    with pytest.raises(LookupError, match="Nothing to reset to: run Compute from World first"):
        api.reset(bpy.context.scene)


def test_coefficients_can_be_keyframed(addon):
    scene = bpy.context.scene
    scene_data.store(scene, KNOWN, SCRIPT)
    assert scene.keyframe_insert('["sh_L10"]', frame=1)
    scene["sh_L10"] = [5.0, -5.0, 9.0]
    assert scene.keyframe_insert('["sh_L10"]', frame=11)
    scene.frame_set(1)
    assert list(scene["sh_L10"]) == pytest.approx(KNOWN[2])
    scene.frame_set(6)  # midway between two auto-clamped Bézier keys: the average
    assert list(scene["sh_L10"]) == pytest.approx((KNOWN[2] + [5.0, -5.0, 9.0]) / 2.0)
    scene.frame_set(11)
    assert list(scene["sh_L10"]) == pytest.approx([5.0, -5.0, 9.0])


def test_set_coefficients_rejects_bad_input_and_keeps_values(addon):
    scene = bpy.context.scene
    api.set_coefficients(scene, KNOWN)
    bad = KNOWN.copy()
    bad[4, 1] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        api.set_coefficients(scene, bad)
    with pytest.raises(ValueError, match=r"shape \(9, 3\)"):
        api.set_coefficients(scene, KNOWN[:4])
    assert_allclose(api.get_coefficients(scene), KNOWN)


# --- Apply / Remove -------------------------------------------------------------------------


def two_objects_with_materials():
    """Objects 'Lit' (selected) and 'Other', each with a Principled material of its own."""
    scene = bpy.context.scene
    result = []
    for name in ("Lit", "Other"):
        material = bpy.data.materials.new(name)
        compat.ensure_node_tree(material)
        mesh = bpy.data.meshes.new(name)
        mesh.materials.append(material)
        obj = bpy.data.objects.new(name, mesh)
        scene.collection.objects.link(obj)
        result.append((obj, material))
    result[0][0].select_set(True)
    return result


def test_apply_and_remove_selected_then_all(addon):
    scene = bpy.context.scene
    (lit, lit_mat), (other, other_mat) = two_objects_with_materials()
    scene_data.store(scene, KNOWN, SCRIPT)

    result, reports = run_execute(operators.SHLIGHT_OT_apply, mode="EMISSION")
    assert result == {"FINISHED"}
    assert reports == [({"INFO"}, "SH lighting (Emission Only) applied to 1 material(s), "
                                  "0 skipped")]
    assert materials.is_applied(lit_mat) and not materials.is_applied(other_mat)

    scene.sh_lighting.apply_target = "ALL"
    assert bpy.ops.shlight.apply() == {"FINISHED"}  # the panel's Mode: Keep BSDF
    assert materials.mode_of(lit_mat) == materials.mode_of(other_mat) == "KEEP_BSDF"

    scene.sh_lighting.apply_target = "SELECTED"
    result, reports = run_execute(operators.SHLIGHT_OT_apply, mode="EMISSION")
    assert materials.mode_of(lit_mat) == "EMISSION" and materials.mode_of(other_mat) == "KEEP_BSDF"
    result, reports = run_execute(operators.SHLIGHT_OT_remove)
    assert result == {"FINISHED"}
    assert reports == [({"INFO"}, "SH lighting removed from 1 material(s), 0 skipped")]
    assert not materials.is_applied(lit_mat) and materials.is_applied(other_mat)

    scene.sh_lighting.apply_target = "ALL"
    result, reports = run_execute(operators.SHLIGHT_OT_remove)
    assert reports == [({"INFO"}, "SH lighting removed from 1 material(s), 1 skipped")]
    assert not materials.is_applied(other_mat)


def test_keep_bsdf_on_the_selection_lights_every_material_the_world_lit(addon):
    """Keep BSDF switches the world's diffuse light off for the whole scene,
    so Apply To Selected (the default) gives every material SH, and says so; Remove likewise."""
    scene = bpy.context.scene
    (lit, lit_mat), (other, other_mat) = two_objects_with_materials()
    scene_data.store(scene, KNOWN, SCRIPT)
    assert scene.sh_lighting.apply_target == "SELECTED"
    result, reports = run_execute(operators.SHLIGHT_OT_apply, mode="KEEP_BSDF")
    assert result == {"FINISHED"} and materials.mode_of(other_mat) == "KEEP_BSDF"
    assert reports == [({"INFO"}, "SH lighting (Keep BSDF) applied to 2 material(s), 0 skipped, "
                                  "1 of them beyond the selection: Keep BSDF turns the world's "
                                  "diffuse light off for the whole scene")]
    result, reports = run_execute(operators.SHLIGHT_OT_remove)
    assert not materials.is_applied(other_mat) and not materials.is_applied(lit_mat)
    assert "1 of them beyond the selection" in reports[0][1]


def test_panel_lines_fit_the_sidebar():
    """Each line under Apply reads in full in the sidebar at its default width (a longer one is
    cut short with "..." by Blender: "SH alone: no lamps, shadows or refl...")."""
    lines = list(notes.MODE_NOTES.values()) + [
        notes.TWICE_LINE, notes.LAMPS_LINE.format(count=12)]
    assert max(map(len, lines)) <= notes.MODE_NOTE_CHARACTERS, lines


def test_panel_says_what_the_mode_does_and_what_emission_drops(addon):
    """The Mode beside Apply, a line for the engine, a line
    when Emission Only would leave the scene's lamps out (and Apply's report says it)."""
    scene = bpy.context.scene
    two_objects_with_materials()
    scene_data.store(scene, KNOWN, SCRIPT)
    scene.render.engine = "CYCLES"
    assert notes.status_lines(scene, "KEEP_BSDF") == [
        ("INFO", "SH diffuse, lamps, reflections")]
    scene.render.engine = compat.eevee_engine_id()
    assert "reflection maps" in notes.status_lines(scene, "KEEP_BSDF")[0][1]
    lamp = bpy.data.objects.new("Key", bpy.data.lights.new("Key", "SUN"))
    scene.collection.objects.link(lamp)
    assert ("ERROR", "1 lamp(s) will not light them") in notes.status_lines(scene, "EMISSION")
    scene.sh_lighting.apply_mode = "EMISSION"
    result, reports = run_execute(operators.SHLIGHT_OT_apply)
    assert reports[0][0] == {"WARNING"} and "lamp(s) (Key) do not light" in reports[0][1]


def test_apply_api_matches_operator(addon):
    scene = bpy.context.scene
    (lit, lit_mat), (other, other_mat) = two_objects_with_materials()
    api.set_coefficients(scene, KNOWN)
    changed, skipped = api.apply_to_materials([lit_mat, other_mat, lit_mat])
    assert changed == [lit_mat.name_full, other_mat.name_full] and skipped == []
    assert api.ensure_node_group().name == "SH Irradiance"
    changed, skipped = api.remove_from_materials([other_mat])
    assert changed == [other_mat.name_full]
    assert materials.is_applied(lit_mat) and not materials.is_applied(other_mat)


def test_apply_reports_objects_without_a_material(addon):
    scene = bpy.context.scene
    (lit, lit_mat), _other = two_objects_with_materials()
    bare = bpy.data.objects.new("Bare", bpy.data.meshes.new("Bare"))
    scene.collection.objects.link(bare)
    empty_slot = bpy.data.objects.new("Empty Slot", bpy.data.meshes.new("Empty Slot"))
    empty_slot.data.materials.append(None)
    scene.collection.objects.link(empty_slot)
    scene.collection.objects.link(bpy.data.objects.new("Axes", None))  # no material possible
    scene_data.store(scene, KNOWN, SCRIPT)
    lit.select_set(False)
    bare.select_set(True)
    result, reports = run_execute(operators.SHLIGHT_OT_apply, mode="KEEP_BSDF")
    assert result == {"CANCELLED"}
    assert reports == [({"WARNING"}, "SH lighting applied to no material: 1 object(s) have no "
                        "material (Bare): give them a material first")]
    scene.sh_lighting.apply_target = "ALL"
    result, reports = run_execute(operators.SHLIGHT_OT_apply, mode="KEEP_BSDF")
    assert result == {"FINISHED"}
    assert reports == [({"INFO"}, "SH lighting (Keep BSDF) applied to 2 material(s), 0 skipped; "
                                  "2 object(s) "
                        "have no material (Bare, Empty Slot): give them a material first")]


def test_cli_apply_reports_objects_without_a_material(addon, tmp_path, capsys):
    from sh_lighting import cli

    two_objects_with_materials()
    scene = bpy.context.scene
    scene.collection.objects.link(bpy.data.objects.new("Bare", bpy.data.meshes.new("Bare")))
    bpy.ops.wm.save_as_mainfile(filepath=str(tmp_path / "shot.blend"))
    preset = tmp_path / "known.json"
    from sh_lighting.formats.presets import write_preset

    write_preset(preset, KNOWN)
    assert cli.main(["apply", str(preset), "--out", str(tmp_path / "out.blend")]) == 0
    out = capsys.readouterr().out
    assert "skipped object 'Bare': it has no material" in out
    assert "applied to 2 material(s)" in out


def test_apply_polls_explain_why_disabled(addon):
    scene = bpy.context.scene
    two_objects_with_materials()
    with pytest.raises(RuntimeError, match="No SH coefficients yet"):
        bpy.ops.shlight.apply()
    scene_data.store(scene, KNOWN, SCRIPT)
    for obj in scene.objects:
        obj.select_set(False)
    with pytest.raises(RuntimeError, match="No objects selected"):
        bpy.ops.shlight.apply()
    with pytest.raises(RuntimeError, match="No objects selected"):
        bpy.ops.shlight.remove()


def test_compute_and_extract_lights_share_one_no_world_poll(addon):
    """The no-world poll was copied per operator, with different messages."""
    from sh_lighting.blender.ui import polls

    bpy.context.scene.world = None
    for operator in (bpy.ops.shlight.compute_from_world, bpy.ops.shlight.extract_lights):
        with pytest.raises(RuntimeError, match=rf"{polls.NO_WORLD}$".replace("(", r"\(")
                           .replace(")", r"\)")):
            operator()


def test_keep_bsdf_says_which_reflections_eevee_does_not_show(addon):
    """EEVEE gets the world's reflections back for Principled BSDFs only
    (shading/glossy.py); Apply's report names the shaders and layers it does not model."""
    scene = bpy.context.scene
    (lit, material), _other = two_objects_with_materials()
    scene_data.store(scene, KNOWN, SCRIPT)
    tree = material.node_tree
    principled = tree.nodes["Principled BSDF"]
    principled.inputs["Coat Weight"].default_value = 0.3
    shiny = tree.nodes.new("ShaderNodeBsdfGlossy")
    mix = tree.nodes.new("ShaderNodeMixShader")
    tree.links.new(principled.outputs[0], mix.inputs[1])
    tree.links.new(shiny.outputs[0], mix.inputs[2])
    tree.links.new(mix.outputs[0], tree.nodes["Material Output"].inputs["Surface"])
    result, reports = run_execute(operators.SHLIGHT_OT_apply)
    assert result == {"FINISHED"}
    assert (f"EEVEE does not show the world's reflections off Coat of 'Principled BSDF' in "
            f"'{material.name}', Glossy BSDF '{shiny.name}' in '{material.name}' (Cycles does)"
            in reports[0][1])
