"""What a careless script hands the API: one clear error each, and the scene unchanged."""

import os
import re
from pathlib import Path

import bpy
import numpy as np
import pytest
from blender_files import write_constant_exr
from blender_scenes import environment_world
from numpy.testing import assert_array_equal

from sh_lighting import api

pytestmark = pytest.mark.blender

KNOWN = np.arange(27, dtype=np.float64).reshape(9, 3) / 8.0


@pytest.mark.parametrize(
    "coeffs, message",
    [
        ([["1", "2", "3"]] * 9, r"L00 channel R is a string \('1'\), not a number"),
        ([[True, False, True]] * 9, r"L00 channel R is a boolean"),
        ([[1 + 0j, 0, 0]] + [[0, 0, 0]] * 8, r"L00 channel R is a complex number"),
        ({"L00": [1, 2, 3]}, r"coefficients are a dict, not a list of rows"),
        ([[0, 0, 0]] * 8 + [[1, 2]], r"coefficient L22 has 2 values, not 3"),
        (np.full((9, 3), 1e39), r"L00 channel R is 1e\+39, beyond the float32 range"),
        ("L00", r"coefficients are a string"),
    ],
)
def test_set_coefficients_refuses_what_is_not_9_rgb_numbers(addon, coeffs, message):
    scene = bpy.context.scene
    api.set_coefficients(scene, KNOWN)
    with pytest.raises(ValueError, match=message):
        api.set_coefficients(scene, coeffs)
    assert_array_equal(api.get_coefficients(scene), KNOWN)


def test_a_world_beyond_float32_is_refused_not_rendered_black(addon, tmp_path):
    """1e38 texels: L00 = 2√π·1e38 = 3.5e38 would become infinite in Blender's float32."""
    scene = bpy.context.scene
    api.set_coefficients(scene, KNOWN)
    environment_world(scene, write_constant_exr(tmp_path / "huge.exr", (1e38,) * 3), name="Huge")
    with pytest.raises(ValueError, match=r"L00 channel R is 3.54491e\+38, beyond the float32"):
        api.compute_from_world(scene)
    assert_array_equal(api.get_coefficients(scene), KNOWN)


@pytest.mark.parametrize("width", ["abc", 256.5, True])
def test_compute_from_world_refuses_a_capture_width_that_is_not_whole(addon, width):
    scene = bpy.context.scene
    with pytest.raises(ValueError, match=rf"capture_width is {width!r}: give a whole number"):
        api.compute_from_world(scene, capture_width=width)


@pytest.mark.parametrize("function", [api.apply_to_materials, api.remove_from_materials])
def test_materials_must_be_an_iterable_of_materials(addon, function):
    with pytest.raises(TypeError, match=r"materials is NoneType: pass an iterable of Material"):
        function(None)
    material = bpy.data.materials.new("One")
    with pytest.raises(TypeError, match=r"materials is one Material \('One'\): pass a list"):
        function(material)


@pytest.fixture
def user_dir(tmp_path, monkeypatch):
    """Blender's user folder in ``tmp_path`` (checked), so the real one is never touched."""
    from sh_lighting.blender.presets import preset_io

    resources = tmp_path / "user_resources"
    monkeypatch.setenv("BLENDER_USER_RESOURCES", str(resources))
    monkeypatch.delenv("BLENDER_USER_SCRIPTS", raising=False)
    folder = preset_io.user_preset_dir()
    assert folder == resources / "scripts" / "presets" / "sh_lighting"
    return folder


@pytest.mark.parametrize(
    "name, stem",
    [
        ("Студия", "Студия"),
        ("スタジオ", "スタジオ"),
        ("Ümlaut Warm", "Ümlaut_Warm"),
        ("U\u0308mlaut", "Ümlaut"),  # decomposed (as macOS types it): one file name, NFC
        ("../../etc/passwd", "etc_passwd"),  # still no path separators
        ("a\\b:c", "a_b_c"),
        ("スタジオ" * 40, "スタジオ" * 16),  # 64 characters, 192 bytes of UTF-8
    ],
)
def test_user_preset_names_keep_their_letters(addon, user_dir, name, stem):
    from sh_lighting.blender.presets import preset_io

    scene = bpy.context.scene
    api.set_coefficients(scene, KNOWN)
    path = api.save_user_preset(scene, name)
    assert path == user_dir / f"{stem}.json"
    assert list(preset_io.user_presets()) == [stem]
    assert [p.name for p in user_dir.iterdir()] == [f"{stem}.json"]
    assert_array_equal(api.import_preset(scene, path), KNOWN)
    assert api.remove_user_preset(name) == path and not path.exists()


def test_a_name_of_only_punctuation_is_refused(addon, user_dir):
    with pytest.raises(ValueError, match="has no letters or digits"):
        api.save_user_preset(bpy.context.scene, " /.:\\ ")


