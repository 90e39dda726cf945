"""Extract Lights in Blender (blender/lights.py, lights_ui.py, api, CLI): Sun lights plus the
SH of the rest give the world's irradiance, with the world's Mapping rotation and Strength;
re-extraction, Reset, Split Sun and Compute never double a light; undo."""

import subprocess
import sys

import bpy
import numpy as np
import pytest

from sh_lighting import api
from sh_lighting.blender import compat, scene_data
from sh_lighting.blender.design import lights
from sh_lighting.blender.world.images import load_image_pixels
from sh_lighting.core.irradiance import irradiance, relative_error, total_power
from sh_lighting.core.sh import spread_normals
from sh_lighting.core.world_map import map_irradiance
from tests.blender.test_design_ui import environment_world
from tests.conftest import ROOT

ROTATION = (0.3, -0.2, 1.1)
STRENGTH = 2.5


def scene_light_irradiance(scene, normals):
    """Σ over the scene's Sun lights of energy · colour · max(n·(its +Z), 0), from Blender's
    own objects (what the renderer is given)."""
    total = np.zeros((len(normals), 3))
    for obj in lights.extracted_lights(scene):
        toward = np.array(obj.rotation_euler.to_matrix().col[2])
        total += (np.maximum(normals @ toward, 0.0)[:, None] * obj.data.energy
                  * np.array(obj.data.color))
    return total


@pytest.mark.parametrize("name", ["sunrise", "studio"])
def test_lights_plus_sh_equal_the_rotated_scaled_world(addon, hdri_dir, name):
    scene = bpy.context.scene
    path = str(hdri_dir / f"{name}.exr")
    environment_world(scene, path, STRENGTH, ROTATION)
    whole = api.compute_from_world(scene)
    info = api.extract_lights(scene, count=4)
    assert info.lights and len(lights.extracted_lights(scene)) == len(info.lights)
    for obj in lights.extracted_lights(scene):  # the world's image still shows in reflections
        assert not obj.visible_glossy and not obj.visible_transmission and obj.visible_diffuse
    pixels = load_image_pixels(path)
    normals = spread_normals(512)
    truth = map_irradiance(pixels, normals, STRENGTH, ROTATION)
    power = total_power(whole)
    plain = relative_error(irradiance(whole, normals), truth, power)
    split = relative_error(irradiance(scene_data.get_coefficients(scene), normals)
                           + scene_light_irradiance(scene, normals), truth, power)
    print(f"\n{name}: {len(info.lights)} light(s); mean / max error (% of the light): SH "
          f"{100 * plain[0]:.2f} / {100 * plain[1]:.2f}, SH + lights {100 * split[0]:.2f} / "
          f"{100 * split[1]:.2f}; core's own {100 * info.extraction.errors[-1][0]:.2f}")
    # the Blender objects give what the core measured (same numbers, other normals' order)
    assert split[0] == pytest.approx(info.extraction.errors[-1][0], rel=0.02)
    assert split[0] < 0.35 * plain[0]


def light_count(scene):
    return len([o for o in scene.objects if o.type == "LIGHT"])


def test_reextraction_reset_split_sun_and_compute_never_double_a_light(addon, hdri_dir):
    scene = bpy.context.scene
    environment_world(scene, str(hdri_dir / "studio.exr"), 1.0)
    whole = api.compute_from_world(scene)
    first = api.extract_lights(scene, count=3)
    assert len(first.created) == 3
    scene.objects[first.lights[0]].data.color = (1.0, 0.0, 0.0)  # the artist retints one
    again = api.extract_lights(scene, count=3)
    assert again.created == [] and again.lights == first.lights and light_count(scene) == 3
    np.testing.assert_array_equal(again.coefficients, first.coefficients)
    # Reset: the Reset values are the rest now, the lights stay
    api.set_coefficients(scene, whole)
    api.reset(scene)
    np.testing.assert_array_equal(scene_data.get_coefficients(scene), first.coefficients)
    assert light_count(scene) == 3
    # Split Sun updates the brightest light instead of adding a sun, coefficients unchanged
    api.split_sun(scene)
    assert light_count(scene) == 3
    np.testing.assert_array_equal(scene_data.get_coefficients(scene), first.coefficients)
    fewer = api.extract_lights(scene, count=1)
    assert fewer.lights == first.lights[:1] and sorted(fewer.removed) == sorted(first.lights[1:])
    bpy.data.objects.remove(scene.objects[fewer.lights[0]])  # the artist deletes it
    back = api.extract_lights(scene, count=1)
    assert len(back.created) == 1 and light_count(scene) == 1
    api.compute_from_world(scene)  # the whole world in the SH again: no light left
    assert light_count(scene) == 0
    np.testing.assert_array_equal(scene_data.get_coefficients(scene), whole)


def test_operator_reports_and_undoes(addon, hdri_dir):
    scene = bpy.context.scene
    environment_world(scene, str(hdri_dir / "sunrise.exr"), 1.0)
    assert bpy.ops.shlight.compute_from_world() == {"FINISHED"}
    before = scene_data.get_coefficients(scene)
    bpy.ops.ed.undo_push(message="before")
    assert bpy.ops.shlight.extract_lights("EXEC_DEFAULT", True, count=2) == {"FINISHED"}
    scene = bpy.context.scene
    assert len(lights.extracted_lights(scene)) >= 1
    bpy.ops.ed.undo()
    scene = bpy.context.scene
    assert lights.extracted_lights(scene) == []
    np.testing.assert_array_equal(scene_data.get_coefficients(scene), before)
    assert bpy.ops.shlight.extract_lights("EXEC_DEFAULT", True, count=2) == {"FINISHED"}
    assert bpy.ops.shlight.compute_from_world() == {"FINISHED"}
    assert lights.extracted_lights(bpy.context.scene) == []


def test_no_image_world_is_one_clear_error_and_nothing_changes(addon):
    scene = bpy.context.scene
    scene.world = bpy.data.worlds.new("Plain")
    compat.ensure_node_tree(scene.world)  # a Background colour, no image
    api.set_coefficients(scene, np.ones((9, 3)))
    with pytest.raises(ValueError, match="Environment Texture"):
        api.extract_lights(scene)
    np.testing.assert_array_equal(scene_data.get_coefficients(scene), np.ones((9, 3)))
    assert not [o for o in scene.objects if o.type == "LIGHT"]


def test_cli_compute_lights(hdri_dir):
    result = subprocess.run(
        [sys.executable, "-m", "sh_lighting", "compute", str(hdri_dir / "sunrise.exr"),
         "--lights", "2"], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    assert "Light 1: Sun toward (" in result.stdout
    assert "light(s) extracted: mean irradiance error 2.2" in result.stdout
    bad = subprocess.run([sys.executable, "-m", "sh_lighting", "compute", "x.exr", "--lights",
                          "12"], cwd=ROOT, capture_output=True, text=True, timeout=60)
    assert bad.returncode == 2 and "--lights" in bad.stderr
