"""sh_lighting.blender.world.reader.read_world: what the world is, as the next render shows it.

Animated worlds are checked against Cycles captures at two frames, with the scene's frame
changed the way a script does it (``scene.frame_current = f``, no ``frame_set``), which
leaves the original datablock's values stale until the depsgraph evaluates them.
"""

import bpy
import numpy as np
import pytest
from blender_files import write_exr
from blender_scenes import environment_world

from sh_lighting.blender.data import compat
from sh_lighting.blender.world.capture import capture_world
from sh_lighting.blender.world.reader import (
    ImageSource,
    ProceduralSource,
    WorldError,
    read_world,
    world_coefficients,
)
from sh_lighting.core.equirect import texel_directions
from sh_lighting.core.projection import project_equirect

pytestmark = pytest.mark.blender


def rel_err(a, b):
    return np.abs(np.asarray(a) - np.asarray(b)).max() / np.abs(b).max()


def smooth_pixels(height=32, width=64):
    d = texel_directions(height, width)
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    spot = np.exp((d @ np.array([0.48, 0.6, 0.64]) - 1.0) / 0.08)
    pixels = np.ones((height, width, 4), dtype=np.float32)
    pixels[..., 0] = 1.0 + 0.5 * x + 3.0 * spot
    pixels[..., 1] = 1.2 - 0.4 * z + 2.0 * spot
    pixels[..., 2] = 0.8 + 0.3 * y + 1.0 * spot
    return pixels


def image_world(tmp_path, pixels, strength=1.0, rotation=None):
    """``pixels`` as tmp_path/world.exr, the world "Env" of the scene (``environment_world``)."""
    return environment_world(bpy.context.scene, write_exr(tmp_path / "world.exr", pixels),
                             strength, rotation)


def test_an_image_world_is_an_image_source_with_its_settings(tmp_path):
    pixels = smooth_pixels(8, 16)
    image_world(tmp_path, pixels, strength=2.5, rotation=(0.1, 0.2, 0.3))
    datablocks = (len(bpy.data.images), len(bpy.data.worlds), len(bpy.data.scenes))
    source = read_world(bpy.context.scene)
    assert isinstance(source, ImageSource)
    assert (source.world, source.image.name, source.projection) == ("Env", "world.exr",
                                                                    "EQUIRECTANGULAR")
    assert source.image == bpy.data.images["world.exr"]  # the original datablock
    assert source.strength == 2.5 and source.rotation == pytest.approx((0.1, 0.2, 0.3))
    assert source.working_space == "Linear Rec.709" and source.colour_space
    assert source.frame == bpy.context.scene.frame_current
    first = source.pixels()
    assert first.shape == (8, 16, 4) and first.dtype == np.float32
    np.testing.assert_array_equal(first, pixels)
    first[...] = 0.0  # a fresh array: the next call is not affected
    np.testing.assert_array_equal(source.pixels(), pixels)
    assert (len(bpy.data.images), len(bpy.data.worlds), len(bpy.data.scenes)) == datablocks


def test_any_other_world_is_procedural_with_the_reason():
    world = bpy.data.worlds.new("Sky")
    compat.ensure_node_tree(world)
    sky = world.node_tree.nodes.new("ShaderNodeTexSky")
    world.node_tree.links.new(sky.outputs["Color"],
                              world.node_tree.nodes["Background"].inputs["Color"])
    bpy.context.scene.world = world
    source = read_world(bpy.context.scene)
    assert isinstance(source, ProceduralSource)
    assert source.world == "Sky" and "Sky Texture" in source.reason


def test_a_broken_world_is_an_error():
    bpy.context.scene.world = None
    with pytest.raises(WorldError, match="has no world"):
        read_world(bpy.context.scene)


def key(socket, values):
    """Keyframe ``socket.default_value`` at each (frame, value); linear interpolation."""
    for frame, value in values:
        socket.default_value = value
        socket.keyframe_insert("default_value", frame=frame)


def test_keyed_strength_and_mapping_rotation_are_read_at_the_current_frame(tmp_path):
    """Strength 1 → 3 and Mapping Z rotation 0 → 1.2 rad over frames 1–11; at frames 4 and 9
    the image path agrees with Cycles capturing the world at that frame (measured 4.0e-4 and
    4.6e-4 of the largest coefficient: Cycles interpolates the 64-wide image bilinearly); frame 1's
    coefficients are off by more than 30 %."""
    pixels = smooth_pixels()
    world = image_world(tmp_path, pixels, rotation=(0.0, 0.0, 0.0))
    tree = world.node_tree
    strength = tree.nodes["Background"].inputs["Strength"]
    rotation = tree.nodes["Mapping"].inputs["Rotation"]
    key(strength, [(1, 1.0), (11, 3.0)])
    key(rotation, [(1, (0.0, 0.0, 0.0)), (11, (0.0, 0.0, 1.2))])
    scene = bpy.context.scene
    scene.frame_set(1)
    stale, _ = world_coefficients(scene)
    for frame in (4, 9):
        scene.frame_current = frame
        source = read_world(scene)
        assert source.frame == frame
        assert source.strength == pytest.approx(1.0 + 2.0 * _ease(frame), rel=1e-6)
        assert source.rotation[2] == pytest.approx(1.2 * _ease(frame), rel=1e-6)
        coeffs, info = world_coefficients(scene)
        assert info.source == "image" and info.strength == source.strength
        reference = project_equirect(capture_world(world, 128, frame=frame))
        assert rel_err(coeffs, reference) < 2e-3
        assert rel_err(stale, reference) > 0.3