def test_capture_folders_a_killed_run_left_are_removed(tmp_path):
    import subprocess
    import sys

    from sh_lighting.blender.world import capture

    finished = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                              capture_output=True, text=True, check=True)
    dead = int(finished.stdout)
    now = 1_000_000_000.0
    names = {
        f"sh_lighting_capture_{dead}_abc": True,  # its process is gone: a leftover
        f"sh_lighting_capture_{os.getpid()}_abc": False,  # ours, in use
        "sh_lighting_capture_1_abc": False,  # process 1 runs
        "sh_lighting_capture_old": True,  # an earlier version's, two hours old
        "sh_lighting_capture_new": False,  # an earlier version's, maybe in use
        "other_folder": False,
    }
    for name, _ in names.items():
        (tmp_path / name).mkdir()
        (tmp_path / name / "world.exr").write_bytes(b"x")
    os.utime(tmp_path / "sh_lighting_capture_old", (now - 7200, now - 7200))
    os.utime(tmp_path / "sh_lighting_capture_new", (now - 60, now - 60))
    (tmp_path / f"sh_lighting_capture_{dead}_file").write_text("a file is not ours")
    removed = capture.remove_stale_captures(tmp_path, now=now)
    assert sorted(Path(p).name for p in removed) == sorted(n for n, gone in names.items() if gone)
    left = sorted(p.name for p in tmp_path.iterdir())
    assert left == sorted([n for n, gone in names.items() if not gone]
                          + [f"sh_lighting_capture_{dead}_file"])


def test_the_next_capture_removes_a_killed_captures_folder(addon):
    import subprocess
    import sys
    import tempfile

    finished = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                              capture_output=True, text=True, check=True)
    stale = Path(tempfile.gettempdir()) / f"sh_lighting_capture_{int(finished.stdout)}_killed"
    stale.mkdir()
    (stale / "world.exr").write_bytes(b"half")
    scene = bpy.context.scene
    world = bpy.data.worlds.new("Procedural")
    if world.node_tree is None:
        world.use_nodes = True
    background = next(n for n in world.node_tree.nodes if n.bl_idname == "ShaderNodeBackground")
    background.inputs["Color"].default_value = (0.25, 0.5, 1.0, 1.0)
    scene.world = world
    coeffs = api.compute_from_world(scene, capture_width=16)
    assert coeffs[0] == pytest.approx(2.0 * np.sqrt(np.pi) * np.array([0.25, 0.5, 1.0]),
                                      rel=1e-5)
    # Other processes (other test runs) may be capturing meanwhile: only ours are checked.
    ours = list(Path(tempfile.gettempdir()).glob(f"sh_lighting_capture_{os.getpid()}_*"))
    assert not stale.exists() and ours == []


def test_a_driven_strength_is_read_as_the_next_render_shows_it(addon, tmp_path):
    """Strength driven by scene["k"]; a render, then scene["k"] set from
    Python and view_layer.update(): Compute read the old Strength (1 instead of 3)."""
    scene = bpy.context.scene
    world = environment_world(scene, write_constant_exr(tmp_path / "c.exr", (0.5,) * 3),
                              name="Driven")
    background = world.node_tree.nodes["Background"]
    scene["k"] = 1.0
    driver = background.inputs["Strength"].driver_add("default_value").driver
    driver.type = "SCRIPTED"
    variable = driver.variables.new()
    variable.targets[0].id_type = "SCENE"
    variable.targets[0].id = scene
    variable.targets[0].data_path = '["k"]'
    driver.expression = variable.name
    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    scene.collection.objects.link(camera)
    scene.camera = camera
    scene.render.engine = "CYCLES"
    scene.cycles.samples = 1
    scene.render.resolution_x = scene.render.resolution_y = 8
    bpy.context.view_layer.update()
    bpy.ops.render.render()
    scene["k"] = 3.0
    bpy.context.view_layer.update()
    coeffs = api.compute_from_world(scene)
    exact = 2.0 * np.sqrt(np.pi) * 0.5 * 3.0  # L00 of a constant sky c at Strength 3
    np.testing.assert_allclose(coeffs[0], exact, rtol=1e-6)
    assert api.get_provenance(scene)["strength"] == 3.0


BAD_PROPERTIES = [
    ("sh_L10", "abc", r"scene\['sh_L10'\] is a string \('abc'\), not 3 numbers \(R, G, B\)"),
    ("sh_L10", 0.5, r"scene\['sh_L10'\] is float \(0.5\), not 3 numbers"),
    ("sh_L10", [1, 2], r"scene\['sh_L10'\] is a list \(\[1, 2\]\), not 3 numbers"),
    ("sh_L10", {"r": 1}, r"scene\['sh_L10'\] is a dict \(\{'r': 1\}\), not 3 numbers"),
    ("sh_L10_gain", "abc", r"scene\['sh_L10_gain'\] is a string \('abc'\), not a number"),
    ("sh_L10_gain", [1, 2], r"scene\['sh_L10_gain'\] is a list \(\[1, 2\]\), not a number"),
]


