"""Registration: nothing left behind after many enable/disable cycles, and what the UI needs
(undoable operators, described properties without a 0-1 clamp, panels that draw valid paths),
and everything gone again after unregister.
"""

from types import SimpleNamespace

import bpy
import numpy as np
import pytest
from blender_files import SCRIPT

from sh_lighting import blender
from sh_lighting.blender.design import edits as design
from sh_lighting.blender.ui import operators, panels
from sh_lighting.blender.data import scene_data
from sh_lighting.core.sh import COEFFICIENT_NAMES
from ui_layout import RecordingLayout

CYCLES = 20


def handler_snapshot():
    """Every list of bpy.app.handlers, as the ids of the functions it holds."""
    return {
        name: [id(h) for h in getattr(bpy.app.handlers, name)]
        for name in dir(bpy.app.handlers)
        if isinstance(getattr(bpy.app.handlers, name), list)
    }


def test_enable_disable_many_times_leaves_nothing_behind():
    import sh_lighting

    types_before = set(dir(bpy.types))
    handlers_before = handler_snapshot()
    ops_before = set(dir(bpy.ops.shlight))
    for _ in range(CYCLES):
        sh_lighting.register()
        assert hasattr(bpy.types.Scene, "sh_lighting")
        assert "SHLIGHT_OT_compute_from_world" in dir(bpy.types)
        assert "SHLIGHT_PT_view3d_coefficients" in dir(bpy.types)
        assert bpy.context.scene.sh_lighting.apply_target == "SELECTED"
        sh_lighting.unregister()
    assert not hasattr(bpy.types.Scene, "sh_lighting")
    assert set(dir(bpy.types)) == types_before
    assert handler_snapshot() == handlers_before
    assert set(dir(bpy.ops.shlight)) == ops_before
    assert not any(name.startswith("SHLIGHT_") for name in dir(bpy.types))


def test_every_class_registered_and_gone():
    import sh_lighting

    classes = [cls for module in blender.MODULES for cls in module.classes]
    assert len(classes) > 10
    assert not any(cls.is_registered for cls in classes)
    sh_lighting.register()
    try:
        assert [cls for cls in classes if not cls.is_registered] == []
        assert hasattr(bpy.types.Scene, "sh_lighting")
    finally:
        sh_lighting.unregister()
    assert [cls.__name__ for cls in classes if cls.is_registered] == []
    assert not hasattr(bpy.types.Scene, "sh_lighting")
    for cls in classes:
        assert getattr(bpy.types, cls.__name__, None) is None, cls.__name__


@pytest.mark.parametrize("cls", operators.classes, ids=lambda c: c.__name__)
def test_operators_are_undoable(addon, cls):
    assert {"REGISTER", "UNDO"} <= cls.bl_options
    assert cls.__doc__
    idname = cls.bl_idname.split(".")
    assert "UNDO" in getattr(getattr(bpy.ops, idname[0]), idname[1]).bl_options


def test_settings_properties_are_described(addon):
    rna = bpy.types.Scene.bl_rna.properties["sh_lighting"].fixed_type
    names = {p.identifier for p in rna.properties} - {"rna_type", "name"}
    assert names == {"apply_target", "apply_mode", "use_capture_width", "capture_width"}  # no coefficients
    for name in names:
        assert rna.properties[name].description, name


def test_coefficient_custom_properties_get_ui_data(addon):
    scene = bpy.context.scene
    scene_data.store(scene, [[-3.0, 0.5, 40.0]] * 9, SCRIPT)
    for index, name in enumerate(scene_data.PROPERTY_NAMES):
        ui = scene.id_properties_ui(name).as_dict()
        assert ui["subtype"] == "NONE"  # 3 number fields, no colour swatch
        assert ui["min"] < -1e30 and ui["max"] > 1e30  # signed HDR: no hard limits
        assert ui["soft_min"] == -80.0 and ui["soft_max"] == 80.0  # 2 × the largest value
        assert COEFFICIENT_NAMES[index] in ui["description"]
        assert list(scene[name]) == [-3.0, 0.5, 40.0]  # written as given, not clamped
        gain = scene.id_properties_ui(scene_data.GAIN_NAMES[index]).as_dict()
        assert scene[scene_data.GAIN_NAMES[index]] == 1.0 and gain["default"] == 1.0
        assert "strength" in gain["description"].lower() and gain["min"] < -1e30
    scene_data.store(scene, [[0.01, 0.02, -0.03]] * 9, SCRIPT)  # the drag range follows
    assert scene.id_properties_ui("sh_L10").as_dict()["soft_max"] == pytest.approx(0.06)


