"""Writes over keyframed or driven coefficients and gains.

Every writer ends with what it stored being what renders: checked through the evaluated
scene (what the depsgraph hands the render: the gains through their packs) at two frames,
after frame changes.
"""

import bpy
import numpy as np
import pytest
from numpy.testing import assert_allclose

from sh_lighting import api
from sh_lighting.blender.data import gain_packs, scene_data
from sh_lighting.blender.data.scene_data import GAIN_NAMES, PROPERTY_NAMES

pytestmark = pytest.mark.blender

BASE = np.arange(1, 28, dtype=np.float64).reshape(9, 3) / 8.0


def rendered(scene, frame):
    """L = s · c of the evaluated scene at ``frame`` (after leaving it and coming back)."""
    scene.frame_set(frame + 1)
    scene.frame_set(frame)
    evaluated = scene.evaluated_get(bpy.context.evaluated_depsgraph_get())
    c = np.array([list(evaluated[name]) for name in PROPERTY_NAMES])
    s = np.concatenate([list(evaluated[name]) for name in gain_packs.PACK_NAMES])
    # the packs are what the node groups read: the gains, exactly (float32)
    gains = np.array([float(evaluated[name]) for name in GAIN_NAMES], dtype=np.float32)
    assert np.array_equal(s.astype(np.float32), gains), (s, gains)
    return c * s[:, None]


def key(scene, name, frame, value):
    scene[name] = value
    assert scene.keyframe_insert(f'["{name}"]', frame=frame)


def keyed_gain_scene():
    """BASE stored, then sh_L00_gain keyed 0.5 at frame 1 and 2.0 at frame 10; at frame 1."""
    scene = bpy.context.scene
    api.set_coefficients(scene, BASE)
    key(scene, "sh_L00_gain", 1, 0.5)
    key(scene, "sh_L00_gain", 10, 2.0)
    scene.frame_set(1)
    return scene


def test_store_over_a_keyed_gain_keys_it_at_the_current_frame(addon):
    scene = keyed_gain_scene()
    new = BASE.copy()
    new[0] = 4.0
    stored = api.set_coefficients(scene, new)
    assert stored.note == "keyed at frame 1 because sh_L00_gain is animated"
    assert_allclose(rendered(scene, 1), new)  # the old code rendered L00 = 2 here
    later = new.copy()
    later[0] *= 2.0  # the gain's key at frame 10 is kept, the channel is not animated
    assert_allclose(rendered(scene, 10), later)


def test_store_refuses_or_clears_when_asked(addon):
    scene = keyed_gain_scene()
    new = np.full((9, 3), 4.0)
    with pytest.raises(scene_data.AnimatedError,
                       match=r"^sh_L00_gain is animated \(keyframed\).*nothing stored"):
        scene_data.store(scene, new, {"source": "SCRIPT"}, animation="REFUSE")
    assert_allclose(rendered(scene, 1)[0], 0.5 * BASE[0])
    stored = scene_data.store(scene, new, {"source": "SCRIPT"}, animation="CLEAR")
    assert stored.note == "animation of sh_L00_gain removed"
    assert scene_data.animated(scene) == {}
    for frame in (1, 10):
        assert_allclose(rendered(scene, frame), new)


def test_a_driven_gain_is_refused_by_name_unless_cleared(addon):
    scene = bpy.context.scene
    api.set_coefficients(scene, BASE)
    scene["k"] = 0.25
    driver = scene.driver_add('["sh_L10_gain"]').driver
    driver.type = "SCRIPTED"
    variable = driver.variables.new()
    variable.targets[0].id_type = "SCENE"
    variable.targets[0].id = scene
    variable.targets[0].data_path = '["k"]'
    driver.expression = variable.name
    new = np.full((9, 3), 3.0)
    with pytest.raises(scene_data.AnimatedError, match=r"^sh_L10_gain is driven by a driver"):
        api.set_coefficients(scene, new)
    assert_allclose(rendered(scene, 1)[2], 0.25 * BASE[2])
    api.set_coefficients(scene, new, animation="CLEAR")
    for frame in (1, 7):
        assert_allclose(rendered(scene, frame), new)


@pytest.mark.parametrize("edit", ["exposure", "window", "rotate"])
def test_design_edits_change_the_channels_and_keep_an_animated_gain(addon, edit):
    """The L10 gain keyed 2.5 at frame 1; the old edits folded it into the
    channel (L10 × 2.5), set it to 1, and the next frame multiplied again (6.25×)."""
    scene = bpy.context.scene
    api.set_coefficients(scene, BASE)
    key(scene, "sh_L10_gain", 1, 2.5)
    scene.frame_set(1)
    gains = np.ones(9)
    gains[2] = 2.5
    if edit == "exposure":
        api.exposure(scene, 1.0)
        expected = 2.0 * BASE * gains[:, None]
    elif edit == "window":
        result = api.apply_window(scene, "HANNING")
        window = np.repeat(result.window, [1, 3, 5])
        expected = BASE * (window * gains)[:, None]
    else:
        from sh_lighting.core.edits import rotate

        api.rotate(scene, yaw=0.7)
        expected = rotate(BASE, 0.7, 0.0, 0.0) * gains[:, None]
    assert float(scene["sh_L10_gain"]) == 2.5
    for frame in (1, 2):
        assert_allclose(rendered(scene, frame), expected, atol=1e-6)


