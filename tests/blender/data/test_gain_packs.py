"""The gains' packs: three driven 3-float copies of the nine gains, what the groups read.

Each test reads the evaluated scene (what the render is handed) and asks for the gains
bit for bit in float32: keyed, typed over, copied with the scene, repaired when broken, and
added to a file that has gains but no packs (a file from before the packs).
"""

import bpy
import numpy as np
import pytest

from sh_lighting.blender.data import gain_packs, scene_data
from sh_lighting.blender.data.scene_data import GAIN_NAMES
from sh_lighting.blender.shading import nodes
from sh_lighting.blender.transfer import nodes as transfer_nodes

pytestmark = pytest.mark.blender

BASE = np.arange(1, 28, dtype=np.float64).reshape(9, 3) / 8.0
SCRIPT = {"source": "SCRIPT"}


def evaluated_packs(scene):
    """The nine gains the render reads (the evaluated packs, in index order)."""
    depsgraph = scene.view_layers[0].depsgraph  # this scene's, active or not
    depsgraph.update()
    evaluated = scene.evaluated_get(depsgraph)
    return np.concatenate([list(evaluated[name]) for name in gain_packs.PACK_NAMES])


def gains_of(scene):
    return np.array([float(scene[name]) for name in GAIN_NAMES], dtype=np.float32)


def drivers_of(scene):
    return [c for c in scene.animation_data.drivers if c.data_path.startswith('["sh_gains_')]


def stored_scene():
    scene = bpy.context.scene
    scene_data.store(scene, BASE, SCRIPT)
    return scene


def test_store_makes_the_packs_and_they_copy_every_gain_exactly():
    scene = stored_scene()
    assert gain_packs.has_packs(scene) and len(drivers_of(scene)) == 9
    values = [0.3, -2.0, 0.0, 1e-7, 3.7, 1.0, -0.25, 1e30, 0.1]
    for name, value in zip(GAIN_NAMES, values):
        scene[name] = value
    scene.update_tag()
    got = evaluated_packs(scene).astype(np.float32)
    assert np.array_equal(got, gains_of(scene)), got  # no 1-ulp rounding from driver keys
    assert gain_packs.ensure(scene, GAIN_NAMES) == []  # nothing to write a second time
    assert len(drivers_of(scene)) == 9


def test_a_keyed_gain_reaches_the_pack_at_every_frame():
    scene = stored_scene()
    for frame, value in ((1, 0.5), (9, 2.5)):
        scene["sh_L21_gain"] = value
        scene.keyframe_insert('["sh_L21_gain"]', frame=frame)
    seen = []
    for frame in (1, 4, 9):
        scene.frame_set(frame)
        got = evaluated_packs(scene)
        assert np.array_equal(got.astype(np.float32), gains_of(scene)), frame
        seen.append(got[7])
    assert seen[0] == 0.5 and 0.5 < seen[1] < 2.5 and seen[2] == 2.5, seen


def test_a_value_typed_into_a_pack_does_not_last():
    scene = stored_scene()
    scene["sh_gains_1"] = [7.0, 7.0, 7.0]
    scene.update_tag()
    assert np.array_equal(evaluated_packs(scene), np.ones(9))


def test_broken_packs_are_repaired_by_the_next_store_or_group_build():
    scene = stored_scene()
    animation = scene.animation_data
    animation.drivers.remove(drivers_of(scene)[4])  # a driver deleted
    drivers_of(scene)[0].driver.variables[0].targets[0].data_path = '["sh_L22_gain"]'  # retargeted
    del scene["sh_gains_2"]  # a pack deleted
    scene["sh_L22_gain"] = 0.5
    scene_data.store(scene, BASE, SCRIPT, gains="KEEP")
    assert len(drivers_of(scene)) == 9
    assert np.array_equal(evaluated_packs(scene).astype(np.float32), gains_of(scene))
    animation.drivers.remove(drivers_of(scene)[8])
    nodes.ensure_node_group()
    assert np.array_equal(evaluated_packs(scene).astype(np.float32), gains_of(scene))


def test_a_file_from_before_the_packs_gets_them_from_every_group_builder():
    for build in (nodes.ensure_node_group, transfer_nodes.ensure_node_group):
        bpy.ops.wm.read_factory_settings(use_empty=True)
        scene = stored_scene()
        scene["sh_L10_gain"] = -1.5
        for curve in drivers_of(scene):
            scene.animation_data.drivers.remove(curve)
        for name in gain_packs.PACK_NAMES:
            del scene[name]
        build()
        assert np.array_equal(evaluated_packs(scene).astype(np.float32), gains_of(scene)), build


def test_a_copied_scene_reads_its_own_gains():
    scene = stored_scene()
    bpy.ops.scene.new(type="FULL_COPY")
    copy = bpy.context.scene
    assert copy != scene and gain_packs.has_packs(copy)
    copy["sh_L00_gain"] = 0.125
    copy.update_tag()
    assert evaluated_packs(copy)[0] == 0.125
    assert evaluated_packs(scene)[0] == 1.0  # the original's gains are its own
    assert all(c.driver.variables[0].targets[0].id == copy for c in drivers_of(copy))


@pytest.mark.parametrize("damage", ["deleted", "text", "whole numbers", "driver deleted"])
def test_a_broken_pack_is_named_and_repaired(damage):
    scene = stored_scene()
    scene["sh_L11_gain"] = 0.5
    if damage == "deleted":
        del scene["sh_gains_1"]
    elif damage == "text":
        scene["sh_gains_1"] = "gains"
    elif damage == "whole numbers":
        scene["sh_gains_1"] = [1, 1, 1]  # an int array would truncate 0.5 to 0
    else:
        scene.animation_data.drivers.remove(drivers_of(scene)[3])
    (found,) = scene_data.problems(scene)
    assert found[0] == "sh_gains_1" and "Repair writes it again" in found[1], found
    assert "sh_L11_gain" in found[1]
    assert scene_data.repair(scene) == ["sh_gains_1"]
    assert scene_data.problems(scene) == []
    assert np.array_equal(evaluated_packs(scene).astype(np.float32), gains_of(scene))


def test_a_file_from_before_the_packs_has_no_problem():
    scene = stored_scene()
    for curve in drivers_of(scene):
        scene.animation_data.drivers.remove(curve)
    for name in gain_packs.PACK_NAMES:
        del scene[name]
    assert scene_data.problems(scene) == []  # its version-4 group reads the gains directly