def test_panels_draw_resolvable_properties_and_operators(addon):
    scene = bpy.context.scene
    context = bpy.context
    layout = RecordingLayout()
    panels.draw_main(layout, context)
    ops = layout.operators()
    assert ops == ["shlight.compute_from_world", "shlight.reset", "shlight.apply", "shlight.remove"]
    for idname in ops:
        module, name = idname.split(".")
        assert hasattr(getattr(bpy.ops, module), name)

    layout = RecordingLayout()
    panels.draw_coefficients(layout, context)
    assert not layout.of("prop")  # no coefficients yet: a hint only
    assert "press Compute from World" in layout.text()

    scene_data.store(scene, [[float(i), 1.0, 2.0] for i in range(9)], SCRIPT)
    layout = RecordingLayout()
    panels.draw_coefficients(layout, context)
    names = [c[3]["text"] for c in layout.of("operator")]
    assert names[2] == "Up/down" and names[3] == "Right/left"  # one line per coefficient
    assert [c[2].index for c in layout.of("operator")] == list(range(9))
    assert len(layout.of("icon")) == 9  # a swatch each
    props = layout.of("prop")
    assert [path for _, data, path, _kwargs in props] == [
        f'["{name}"]' for name in scene_data.GAIN_NAMES]  # the strength only: channels on demand
    for _, data, path, _kwargs in props:
        data.path_resolve(path)  # the drawn path exists

    bpy.context.window_manager.sh_lighting_show_channels[2] = True  # L10 opened
    layout = RecordingLayout()
    panels.draw_coefficients(layout, context)
    rgb = [(path, kwargs["index"]) for _, data, path, kwargs in layout.of("prop")
           if "index" in kwargs]
    assert rgb == [('["sh_L10"]', 0), ('["sh_L10"]', 1), ('["sh_L10"]', 2)]
    assert layout.of("operator")[2][3]["icon"] == "DISCLOSURE_TRI_DOWN"


def test_coefficient_line_tooltip_says_what_it_does_now(addon):
    from sh_lighting.core.edits import describe_coefficients

    scene = bpy.context.scene
    op = panels.SHLIGHT_OT_show_channels
    assert op.description(bpy.context, SimpleNamespace(index=2)).startswith(
        "L10: light from above vs below")
    coeffs = np.array([[float(i), 1.0, 2.0] for i in range(9)])
    scene_data.store(scene, coeffs, SCRIPT)
    text = op.description(bpy.context, SimpleNamespace(index=2))
    assert text.startswith(describe_coefficients(coeffs, design.luminance())[2])
    assert bpy.ops.shlight.show_channels(index=4) == {"FINISHED"}
    assert list(bpy.context.window_manager.sh_lighting_show_channels) == [False] * 4 + [True] + [
        False] * 4


def test_panels_live_in_world_properties_and_sidebar(addon):
    assert panels.SHLIGHT_PT_world.bl_context == "world"
    assert panels.SHLIGHT_PT_world.bl_space_type == "PROPERTIES"
    assert panels.SHLIGHT_PT_view3d.bl_space_type == "VIEW_3D"
    assert panels.SHLIGHT_PT_view3d.bl_category == "SH Lighting"
    assert panels.SHLIGHT_PT_world_coefficients.bl_parent_id == "SHLIGHT_PT_world"
    assert panels.SHLIGHT_PT_view3d_coefficients.bl_parent_id == "SHLIGHT_PT_view3d"
