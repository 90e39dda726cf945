"""The panel's words as an artist reads them: the line under the sphere in proportion (a
small dip below zero is not a red error); under Apply, how many materials beyond the selection
Keep BSDF changes (said before, not only in the report after) and, in Material Preview, that
the preview's studio light adds to the SH light; ..."""

from types import SimpleNamespace

import bpy
import numpy as np
import pytest
from blender_scenes import environment_world, run_execute
from ui_layout import RecordingLayout

from sh_lighting.blender.data import compat, scene_data
from sh_lighting.blender.shading import notes
from sh_lighting.blender.presets import preset_io
from sh_lighting.blender.ui import design as design_ui, operators, panels, previews
from sh_lighting.core.sh import sh_basis


def _sphere_line(monkeypatch):
    monkeypatch.setattr(previews, "irradiance",
                        lambda coeffs: (SimpleNamespace(icon_id=200), 0.5))
    layout = RecordingLayout()
    panels.draw_main(layout, bpy.context)
    return [c for c in layout.of("operator") if c[1] == "shlight.window"]


@pytest.mark.skipif(bpy.app.version < (5, 0, 0),
                    reason="Blender 4.2's sunrise.exr is another image (−6 %)")
def test_sunrise_dips_below_zero_quietly(addon, hdri_dir, monkeypatch):
    """Right after Compute on Blender's sunrise.exr (−4.6 %): a quiet line with the depth, not
    a red error; the tooltip says where and over how much of the sphere, and that smoothing
    costs elsewhere."""
    scene = bpy.context.scene
    environment_world(scene, str(hdri_dir / "sunrise.exr"))
    assert bpy.ops.shlight.compute_from_world() == {"FINISHED"}
    [(_, _, props, kwargs)] = _sphere_line(monkeypatch)
    assert kwargs["text"] == "Slight negative light (-4.6 %)"
    assert kwargs["icon"] == "INFO" and not kwargs["alert"] and props.kind == "MINIMAL"
    tooltip = design_ui.SHLIGHT_OT_window.description(bpy.context, props)
    assert "on surfaces facing below" in tooltip and "2.3 % of all directions" in tooltip
    assert "a small dip" in tooltip


def test_grace_dips_below_zero_quietly(addon, monkeypatch):
    """After loading Grace Cathedral (−1.2 %): the quiet line, whole at the default width."""
    grace = preset_io.shipped_preset_dir() / "grace_cathedral.json"
    assert bpy.ops.shlight.load_preset(filepath=str(grace)) == {"FINISHED"}
    [(_, _, _, kwargs)] = _sphere_line(monkeypatch)
    assert kwargs["text"] == "Slight negative light (-1.2 %)" and not kwargs["alert"]
    assert kwargs["icon"] == "INFO"
    assert len(kwargs["text"]) <= 34  # reads in full in the sidebar at its default width


def test_a_deep_dip_is_still_an_error(addon, monkeypatch):
    """A lone bright light, nothing else (−15.8 %): red, with the depth."""
    scene = bpy.context.scene
    lone = np.repeat(sh_basis(np.array([0.0, 0.0, 1.0]))[:, None], 3, axis=1)
    scene_data.store(scene, lone, {"source": "SCRIPT"})
    [(_, _, _, kwargs)] = _sphere_line(monkeypatch)
    assert kwargs["text"] == "Negative light (-16 %): smooth it"
    assert kwargs["icon"] == "ERROR" and kwargs["alert"]


class ViewContext:
    """bpy.context with a 3D Viewport of the given shading as its space."""

    def __init__(self, shading_type, use_scene_world=False):
        self.space_data = SimpleNamespace(type="VIEW_3D", shading=SimpleNamespace(
            type=shading_type, use_scene_world=use_scene_world))

    def __getattr__(self, name):
        return getattr(bpy.context, name)


def three_objects():
    """'Lit' (selected), 'Other' and 'Third', each with a material of its own."""
    scene = bpy.context.scene
    made = []
    for name in ("Lit", "Other", "Third"):
        material = bpy.data.materials.new(name)
        compat.ensure_node_tree(material)
        mesh = bpy.data.meshes.new(name)
        mesh.materials.append(material)
        obj = bpy.data.objects.new(name, mesh)
        scene.collection.objects.link(obj)
        obj.select_set(name == "Lit")
        made.append(material)
    ambient = np.zeros((9, 3))
    ambient[0] = 1.0
    ambient[2] = 0.3  # light from above
    scene_data.store(scene, ambient, {"source": "SCRIPT"})
    return made


