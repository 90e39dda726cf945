"""Rotate, Exposure, Saturation and Band Gains from a button: they run at once with values
that change nothing, then Blender's Adjust Last Operation popup redoes them on every change,
so one use is one undo step (``invoke_props_popup`` pushed a no-op step of its own before
the first change). Rotate's angles drag 1° per pixel, as Blender's own Rotation fields (the
default step turned 3.9° for a 150 px drag). The popup itself and the undo steps are checked
in the GUI session (tests/gui/session.py)."""

from types import SimpleNamespace

import bpy
import numpy as np
from blender_scenes import Recorder
from numpy.testing import assert_allclose

from sh_lighting.blender.data import scene_data
from sh_lighting.blender.ui import design as design_ui

LIGHT = np.arange(27, dtype=np.float64).reshape(9, 3) / 10.0 + 0.5


def invoke(cls, **given):
    """``cls.invoke`` as a button calls it (background Blender has no window, so bpy.ops
    skips invoke): the properties at their defaults, ``given`` ones set; the result."""
    rna = getattr(bpy.ops.shlight, cls.bl_idname.split(".")[1]).get_rna_type().properties
    values = {p.identifier: p.default for p in rna if hasattr(p, "default")
              and not getattr(p, "is_array", False)}
    values.update(given)
    op = Recorder(**values)
    op.IDENTITY = cls.IDENTITY
    op.properties = SimpleNamespace(is_property_set=lambda name: name in given)
    op.apply = lambda scene: cls.apply(op, scene)
    op.execute = lambda context: cls.execute(op, context)
    op.message = lambda result: cls.message(op, result)
    return cls.invoke(op, bpy.context, None), op


def test_from_a_button_each_runs_as_the_identity_then_adjusts(addon):
    scene = bpy.context.scene
    scene_data.store(scene, LIGHT, {"source": "SCRIPT"})
    for name in ("rotate", "exposure", "saturation", "band_gains"):
        cls = getattr(design_ui, f"SHLIGHT_OT_{name}")
        result, op = invoke(cls)
        assert result == {"FINISHED"}, name
        assert_allclose(scene_data.get_coefficients(scene), LIGHT, atol=1e-12, err_msg=name)
    assert op.quadratic == 1.0 and invoke(design_ui.SHLIGHT_OT_saturation)[1].amount == 1.0
    # values given to the button (or by a script) are used
    assert invoke(design_ui.SHLIGHT_OT_exposure, stops=1.0)[0] == {"FINISHED"}
    assert_allclose(scene_data.get_coefficients(scene), 2.0 * LIGHT, rtol=1e-12)
    # and not remembered from a run (SKIP_SAVE): a new one starts from nothing again
    for name, props in (("rotate", ("yaw", "pitch", "roll")), ("exposure", ("stops",)),
                        ("saturation", ("amount",)),
                        ("band_gains", ("ambient", "directional", "quadratic"))):
        rna = getattr(bpy.ops.shlight, name).get_rna_type().properties
        assert all(rna[p].is_skip_save for p in props), name


def test_rotate_drags_a_degree_per_pixel(addon):
    rna = bpy.ops.shlight.rotate.get_rna_type().properties
    for name in ("yaw", "pitch", "roll"):
        assert rna[name].step == design_ui.ANGLE_STEP == 100
        assert rna[name].is_skip_save
    # the same step as Blender's own Object rotation field
    assert bpy.types.Object.bl_rna.properties["rotation_euler"].step == 100
