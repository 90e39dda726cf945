"""Live and never stale: every writer of the coefficients reaches the evaluated scene at once
(what the viewports show), and every way a coefficient changes reaches the next render.

Writers are checked headless: after each one, ``scene.evaluated_get(depsgraph)`` (after
``depsgraph.update()``) holds the new values. Renders are Cycles renders of a sphere whose
pixels are compared with E(n)/π of the values expected at that moment (test_node_group's
exact-pixel setup), in the order people work: Compute → Apply → edit a channel → render;
Apply → keyframe → render two frames; save → render where the add-on is not installed.
"""

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import bpy
import numpy as np
import pytest
from blender_files import SCRIPT, WORLD, write_constant_exr, write_exr
from numpy.testing import assert_allclose
from blender_scenes import (
    EULER, check_against_core, environment_world, read_exr, render, setup_render, sunny_map,
    unpack,
)

from benchmarks.render_bench import add_camera
from sh_lighting import api, cli
from sh_lighting.blender.data import compat, scene_data
from sh_lighting.blender.design import edits as design
from sh_lighting.blender.presets import preset_io

pytestmark = pytest.mark.blender

ROOT = Path(__file__).resolve().parents[3]
FOREST = ROOT / "presets" / "forest.json"
# Values a writer replaces: E > 0 everywhere, every term present.
BEFORE = np.array(
    [[2.0, 1.8, 1.6], [0.3, -0.2, 0.1], [0.6, 0.5, 0.2], [-0.4, 0.25, 0.35], [0.2, -0.15, 0.05],
     [-0.1, 0.2, 0.15], [0.25, 0.1, -0.2], [0.15, -0.25, 0.1], [-0.2, 0.1, 0.3]]
)
FLOAT32 = 1e-6


def evaluated(scene):
    """(9, 3) s · c as the depsgraph's evaluated copy of ``scene`` holds them."""
    depsgraph = bpy.context.evaluated_depsgraph_get()
    depsgraph.update()
    copy = scene.evaluated_get(depsgraph)
    c = np.array([list(copy[name]) for name in scene_data.PROPERTY_NAMES])
    s = np.array([float(copy.get(name, 1.0)) for name in scene_data.GAIN_NAMES])
    return c * s[:, None]


def world_scene(tmp_path):
    """The context scene with a sunny, rotated image world (every tool can run on it), Reset
    values and current values ``BEFORE`` that the evaluated scene already holds."""
    scene = bpy.context.scene
    pixels, _disc = sunny_map()
    environment_world(scene, write_exr(tmp_path / "sun.exr", pixels), 1.5, EULER)
    scene_data.store(scene, BEFORE * 0.5, WORLD)
    scene_data.store(scene, BEFORE, SCRIPT)
    assert_allclose(evaluated(scene), BEFORE)
    return scene


def _cli_apply(scene, tmp_path):
    bpy.ops.wm.save_as_mainfile(filepath=str(tmp_path / "shot.blend"))
    scene = bpy.context.scene
    scene_data.store(scene, BEFORE, SCRIPT)
    assert_allclose(evaluated(scene), BEFORE)
    assert cli.main(["apply", str(FOREST), "--out", str(tmp_path / "out.blend")]) == 1  # no
    # material to apply to is an error, but the preset is stored in the open session first
    return bpy.context.scene


WRITERS = {
    "compute operator": lambda scene, _t: bpy.ops.shlight.compute_from_world(),
    "compute api": lambda scene, _t: api.compute_from_world(scene),
    "reset operator": lambda scene, _t: bpy.ops.shlight.reset(),
    "reset api": lambda scene, _t: api.reset(scene),
    "set_coefficients": lambda scene, _t: api.set_coefficients(scene, BEFORE * 2.0),
    "exposure": lambda scene, _t: bpy.ops.shlight.exposure(stops=1.0),
    "rotate": lambda scene, _t: bpy.ops.shlight.rotate(yaw=0.5),
    "saturation": lambda scene, _t: bpy.ops.shlight.saturation(amount=0.5),
    "band gains": lambda scene, _t: bpy.ops.shlight.band_gains(quadratic=0.5),
    "flip": lambda scene, _t: bpy.ops.shlight.flip_vertical(),
    "window": lambda scene, _t: bpy.ops.shlight.window(kind="HANNING"),
    "match mapping": lambda scene, _t: design.match_mapping(scene),
    "extract one light": lambda scene, _t: bpy.ops.shlight.extract_lights("EXEC_DEFAULT", count=1),
    "load preset": lambda scene, _t: bpy.ops.shlight.load_preset(filepath=str(FOREST)),
    "import preset": lambda scene, _t: bpy.ops.shlight.import_preset(filepath=str(FOREST)),
    "preset_io": lambda scene, _t: preset_io.import_preset(scene, FOREST),
    "cli apply": _cli_apply,
}