@pytest.mark.parametrize("name, value, message", BAD_PROPERTIES)
def test_a_bad_custom_property_is_named_by_panel_api_and_export_and_repaired(
        addon, tmp_path, name, value, message):
    """The panel's draw raised on every redraw, API and export gave raw
    numpy errors."""
    from sh_lighting.blender.data import scene_data
    from sh_lighting.blender.ui import design as design_ui
    from sh_lighting.blender.ui import panels
    from ui_layout import RecordingLayout

    scene = bpy.context.scene
    api.set_coefficients(scene, KNOWN, {"source": "WORLD"})  # also the Reset values
    api.set_coefficients(scene, 2 * KNOWN)
    scene[name] = value
    hint = "Repair in the SH Lighting panel"
    for draw in (panels.draw_main, panels.draw_coefficients, design_ui.draw_design):
        layout = RecordingLayout()
        draw(layout, bpy.context)
        if draw is not design_ui.draw_design:
            assert re.search(message, layout.text()) and hint in layout.text()
            assert "shlight.repair" in layout.operators()
    with pytest.raises(scene_data.PropertyError, match=message + ".*" + hint):
        api.get_coefficients(scene)
    with pytest.raises(ValueError, match=message):
        api.export_preset(scene, tmp_path / "p.json")
    assert not (tmp_path / "p.json").exists()
    assert bpy.ops.shlight.repair() == {"FINISHED"}
    expected = 2 * KNOWN
    expected[2] = KNOWN[2] if name == "sh_L10" else 2 * KNOWN[2]  # the Reset row, or gain 1
    assert_array_equal(api.get_coefficients(scene), expected)
    assert scene_data.problems(scene) == []


def _bad_gain_blend(tmp_path, how):
    from cli_runs import make_inputs

    inputs = make_inputs(tmp_path / "inputs")
    bpy.ops.wm.open_mainfile(filepath=str(inputs["blend"]))
    scene = bpy.context.scene
    api.set_coefficients(scene, KNOWN)
    if how == "keyed NaN":
        scene["sh_L00_gain"] = float("nan")
        scene.keyframe_insert('["sh_L00_gain"]', frame=2)
    elif how == "driven 1e39":
        scene.driver_add('["sh_L00_gain"]').driver.expression = "1e39"
    else:
        scene["sh_L00_gain"] = "abc"
    blend = tmp_path / "bad.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend))
    return blend


@pytest.mark.parametrize("how, message", [
    ("keyed NaN", r"scene\['sh_L00_gain'\] \(keyframed\) at frame 1 is nan"),
    # Blender 5.0 clamps the driver's 1e39 to the largest float32; 4.2 makes it NaN
    ("driven 1e39", r"scene\['sh_L00_gain'\] \(driven\) at frame 1 is (3.40282e\+38, beyond "
                    r"the float32 range|nan: NaN and infinite values are not allowed)"),
    ("text", r"scene\['sh_L00_gain'\] is a string \('abc'\), not a number"),
])
def test_render_names_a_bad_gain_instead_of_rendering_black(tmp_path, how, message):
    """These rendered black with exit status 0."""
    from cli_runs import run

    blend = _bad_gain_blend(tmp_path, how)
    renders = tmp_path / "renders"
    result = run("render", blend, "--output", renders / "f_####", "--frame", "1",
                 "--engine", "CYCLES", "--samples", "1")
    assert result.returncode == 1
    line = result.stderr.strip().splitlines()[-1]
    assert re.search(r"frame 1 not rendered: " + message, line), line
    assert not renders.exists() or list(renders.iterdir()) == []


@pytest.mark.parametrize("call, message", [
    (lambda s: api.rotate(s, yaw="x"), r"^yaw is a string \('x'\), not a number: give an angle"),
    (lambda s: api.rotate(s, pitch=float("inf")), r"^pitch is inf, not a finite number"),
    (lambda s: api.rotate(s, roll=float("nan")), r"^roll is nan, not a finite number"),
    (lambda s: api.exposure(s, None), r"^stops is None \(null\), not a number: give "),
    (lambda s: api.exposure(s, float("-inf")), r"^stops is -inf, not a finite number"),
    (lambda s: api.exposure(s, 1e6), r"^stops is 1e\+06: 2\^1e\+06 takes the lighting beyond"),
    (lambda s: api.apply_window(s, "HANNING", "x"), r"^width is a string \('x'\), not a numb"),
    (lambda s: api.apply_window(s, "LANCZOS", float("nan")), r"^width is nan, not a finite"),
    (lambda s: api.apply_window(s, "x"), r"^unknown window 'x': use one of HANNING"),
    (lambda s: api.saturation(s, [1]), r"^amount is a list \(\[1\]\), not a number"),
    (lambda s: api.band_gains(s, quadratic=float("inf")), r"^quadratic is inf, not a finite"),
])
def test_design_api_arguments_are_one_clear_line_and_change_nothing(addon, call, message):
    """Raw TypeErrors for strings and None, RuntimeWarnings for inf."""
    import warnings

    scene = bpy.context.scene
    api.set_coefficients(scene, KNOWN)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a RuntimeWarning fails the test
        with pytest.raises(api.DesignError, match=message):
            call(scene)
    assert_array_equal(api.get_coefficients(scene), KNOWN)