def _ease(frame):
    """Blender's default Bézier keyframe interpolation between frames 1 and 11 (auto-clamped
    handles: the curve is the cubic Bézier 0, 0, 1, 1 in value at t = (frame − 1) / 10)."""
    t = (frame - 1) / 10.0
    return 3 * t * t - 2 * t * t * t


def test_driven_strength_is_read_at_the_current_frame(tmp_path):
    """A driver Strength = frame / 4 (a simple expression, which runs without auto-run)."""
    world = image_world(tmp_path, smooth_pixels())
    strength = world.node_tree.nodes["Background"].inputs["Strength"]
    driver = strength.driver_add("default_value").driver
    driver.type, driver.expression = "SCRIPTED", "frame / 4"
    scene = bpy.context.scene
    for frame in (2, 7):
        scene.frame_current = frame
        source = read_world(scene)
        assert source.strength == pytest.approx(frame / 4.0)
        coeffs, _ = world_coefficients(scene)
        reference = project_equirect(capture_world(world, 128, frame=frame))
        assert rel_err(coeffs, reference) < 2e-3


def test_a_driver_is_read_as_evaluated_not_from_the_stale_original(tmp_path):
    """Strength driven by an Empty's X location: after moving the Empty, the original
    datablock keeps the old Strength until the depsgraph evaluates; the reader does not."""
    world = image_world(tmp_path, smooth_pixels())
    empty = bpy.data.objects.new("Dimmer", None)
    bpy.context.scene.collection.objects.link(empty)
    strength = world.node_tree.nodes["Background"].inputs["Strength"]
    driver = strength.driver_add("default_value").driver
    driver.type = "AVERAGE"
    target = driver.variables.new().targets[0]
    target.id, target.data_path = empty, "location.x"
    empty.location.x = 2.0
    bpy.context.evaluated_depsgraph_get()
    empty.location.x = 0.5
    assert strength.default_value == pytest.approx(2.0)  # stale: what the old reading saw
    scene = bpy.context.scene
    source = read_world(scene)
    assert source.strength == pytest.approx(0.5)
    coeffs, _ = world_coefficients(scene)
    reference = project_equirect(capture_world(world, 128))
    assert rel_err(coeffs, reference) < 2e-3


def test_another_scene_is_read_at_its_own_frame(tmp_path):
    world = image_world(tmp_path, smooth_pixels(8, 16))
    key(world.node_tree.nodes["Background"].inputs["Strength"], [(1, 1.0), (11, 3.0)])
    other = bpy.data.scenes.new("Other")
    other.world = world
    other.frame_current = 11
    bpy.context.scene.frame_current = 1
    assert read_world(other).strength == pytest.approx(3.0)
    assert read_world(bpy.context.scene).strength == pytest.approx(1.0)


def test_window_costs_and_preset_metadata_follow_the_recorded_provenance(tmp_path, addon):
    """Compute from World records what the reader saw (with the working space); the window's
    error against the world is shown while the world still reads the same, and not after its
    Strength changed (nothing is re-projected to find out). Preset metadata names the image,
    Mapping and Strength the values were computed from, not the world's current ones."""
    from sh_lighting import api
    from sh_lighting.blender.data import scene_data
    from sh_lighting.blender.design import edits as design
    from sh_lighting.blender.presets import preset_io

    world = image_world(tmp_path, smooth_pixels(16, 32), strength=2.0, rotation=(0.0, 0.0, 0.4))
    scene = bpy.context.scene
    coeffs = api.compute_from_world(scene)
    record = scene_data.computed_provenance(scene)
    assert record["working_space"] == "Linear Rec.709" and record["strength"] == 2.0
    shown = design.apply_window(scene, "HANNING")
    assert set(shown.costs) == set(design.WINDOWS) and shown.cost is shown.costs["HANNING"]
    api.reset(scene)
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 3.0
    hidden = design.apply_window(scene, "HANNING")
    assert not hidden.costs and "world changed" in hidden.note
    api.reset(scene)
    metadata = preset_io.scene_metadata(scene)
    assert metadata["strength"] == 2.0 and metadata["mapping"] == pytest.approx([0, 0, 0.4])
    assert np.array_equal(scene_data.get_coefficients(scene), coeffs)
