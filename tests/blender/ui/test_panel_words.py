"""The panel's words as an artist reads them: the line under the sphere in proportion (a
small dip below zero is not a red error), ..."""

from types import SimpleNamespace

import bpy
import numpy as np
from blender_scenes import environment_world
from ui_layout import RecordingLayout

from sh_lighting.blender.data import scene_data
from sh_lighting.blender.presets import preset_io
from sh_lighting.blender.ui import design as design_ui, panels, previews
from sh_lighting.core.sh import sh_basis


def _sphere_line(monkeypatch):
    monkeypatch.setattr(previews, "irradiance",
                        lambda coeffs: (SimpleNamespace(icon_id=200), 0.5))
    layout = RecordingLayout()
    panels.draw_main(layout, bpy.context)
    return [c for c in layout.of("operator") if c[1] == "shlight.window"]


def test_sunrise_and_grace_dip_below_zero_quietly(addon, hdri_dir, monkeypatch):
    """Right after Compute on Blender's sunrise.exr (−4.6 %) and after loading Grace
    Cathedral (−1.2 %): a quiet line with the depth, not a red error; the tooltip says where
    and over how much of the sphere, and that smoothing costs elsewhere."""
    scene = bpy.context.scene
    environment_world(scene, str(hdri_dir / "sunrise.exr"))
    assert bpy.ops.shlight.compute_from_world() == {"FINISHED"}
    [(_, _, props, kwargs)] = _sphere_line(monkeypatch)
    assert kwargs["text"] == "Slight negative light (-4.6 %)"
    assert kwargs["icon"] == "INFO" and not kwargs["alert"] and props.kind == "MINIMAL"
    tooltip = design_ui.SHLIGHT_OT_window.description(bpy.context, props)
    assert "on surfaces facing below" in tooltip and "2.3 % of all directions" in tooltip
    assert "a small dip" in tooltip
    grace = preset_io.shipped_preset_dir() / "grace_cathedral.json"
    assert bpy.ops.shlight.load_preset(filepath=str(grace)) == {"FINISHED"}
    [(_, _, _, kwargs)] = _sphere_line(monkeypatch)
    assert kwargs["text"] == "Slight negative light (-1.2 %)" and not kwargs["alert"]
    assert len(kwargs["text"]) <= 34  # reads in full in the sidebar at its default width


def test_a_deep_dip_is_still_an_error(addon, monkeypatch):
    """A lone bright light, nothing else (−15.8 %): red, with the depth."""
    scene = bpy.context.scene
    lone = np.repeat(sh_basis(np.array([0.0, 0.0, 1.0]))[:, None], 3, axis=1)
    scene_data.store(scene, lone, {"source": "SCRIPT"})
    [(_, _, _, kwargs)] = _sphere_line(monkeypatch)
    assert kwargs["text"] == "Negative light (-16 %): smooth it"
    assert kwargs["icon"] == "ERROR" and kwargs["alert"]
