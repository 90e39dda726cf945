"""Transfer's log as an artist reads it: Apply Transfer after Select All says nothing about
the camera and the lamps (they have no transfer to apply), only about meshes; a bake sends
OpenImageIO's debug channel nowhere unless the user chose a file for it."""

import os

import bpy
import transfer_scenes as ts
from blender_scenes import run_execute

from sh_lighting.blender.transfer import bake
from sh_lighting.blender.ui import transfer as transfer_ui
from sh_lighting.blender.ui import bake_steps
from tests.blender.transfer.test_transfer_ui import _scene


def test_apply_transfer_after_select_all_names_no_camera_or_lamp(addon):
    scene, ground, box = _scene(2, 0)
    bake.bake_transfer(scene, [ground], samples=1)
    ground.data.materials[0] = ts.diffuse_material("Ground Grey")
    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
    for obj in (camera, sun):
        scene.collection.objects.link(obj)
    for obj in scene.objects:
        obj.select_set(True)
    scene.sh_lighting.apply_target = "SELECTED"
    result, reports = run_execute(transfer_ui.SHLIGHT_OT_apply_transfer, mode="SCENE")
    [(kind, message)] = reports
    print(f"\n{message}")
    assert result == {"FINISHED"}
    assert "Camera" not in message and "Sun" not in message
    assert box.name in message  # a mesh without a bake is still named


def test_a_bake_sends_the_image_librarys_debug_channel_nowhere(monkeypatch):
    monkeypatch.delenv(bake_steps.OIIO_DEBUG_FILE, raising=False)
    bake_steps.quiet_image_library()
    assert os.environ[bake_steps.OIIO_DEBUG_FILE] == os.devnull
    monkeypatch.setenv(bake_steps.OIIO_DEBUG_FILE, "/tmp/mine.log")
    bake_steps.quiet_image_library()
    assert os.environ[bake_steps.OIIO_DEBUG_FILE] == "/tmp/mine.log"
