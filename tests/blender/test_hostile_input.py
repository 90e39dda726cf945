"""What a careless script hands the API: one clear error each, and the scene unchanged."""

import bpy
import numpy as np
import pytest
from blender_files import write_constant_exr
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
    world = bpy.data.worlds.new("Huge")
    if world.node_tree is None:
        world.use_nodes = True
    tree = world.node_tree
    texture = tree.nodes.new("ShaderNodeTexEnvironment")
    texture.image = bpy.data.images.load(write_constant_exr(tmp_path / "huge.exr", (1e38,) * 3))
    background = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeBackground")
    tree.links.new(texture.outputs["Color"], background.inputs["Color"])
    scene.world = world
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
