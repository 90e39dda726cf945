"""Compute from World is done once per state of the world: the cache in ``world_cache``.

Each change that alters what ``world_coefficients`` would return must invalidate the cached
result (checked by counting calls of the real function and by the values), anything else
must not; a procedural world is captured once; errors are never cached; loading a file
empties the cache.
"""

import math
import os

import bpy
import numpy as np
import pytest
from blender.test_operators import expected_constant, image_world
from blender_files import write_constant_exr as write_exr
from numpy.testing import assert_allclose

from sh_lighting.blender import compat, operators, world, world_cache
from sh_lighting.blender.world import WorldError

pytestmark = pytest.mark.blender



@pytest.fixture
def calls(monkeypatch):
    """Counts of the real ``world_coefficients`` and ``capture_world`` behind the cache."""
    counts = {"compute": 0, "capture": 0}
    compute, capture = world.world_coefficients, world.capture_world

    def counted_compute(*args, **kwargs):
        counts["compute"] += 1
        return compute(*args, **kwargs)

    def counted_capture(*args, **kwargs):
        counts["capture"] += 1
        return capture(*args, **kwargs)

    monkeypatch.setattr(world, "world_coefficients", counted_compute)
    monkeypatch.setattr(world, "capture_world", counted_capture)
    world_cache.clear_cache()
    yield counts
    world_cache.clear_cache()


def compute(scene=None, width=32):
    return world_cache.cached_world_coefficients(scene or bpy.context.scene, capture_width=width)


def image_scene(tmp_path, rgb=(0.2, 0.5, 1.5), strength=2.0):
    scene = bpy.context.scene
    path = write_exr(tmp_path / "sky.exr", rgb)
    return scene, image_world(scene, path, strength=strength), path


def environment(world_id):
    return next(n for n in world_id.node_tree.nodes if n.bl_idname == "ShaderNodeTexEnvironment")


def background(world_id):
    return next(n for n in world_id.node_tree.nodes if n.bl_idname == "ShaderNodeBackground")


def test_unchanged_image_world_is_computed_once_and_never_captured(tmp_path, calls):
    scene, _world, _path = image_scene(tmp_path)
    first, info = compute(scene)
    assert info.source == "image" and not info.cached
    for _ in range(3):
        again, info = compute(scene)
        assert info.cached and info.source == "image"
        assert_allclose(again, first, rtol=0, atol=0)
    again[0, 0] = 99.0  # the caller gets a copy
    assert compute(scene)[0][0, 0] == first[0, 0]
    scene.frame_set(17)  # not animated: the frame does not matter
    assert compute(scene)[1].cached
    assert calls == {"compute": 1, "capture": 0}


def rotate_mapping(world_id):
    tree = world_id.node_tree
    coords = tree.nodes.new("ShaderNodeTexCoord")
    mapping = tree.nodes.new("ShaderNodeMapping")
    tree.links.new(coords.outputs["Generated"], mapping.inputs["Vector"])
    tree.links.new(mapping.outputs["Vector"], environment(world_id).inputs["Vector"])
    mapping.inputs["Rotation"].default_value = (0.0, 0.0, 0.0)
    return mapping


def test_world_changes_invalidate(tmp_path, calls):
    scene, world_id, path = image_scene(tmp_path, rgb=(0.3, 0.3, 0.3))
    expected_l00 = 2.0 * math.sqrt(math.pi) * 0.3 * 2.0
    assert compute(scene)[0][0, 0] == pytest.approx(expected_l00, rel=1e-6)

    background(world_id).inputs["Strength"].default_value = 3.0
    coeffs, info = compute(scene)
    assert not info.cached and coeffs[0, 0] == pytest.approx(expected_l00 * 1.5, rel=1e-6)

    # A non-constant image so that a rotation changes the result.
    gradient = bpy.data.images.new("gradient", 16, 8, float_buffer=True)
    pixels = np.ones((8, 16, 4), np.float32)
    pixels[..., 0] = np.linspace(0.0, 2.0, 16)[None, :]
    gradient.pixels.foreach_set(pixels.ravel())
    environment(world_id).image = gradient  # image replaced
    replaced, info = compute(scene)
    assert not info.cached and abs(replaced[1, 0]) > 1e-3
    mapping = rotate_mapping(world_id)  # node added and relinked: same lighting, recomputed
    assert not compute(scene)[1].cached
    mapping.inputs["Rotation"].default_value = (0.0, 0.0, math.pi)  # mapping rotation
    rotated, info = compute(scene)
    assert not info.cached and rotated[1, 0] == pytest.approx(-replaced[1, 0], rel=1e-5)
    assert compute(scene)[1].cached
    pixels[..., 1] = 5.0  # generated image edited in memory: its pixels are hashed
    gradient.pixels.foreach_set(pixels.ravel())
    edited, info = compute(scene)
    assert not info.cached and edited[0, 1] > rotated[0, 1]

    link = environment(world_id).inputs["Vector"].links[0]
    link.is_muted = True  # a muted link: what Cycles does with it is not read, captured
    _coeffs, info = compute(scene, width=16)
    assert not info.cached and info.source == "capture"
    assert compute(scene, width=16)[1].cached
    assert not compute(scene, width=32)[1].cached  # another capture width
    assert calls["capture"] == 2
    assert calls["compute"] == 8