@pytest.mark.parametrize("writer", WRITERS, ids=str)
def test_every_writer_reaches_the_evaluated_scene(addon, tmp_path, writer):
    scene = world_scene(tmp_path)
    result = WRITERS[writer](scene, tmp_path)
    assert not isinstance(result, set) or result == {"FINISHED"}, result
    scene = bpy.context.scene
    stored = scene_data.get_coefficients(scene)
    assert np.abs(stored - BEFORE).max() > 0.01, f"{writer} changed nothing"
    assert_allclose(evaluated(scene), stored, rtol=FLOAT32, atol=FLOAT32)
    assert scene_data.provenance(scene)["source"] in scene_data.SOURCES


def test_store_records_provenance_and_refuses_bad_input(addon):
    scene = bpy.context.scene
    record = {"source": "WORLD", "world": "Sky", "rotation": [0.0, 0.5, 1.0]}
    scene_data.store(scene, BEFORE, record)
    assert scene_data.provenance(scene) == record
    assert scene_data.computed_provenance(scene) == record
    scene_data.store(scene, BEFORE * 2, scene_data.edited(scene, "exposure"))
    assert scene_data.provenance(scene) == {**record, "edit": "exposure"}
    assert_allclose(scene_data.get_computed(scene), BEFORE)  # an edit is no new Reset value
    for bad, says in (({"source": "GUESS"}, "provenance"), ("WORLD", "provenance")):
        with pytest.raises(ValueError, match=says):
            scene_data.store(scene, BEFORE, bad)
    bad = BEFORE.copy()
    bad[3, 1] = np.inf
    with pytest.raises(ValueError, match="L11 channel G is inf"):
        scene_data.store(scene, bad, SCRIPT)
    assert_allclose(scene_data.get_coefficients(scene), BEFORE * 2)


def test_python_item_assignment_needs_a_tag_to_reach_the_viewport(addon):
    """Measured on bpy 4.2 and 5.0: ``scene["sh_L10"] = ...`` alone leaves the evaluated
    scene (what open viewports draw) stale; ``scene.update_tag()`` brings it (README)."""
    scene = bpy.context.scene
    api.set_coefficients(scene, BEFORE)
    assert_allclose(evaluated(scene), BEFORE)
    scene["sh_L10"] = [0.9, -0.9, 0.0]
    expected = BEFORE.copy()
    expected[2] = [0.9, -0.9, 0.0]
    assert_allclose(evaluated(scene), BEFORE)  # stale: Blender does not tag Python writes
    scene.update_tag()
    assert_allclose(evaluated(scene), expected)


# ---------------------------------------------------------------- renders


def lit_sphere(scene, size=48):
    """A white Principled sphere (selected), a camera, exact-pixel render settings."""
    material = bpy.data.materials.new("White")
    compat.ensure_node_tree(material).nodes["Principled BSDF"].inputs[
        "Base Color"
    ].default_value = (1.0, 1.0, 1.0, 1.0)
    bpy.ops.mesh.primitive_uv_sphere_add(radius=1.0, segments=48, ring_count=24)
    bpy.ops.object.shade_smooth()
    bpy.context.object.data.materials.append(material)
    bpy.context.object.select_set(True)
    add_camera(scene, (3.0, -4.0, 2.5))
    setup_render(scene, size)
    return material


def constant_world(scene, tmp_path, rgb=(0.4, 0.35, 0.3)):
    return environment_world(scene, write_constant_exr(tmp_path / "constant.exr", rgb),
                             name="Constant")


def rendered(scene, path, expected, what):
    """Render, and check every sphere pixel against E(n)/π of ``expected``."""
    rgb, alpha, normal = render(scene, path)
    check_against_core(rgb, alpha, normal, expected, what)
    return rgb


def test_compute_apply_edit_a_channel_render(addon, tmp_path):
    scene = bpy.context.scene
    constant_world(scene, tmp_path)
    lit_sphere(scene)
    assert bpy.ops.shlight.compute_from_world() == {"FINISHED"}
    computed = api.get_coefficients(scene)
    assert bpy.ops.shlight.apply(mode="EMISSION") == {"FINISHED"}  # exactly E/π
    rendered(scene, tmp_path / "computed.exr", computed, "after Compute and Apply")
    # the panel's fields: a channel of L10 and the gain of L00 (RNA writes, as the UI does)
    scene.path_resolve('["sh_L10"]')  # the field's path exists
    scene["sh_L10"] = [0.5, 0.1, -0.2]
    scene["sh_L00_gain"] = 1.5
    scene.update_tag()
    expected = computed.copy()
    expected[2] = [0.5, 0.1, -0.2]
    expected[0] *= 1.5
    assert_allclose(evaluated(scene), expected)
    rendered(scene, tmp_path / "edited.exr", expected, "after editing L10 and L00's gain")


def test_driver_reaches_the_render(addon, tmp_path):
    scene = bpy.context.scene
    lit_sphere(scene)
    api.set_coefficients(scene, BEFORE)
    api.apply_to_materials(bpy.data.materials, scene, mode="EMISSION")
    curve = scene.driver_add('["sh_L10_gain"]')
    curve.driver.type = "SCRIPTED"
    curve.driver.expression = "frame - 2"  # a simple expression: no Python needed
    for frame in (1, 3):
        scene.frame_set(frame)
        expected = BEFORE.copy()
        expected[2] *= frame - 2
        assert_allclose(evaluated(scene), expected, rtol=FLOAT32)
        rendered(scene, tmp_path / f"driven{frame}.exr", expected, f"driven gain, frame {frame}")


