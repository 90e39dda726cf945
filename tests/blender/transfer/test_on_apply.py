"""EEVEE's Default Apply is Keep BSDF with Shadows (``transfer/on_apply``): on a plain
4-vertex floor under a box, as an artist makes it, Apply bakes the transfer first and lights
every material through it; the shadow it gives matches Cycles path tracing of the world; a
current bake is not baked again, a stale one is; too long a bake is not started by the
Default (said, with its time), but is by the mode named; Remove leaves no trace."""

from types import SimpleNamespace

import blender_scenes as scenes
import bpy
import numpy as np
import pytest
import transfer_scenes as ts
from blender_scenes import bound, run_execute

from sh_lighting.blender.data import compat
from sh_lighting.blender.shading import materials
from sh_lighting.blender.transfer import apply as transfer_apply
from sh_lighting.blender.transfer import bake, on_apply, texels
from sh_lighting.blender.ui import operators

# Measured (48 px, the default 64 bake samples, 16 render samples, reference 512 spp): the
# contact region 2.3 %, the whole image 0.94 %.
CONTACT_TOLERANCE = 0.05
ERROR_TOLERANCE = 0.025


def _artist_scene():
    """A one-quad floor, a box on it (Grey Diffuse), the SH world and its coefficients, in
    EEVEE, both selected (Apply To Selected, the default)."""
    scene, ground, box = ts.lit_ground_and_box(1, 0)
    assert len(ground.data.vertices) == 4
    scene.render.engine = compat.eevee_engine_id()
    for obj in (ground, box):
        obj.select_set(True)
    return scene, ground, box


def _message(reports):
    return " | ".join(text for _kinds, text in reports)


@pytest.mark.slow
def test_the_default_apply_bakes_the_shadows_it_renders(addon, tmp_path):
    scene, ground, box = _artist_scene()
    assert scene.sh_lighting.apply_mode == "AUTO"
    scene.render.engine = "CYCLES"
    scene.cycles.samples = 512
    reference, alpha, _ = scenes.render(scene, tmp_path / "reference.exr")
    covered = alpha > 0.999
    brightness = reference.mean(axis=2)
    contact = covered & (brightness < 0.8 * np.median(brightness[covered]))
    assert contact.sum() > 30

    scene.render.engine = compat.eevee_engine_id()
    result, reports = run_execute(operators.SHLIGHT_OT_apply)
    print("\n" + _message(reports))
    assert result == {"FINISHED"}
    assert "Baked the transfer of 2 object(s)" in _message(reports)
    assert "(Keep BSDF with Shadows) applied to 1 material(s), 1 with the transfer's" in (
        _message(reports))
    grey = box.data.materials[0]
    assert materials.mode_of(grey) == "KEEP_BSDF" and transfer_apply.uses_transfer(grey)
    assert bake.record(ground)["store"] == "TEXELS"  # the plain floor: per texel
    assert all(bake.status(scene, o)[0] == "OK" for o in (ground, box))

    scene.render.engine = "CYCLES"  # the same materials, path traced with the transfer
    scene.cycles.samples = 16
    image, _, _ = scenes.render(scene, tmp_path / "default.exr")
    mask = covered[..., None].repeat(3, axis=-1)
    contact3 = contact[..., None].repeat(3, axis=-1)
    errors = (ts.relative_rmse(image, reference, contact3),
              ts.relative_rmse(image, reference, mask))
    print(f"contact {errors[0]:.4f}, whole {errors[1]:.4f}")
    assert errors[0] < CONTACT_TOLERANCE and errors[1] < ERROR_TOLERANCE, errors


def test_a_current_bake_is_kept_and_a_stale_one_baked_again(addon):
    scene, ground, box = _artist_scene()
    result, reports = run_execute(operators.SHLIGHT_OT_apply)
    assert result == {"FINISHED"} and "Baked" in _message(reports)
    baked = bake.record(box)["baked"]

    result, reports = run_execute(operators.SHLIGHT_OT_apply)
    assert result == {"FINISHED"} and "Baked" not in _message(reports)
    assert bake.record(box)["baked"] == baked
    assert on_apply.needed(scene, [ground, box]).objects == []

    box.location.x += 0.5  # moved: the shadow is elsewhere
    bpy.context.view_layer.update()
    need = on_apply.needed(scene, [ground, box])
    assert {o.name for o in need.objects} == {"Ground", "Box"}
    assert on_apply.cost_line(need).startswith("bakes the shadows of 2 object(s) first, about ")
    seconds = bake.record(box)["seconds"]  # the estimate learns from the last bake's time
    assert seconds / 3 < need.plan.seconds < 3 * seconds, (need.plan.seconds, seconds)
    result, reports = run_execute(operators.SHLIGHT_OT_apply)
    assert "Baked the transfer of 2 object(s)" in _message(reports)
    assert bake.status(scene, box)[0] == "OK"