def test_image_file_changed_on_disk_and_reloaded(tmp_path, calls):
    scene, world_id, path = image_scene(tmp_path, rgb=(0.3, 0.3, 0.3), strength=1.0)
    first, _ = compute(scene)
    stat = os.stat(path)
    write_exr(path, (0.6, 0.6, 0.6))  # same size; the modification time is pushed on to be
    os.utime(path, ns=(stat.st_atime_ns, stat.st_mtime_ns + 2_000_000_000))  # sure it moves
    _coeffs, info = compute(scene)
    assert not info.cached  # the file changed: recomputed (from the pixels Blender holds)
    environment(world_id).image.reload()  # Image > Reload: the new pixels
    reloaded, info = compute(scene)
    assert not info.cached and reloaded[0, 0] == pytest.approx(2.0 * first[0, 0], rel=1e-6)
    assert compute(scene)[1].cached
    image = environment(world_id).image
    image.colorspace_settings.name = "Non-Color"
    assert not compute(scene)[1].cached


def test_packed_image_is_identified_by_its_bytes(tmp_path, calls):
    scene, world_id, path = image_scene(tmp_path)
    image = environment(world_id).image
    image.pack()
    compute(scene)
    assert compute(scene)[1].cached
    other = write_exr(tmp_path / "other.exr", (0.9, 0.1, 0.1))
    image.unpack(method="REMOVE")
    image.filepath = str(other)
    image.reload()
    image.pack()
    assert not compute(scene)[1].cached


def test_procedural_world_is_captured_once(calls):
    scene = bpy.context.scene
    world_id = bpy.data.worlds.new("Sky")
    scene.world = world_id
    tree = compat.ensure_node_tree(world_id)
    gradient = tree.nodes.new("ShaderNodeTexGradient")
    tree.links.new(gradient.outputs["Color"], background(world_id).inputs["Color"])
    coeffs, info = compute(scene, width=16)
    assert info.source == "capture" and calls["capture"] == 1
    assert compute(scene, width=16)[1].cached and calls["capture"] == 1
    gradient.gradient_type = "QUADRATIC"  # a node setting, not a socket value
    assert not compute(scene, width=16)[1].cached and calls["capture"] == 2


def test_animated_world_depends_on_the_frame(calls):
    scene = bpy.context.scene
    world_id = bpy.data.worlds.new("Animated")
    compat.ensure_node_tree(world_id)
    scene.world = world_id
    strength = background(world_id).inputs["Strength"]
    for frame, value in ((1, 1.0), (11, 3.0)):
        strength.default_value = value
        strength.keyframe_insert("default_value", frame=frame)
    scene.frame_set(1)
    compute(scene, width=16)
    assert compute(scene, width=16)[1].cached
    scene.frame_set(11)
    coeffs, info = compute(scene, width=16)
    assert not info.cached
    assert coeffs[0] == pytest.approx(expected_constant((0.05, 0.05, 0.05), 3.0)[0], rel=1e-5)


def test_errors_are_not_cached(tmp_path, calls):
    scene, world_id, path = image_scene(tmp_path)
    environment(world_id).image = None
    for _ in range(2):
        with pytest.raises(WorldError, match="has no image"):
            compute(scene)
    assert calls["compute"] == 2


def test_operator_reports_reuse_and_loading_a_file_empties_the_cache(addon, tmp_path, calls):
    image_scene(tmp_path)
    assert bpy.ops.shlight.compute_from_world() == {"FINISHED"}
    reports = []

    class Recorder:
        def report(self, kind, message):
            reports.append(message)

    assert operators.SHLIGHT_OT_compute_from_world.execute(Recorder(), bpy.context) == {
        "FINISHED"
    }
    assert reports and "has not changed" in reports[0]
    assert calls["compute"] == 1 and world_cache._CACHE
    blend = tmp_path / "saved.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend))
    bpy.ops.wm.open_mainfile(filepath=str(blend))
    assert not world_cache._CACHE
