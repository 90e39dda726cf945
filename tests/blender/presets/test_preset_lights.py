"""Loading a preset over a world whose lights Extract Lights took out: those Sun lamps came
from the old world, so they are deleted (an artist's duplicate stays) and the report says so;
a failed load changes nothing, lamps included."""

import bpy
from blender_scenes import environment_world, run_execute

from sh_lighting.blender.design import lights
from sh_lighting.blender.presets import preset_io
from sh_lighting.blender.ui import presets as presets_ui


def test_preset_over_extracted_lights_deletes_them_and_says_so(addon, hdri_dir, tmp_path):
    scene = bpy.context.scene
    environment_world(scene, str(hdri_dir / "sunrise.exr"))
    assert bpy.ops.shlight.compute_from_world() == {"FINISHED"}
    assert bpy.ops.shlight.extract_lights(count=2, use_error_target=False) == {"FINISHED"}
    made = [o.name for o in lights.extracted_lights(scene)]
    assert len(made) == 2
    copy = bpy.data.objects[made[0]].copy()
    scene.collection.objects.link(copy)
    bad = tmp_path / "bad.json"
    bad.write_text("{")
    result, _ = run_execute(presets_ui.SHLIGHT_OT_load_preset, filepath=str(bad))
    assert result == {"CANCELLED"} and len(lights.extracted_lights(scene)) == 2
    grace = preset_io.shipped_preset_dir() / "grace_cathedral.json"
    result, reports = run_execute(presets_ui.SHLIGHT_OT_load_preset, filepath=str(grace))
    [(kind, message)] = reports
    print(f"\n{message}")
    assert result == {"FINISHED"} and kind == {"INFO"}
    assert not lights.extracted_lights(scene)
    assert [o.name for o in scene.objects if o.type == "LIGHT"] == [copy.name]
    assert "2 Sun light(s) extracted from the previous world deleted" in message