def test_loading_a_preset_over_a_keyed_channel_and_gain(addon, tmp_path):
    """The farm's case: the shot's sh_L00 and its gain keyframed at frames 1 and 10; the
    preset loaded at frame 10 renders there, the animation elsewhere is kept."""
    from sh_lighting.formats.presets import preset_to_json

    preset = np.full((9, 3), 0.75)
    preset[0] = (5.0, 6.0, 7.0)
    path = tmp_path / "p.json"
    path.write_text(preset_to_json(preset, {"name": "P"}))
    scene = bpy.context.scene
    api.set_coefficients(scene, BASE)
    key(scene, "sh_L00", 1, (1.0, 1.0, 1.0))
    key(scene, "sh_L00", 10, (3.0, 3.0, 3.0))
    key(scene, "sh_L00_gain", 1, 0.5)
    key(scene, "sh_L00_gain", 10, 0.5)
    scene.frame_set(10)
    from blender_scenes import Recorder

    from sh_lighting.blender.ui.presets import load_preset_file

    recorder = Recorder()
    assert load_preset_file(recorder, scene, str(path)) == {"FINISHED"}
    loaded = "Loaded SH lighting preset 'p'; keyed at frame 10 because sh_L00, sh_L00_gain are"
    assert recorder.reports == [({"INFO"}, loaded + " animated")]
    assert_allclose(rendered(scene, 10), preset, rtol=1e-6)  # the old code: 1.5 × preset
    first = preset.copy()
    first[0] = 0.5  # frame 1's keys are kept
    assert_allclose(rendered(scene, 1), first, rtol=1e-6)


def test_cli_apply_over_a_keyed_gain_refuses_by_default_keys_or_clears(tmp_path):
    """The farm bundle's `apply PRESET shot.blend`: the shot's sh_L00_gain keyed 0.5 at frame
    1 and 2.0 at frame 10, saved at frame 1."""
    from cli_runs import EXACT, make_inputs, run

    inputs = make_inputs(tmp_path / "inputs")
    bpy.ops.wm.open_mainfile(filepath=str(inputs["blend"]))
    scene = bpy.context.scene
    scene_data.store(scene, BASE, {"source": "SCRIPT"})
    key(scene, "sh_L00_gain", 1, 0.5)
    key(scene, "sh_L00_gain", 10, 2.0)
    scene.frame_set(1)
    shot = tmp_path / "shot.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(shot))

    out = tmp_path / "lit.blend"
    result = run("apply", inputs["preset"], shot, "--out", out)
    assert result.returncode == 1
    assert result.stderr.strip().splitlines()[-1].endswith(
        "sh_L00_gain is animated (keyframed), so a value written now would be undone at "
        "the next frame: nothing stored; key the new values at this frame (--animation key) "
        "or remove the animation (--animation clear)")
    assert not out.exists()

    for policy, at_ten in (("key", 2.0), ("clear", 1.0)):
        target = tmp_path / f"{policy}.blend"
        result = run("apply", inputs["preset"], shot, "--out", target, "--animation", policy)
        assert result.returncode == 0, result.stderr
        bpy.ops.wm.open_mainfile(filepath=str(target))
        scene = bpy.context.scene
        assert_allclose(rendered(scene, 1), EXACT, rtol=1e-6)
        scale = np.ones(9)
        scale[0] = at_ten
        assert_allclose(rendered(scene, 10), EXACT * scale[:, None], rtol=1e-6)


def test_the_design_operators_report_the_key_they_wrote(addon):
    from blender_scenes import run_execute

    from sh_lighting.blender.ui import design as design_ui

    scene = bpy.context.scene
    api.set_coefficients(scene, BASE)
    key(scene, "sh_L10", 1, (1.0, 2.0, 3.0))
    scene.frame_set(1)
    result, reports = run_execute(design_ui.SHLIGHT_OT_exposure, stops=1.0)
    assert result == {"FINISHED"}
    assert reports == [({"INFO"}, "SH lighting keyed at frame 1 because sh_L10 is animated")]
    assert_allclose(rendered(scene, 1)[2], (2.0, 4.0, 6.0))


def test_reset_over_a_keyed_gain_keys_it_and_says_so(addon):
    scene = bpy.context.scene
    scene_data.store(scene, BASE, {"source": "WORLD"})  # the Reset values
    api.exposure(scene, 1.0)
    key(scene, "sh_L11_gain", 3, 0.25)
    scene.frame_set(3)
    from blender_scenes import run_execute

    from sh_lighting.blender.ui.operators import SHLIGHT_OT_reset

    assert run_execute(SHLIGHT_OT_reset) == ({"FINISHED"}, [({"INFO"}, (
        "SH lighting reset to the values computed from the world; keyed at frame 3 because "
        "sh_L11_gain is animated"))])
    for frame in (3, 8):  # one key: the Reset value renders at every frame
        assert_allclose(rendered(scene, frame), BASE)


def test_extract_lights_reports_the_key_it_wrote(addon, tmp_path):
    """Extract Lights stores the world without its lights over a keyed gain: its report says
    what the write did, as every other writer's does."""
    from blender_files import write_exr
    from blender_scenes import environment_world, run_execute, sunny_map

    from sh_lighting.blender.design import lights
    from sh_lighting.blender.ui import lights as lights_ui

    scene = bpy.context.scene
    environment_world(scene, write_exr(tmp_path / "sun.exr", sunny_map()[0]), 1.0)
    api.set_coefficients(scene, BASE)
    key(scene, "sh_L00_gain", 1, 0.5)
    scene.frame_set(1)
    result, reports = run_execute(lights_ui.SHLIGHT_OT_extract_lights, count=1,
                                  use_error_target=False, error_target=0.5,
                                  size_limit=lights.SIZE_LIMIT)
    assert result == {"FINISHED"}
    [(kinds, message)] = reports
    assert kinds == {"INFO"} and message.startswith("Extract Lights from 'sun.exr'")
    assert message.endswith("; SH lighting keyed at frame 1 because sh_L00_gain is animated")
    assert len(lights.extracted_lights(scene)) == 1