def test_apply_says_before_how_many_materials_beyond_the_selection_change(addon):
    """Keep BSDF, Apply To Selected, one of three objects selected: the line under Apply and
    the button's tooltip say 2 more materials change; Emission Only or Apply To All: no line."""
    three_objects()
    bpy.context.scene.sh_lighting.apply_mode = "KEEP_BSDF"
    layout = RecordingLayout()
    panels.draw_main(layout, bpy.context)
    assert ("label", "Also 2 material(s) not selected", "INFO") in layout.calls
    assert len(panels.BEYOND_LINE.format(count=12)) <= notes.MODE_NOTE_CHARACTERS
    tooltip = operators.SHLIGHT_OT_apply.description(bpy.context, SimpleNamespace(mode="SCENE"))
    assert "Keep BSDF also changes 2 material(s) of objects not selected (Other, Third)" in tooltip
    result, reports = run_execute(operators.SHLIGHT_OT_apply, mode="SCENE")
    assert "applied to 3 material(s)" in reports[0][1] and "2 of them beyond" in reports[0][1]
    bpy.context.scene.sh_lighting.apply_mode = "EMISSION"
    layout = RecordingLayout()
    panels.draw_main(layout, bpy.context)
    assert "not selected" not in layout.text()
    bpy.context.scene.sh_lighting.apply_mode = "KEEP_BSDF"
    bpy.context.scene.sh_lighting.apply_target = "ALL"
    assert not operators.beyond_selection(bpy.context)


def test_material_preview_says_its_studio_light_adds_to_the_sh(addon):
    """After Apply, a viewport in Material Preview (its own studio HDRI) gets a line and the
    switch to preview with the scene's world; with Scene World on, Rendered shading, nothing
    applied or Emission Only (its SH light alone): none."""
    three_objects()
    preview = ViewContext("MATERIAL")
    assert panels.studio_preview(preview) is None  # nothing applied yet
    assert bpy.ops.shlight.apply(mode="EMISSION") == {"FINISHED"}
    assert panels.studio_preview(preview) is None
    assert bpy.ops.shlight.apply() == {"FINISHED"}
    layout = RecordingLayout()
    panels.draw_main(layout, preview)
    assert ("label", panels.PREVIEW_LINE, "ERROR") in layout.calls
    assert len(panels.PREVIEW_LINE) <= notes.MODE_NOTE_CHARACTERS
    [switch] = [c for c in layout.of("prop") if c[2] == "use_scene_world"]
    assert switch[1] is preview.space_data.shading
    assert panels.studio_preview(ViewContext("MATERIAL", use_scene_world=True)) is None
    assert panels.studio_preview(ViewContext("RENDERED")) is None


def test_the_panel_speaks_an_artists_words_first(addon):
    """Each coefficient line says what the term does ("Up/down", not "L10 up/down"); its
    tooltip names it (L10) and says what the swatch is; the strength field has a label of
    its own, so Blender does not title its tooltip "sh_L10_gain", and the tooltip says what
    the number does before the paper's s_lm; the smoothing buttons say how much, the paper's
    windows in their tooltips; Flip Vertically says what it does."""
    three_objects()
    layout = RecordingLayout()
    panels.draw_coefficients(layout, bpy.context)
    names = [c[3]["text"] for c in layout.of("operator") if c[1] == "shlight.show_channels"]
    assert names[:3] == ["Overall", "Back/front", "Up/down"] and len(names) == 9
    assert not any(name.startswith("L") for name in names)
    # the name column at the sidebar's default width: "Poles/horizon" showed "Poles/horiz..."
    assert max(map(len, names)) <= 11
    gains = [c for c in layout.of("prop") if c[2].endswith('_gain"]')]
    assert len(gains) == 9 and {c[3]["text"] for c in gains} == {"×"}
    tip = panels.SHLIGHT_OT_show_channels.description(bpy.context, SimpleNamespace(index=2))
    assert tip.startswith("L10 ") and not tip.startswith("L10: L10") and "swatch beside it is the term's colour" in tip
    gain_tip = scene_data.gain_description(2)
    assert gain_tip.startswith("Strength of the light from above vs below term (L10): 1 as "
                               "computed")
    assert gain_tip.index("removes it") < gain_tip.index("s_lm")
    from sh_lighting.blender.ui import design as design_ui

    layout = RecordingLayout()
    design_ui.draw_design(layout, bpy.context)
    smoothing = [c[3]["text"] for c in layout.of("operator") if c[1] == "shlight.window"]
    assert smoothing == ["Just Enough", "Gentle", "Strong"]
    assert "Smooth the lighting" in layout.text() and "ringing" not in layout.text()
    for kind, paper in (("MINIMAL", "minimal non-negative"), ("LANCZOS", "Lanczos"),
                        ("HANNING", "Hanning")):
        tip = design_ui.SHLIGHT_OT_window.description(bpy.context, SimpleNamespace(kind=kind))
        assert tip.startswith(design_ui.SMOOTHING_LABELS[kind] + ": ") and paper in tip
    assert design_ui.SHLIGHT_OT_flip_vertical.bl_label == "Flip Vertically"