def test_python_assignment_and_undo_redo_reach_the_render(addon, tmp_path):
    scene = bpy.context.scene
    lit_sphere(scene)
    api.set_coefficients(scene, BEFORE)
    api.apply_to_materials(bpy.data.materials, scene, mode="EMISSION")
    bpy.ops.ed.undo_push(message="before")
    scene["sh_L11"] = [0.5, -0.3, 0.2]  # a script's item assignment, no tag
    after = BEFORE.copy()
    after[3] = [0.5, -0.3, 0.2]
    rendered(scene, tmp_path / "assigned.exr", after, "after scene['sh_L11'] = ...")
    bpy.ops.ed.undo_push(message="assigned")
    bpy.ops.ed.undo()
    scene = bpy.context.scene
    assert_allclose(evaluated(scene), BEFORE)
    rendered(scene, tmp_path / "undone.exr", BEFORE, "after undo")
    bpy.ops.ed.redo()
    scene = bpy.context.scene
    assert_allclose(evaluated(scene), after)
    rendered(scene, tmp_path / "redone.exr", after, "after redo")


FARM_SCRIPT = textwrap.dedent(
    """
    import importlib.util, sys
    import bpy
    assert importlib.util.find_spec("sh_lighting") is None, "the add-on must not be importable"
    bpy.ops.wm.open_mainfile(filepath=sys.argv[1])
    scene = bpy.context.scene
    for frame in (1, 2):
        scene.frame_set(frame)
        scene.render.filepath = f"{sys.argv[2]}/frame{frame}.exr"
        bpy.ops.render.render(write_still=True)
    assert "sh_lighting" not in sys.modules
    """
)


@pytest.mark.slow
def test_apply_keyframe_save_render_two_frames_without_the_addon(addon, tmp_path):
    scene = bpy.context.scene
    constant_world(scene, tmp_path)
    lit_sphere(scene)
    assert bpy.ops.shlight.compute_from_world() == {"FINISHED"}
    assert bpy.ops.shlight.apply(mode="EMISSION") == {"FINISHED"}  # exactly E/π
    computed = api.get_coefficients(scene)
    frames = {1: computed.copy(), 2: computed.copy()}
    scene["sh_L10"] = [0.4, 0.3, 0.2]  # a channel, keyed at frame 1
    frames[1][2] = [0.4, 0.3, 0.2]
    scene.keyframe_insert('["sh_L10"]', frame=1)
    scene.keyframe_insert('["sh_L00_gain"]', frame=1)
    scene["sh_L10"] = [-0.3, 0.1, 0.5]  # and another value and a gain at frame 2
    scene["sh_L00_gain"] = 0.75
    frames[2][2] = [-0.3, 0.1, 0.5]
    frames[2][0] *= 0.75
    scene.keyframe_insert('["sh_L10"]', frame=2)
    scene.keyframe_insert('["sh_L00_gain"]', frame=2)
    local = {}
    for frame, expected in frames.items():
        scene.frame_set(frame)
        assert_allclose(evaluated(scene), expected, rtol=FLOAT32)
        local[frame] = rendered(scene, tmp_path / f"local{frame}.exr", expected, f"frame {frame}")
    assert np.abs(local[1] - local[2]).max() > 0.05

    blend = tmp_path / "farm.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend), copy=True)
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    env["HOME"] = str(tmp_path)
    farm = tmp_path / "farm"
    farm.mkdir()
    done = subprocess.run(
        [sys.executable, "-c", FARM_SCRIPT, str(blend), str(farm)],
        cwd=farm, env=env, capture_output=True, text=True, timeout=300,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    for frame, expected in frames.items():
        rgb, alpha, normal = unpack(read_exr(farm / f"frame{frame}.exr"))
        assert np.abs(rgb - local[frame]).max() < 1e-6, f"farm frame {frame} differs"
        check_against_core(rgb, alpha, normal, expected, f"farm render, frame {frame}")


def test_file_load_renders_the_stored_values(addon, tmp_path):
    scene = bpy.context.scene
    lit_sphere(scene)
    api.set_coefficients(scene, BEFORE)
    api.apply_to_materials(bpy.data.materials, scene, mode="EMISSION")
    scene["sh_L2m2_gain"] = -1.0
    blend = tmp_path / "saved.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend))
    api.set_coefficients(scene, BEFORE * 3.0)  # not saved
    bpy.ops.wm.open_mainfile(filepath=str(blend))
    scene = bpy.context.scene
    expected = BEFORE.copy()
    expected[4] *= -1.0
    assert_allclose(evaluated(scene), expected)
    rendered(scene, tmp_path / "loaded.exr", expected, "after loading the file")