def test_the_default_does_not_start_a_long_bake_the_mode_named_does(addon, monkeypatch):
    scene, ground, box = _artist_scene()
    monkeypatch.setattr(on_apply, "AFFORDABLE_SECONDS", 0.0)
    description = operators.SHLIGHT_OT_apply.description(
        bpy.context, type("Props", (), {"mode": "SCENE"})())
    assert "Apply gives no shadows: their bake would take about" in description
    result, reports = run_execute(operators.SHLIGHT_OT_apply)
    message = _message(reports)
    assert result == {"FINISHED"} and "Baked" not in message
    assert "no shadows: their bake would take about" in message
    assert "choose Keep BSDF with Shadows, or Bake Transfer" in message
    grey = box.data.materials[0]
    assert materials.mode_of(grey) == "KEEP_BSDF" and not transfer_apply.uses_transfer(grey)
    assert bake.record(box) is None

    result, reports = run_execute(operators.SHLIGHT_OT_apply, mode="TRANSFER")
    assert "Baked the transfer of 2 object(s)" in _message(reports)
    assert transfer_apply.uses_transfer(grey)


def test_remove_after_the_default_leaves_no_trace(addon, monkeypatch):
    scene, ground, box = _artist_scene()
    assert run_execute(operators.SHLIGHT_OT_apply)[0] == {"FINISHED"}
    assert ground.data.uv_layers.get(texels.UV_NAME) is not None
    result, reports = run_execute(operators.SHLIGHT_OT_remove)
    assert result == {"FINISHED"}, reports
    assert "the transfer bake of 2 object(s) deleted" in _message(reports)
    for obj in (ground, box):
        assert bake.record(obj) is None
        assert not any(a.name.startswith("sh_T") for a in obj.data.color_attributes)
        assert obj.data.uv_layers.get(texels.UV_NAME) is None
    assert not any(i.name.startswith("SH Transfer") for i in bpy.data.images)
    assert not any(materials.is_applied(m) for m in bpy.data.materials)
    assert not any(g.name.startswith("SH Transfer") and g.users for g in bpy.data.node_groups)


def test_a_mesh_that_cannot_be_baked_is_named(addon, monkeypatch):
    scene, ground, box = _artist_scene()
    box.modifiers.new("Mirror", "MIRROR")
    result, reports = run_execute(operators.SHLIGHT_OT_apply)
    message = _message(reports)
    assert result == {"FINISHED"}
    assert "no shadows on 'Box'" in message and "Mirror" in message
    assert "Baked the transfer of 1 object(s)" in message


def test_esc_during_the_defaults_bake_changes_nothing(addon):
    """The modal run (a window's): Esc between two basis bakes stores nothing, applies
    nothing, and says so in one line."""
    scene, ground, box = _artist_scene()
    operator = bound(operators.SHLIGHT_OT_apply)
    operator._objects, operator._notes = [ground, box], []
    operator._job = bake.Bake(scene, [ground, box])
    operator._job.step()
    assert operator.modal(bpy.context, SimpleNamespace(type="ESC")) == {"CANCELLED"}
    assert operator.reports == [({"WARNING"}, "Apply cancelled during the shadows' bake: "
                                 "nothing changed")]
    assert bake.record(ground) is None and bake.record(box) is None
    assert ground.data.uv_layers.get(texels.UV_NAME) is None
    assert not any(materials.is_applied(m) for m in bpy.data.materials)


def test_a_saved_modes_number_is_kept(addon):
    """.blend files store the Mode by number: the new mode took a number of its own, so a
    file saved with Keep BSDF or Emission Only opens with it."""
    items = bpy.types.Scene.bl_rna.properties["sh_lighting"].fixed_type.bl_rna.properties[
        "apply_mode"].enum_items
    assert {i.identifier: i.value for i in items} == {
        "AUTO": 0, "WORLD": 1, "KEEP_BSDF": 2, "EMISSION": 3, "TRANSFER": 4}
