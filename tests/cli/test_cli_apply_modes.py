"""``apply --mode``: the panel's modes and default, through the command in a fresh process.

The default ("AUTO") is Edit World in Cycles and Keep BSDF with Shadows in EEVEE (the transfer
baked first), by the scene's render engine, as Apply in the panel. The preset is a constant sky of its own colour (not the
world's), so the edited world shows that colour around the sphere: the nine terms replace a
world without coefficients of its own.
"""

import math

import bpy
import numpy as np
import pytest
from cli_runs import SIZE, hidden_files, make_inputs, run
from numpy.testing import assert_allclose

from sh_lighting.blender import world_edit
from sh_lighting.blender.data import compat
from sh_lighting.blender.shading import materials
from sh_lighting.blender.transfer import apply as transfer_apply
from sh_lighting.blender.transfer import bake
from sh_lighting.choices import APPLY_MODES, resolve_mode
from sh_lighting.formats.presets import write_preset

pytestmark = pytest.mark.blender

SKY = (1.0, 0.25, 0.5)  # the preset's sky, unlike the world's (cli_runs.SKY)


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("cli_modes")
    found = make_inputs(folder)
    coefficients = np.zeros((9, 3))
    coefficients[0] = 2.0 * math.sqrt(math.pi) * np.array(SKY)
    found["preset"] = write_preset(folder / "own_sky.json", coefficients, {"name": "own sky"})
    return found


def _variant(source, path, change):
    """A copy of the .blend ``source`` at ``path`` with ``change(scene)`` done to it."""
    bpy.ops.wm.open_mainfile(filepath=str(source))
    change(bpy.context.scene)
    bpy.ops.wm.save_as_mainfile(filepath=str(path), copy=True)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    return path


def _opened(path):
    bpy.ops.wm.open_mainfile(filepath=str(path))
    return bpy.context.scene, bpy.data.materials["Grey"]


def test_the_modes_are_the_panels_with_its_default():
    result = run("apply", "--help")
    assert result.returncode == 0, result.stderr
    for mode in APPLY_MODES:
        assert mode in result.stdout
    assert "AUTO (default)" in " ".join(result.stdout.split())
    wrong = run("apply", "p.json", "s.blend", "--out", "o.blend", "--mode", "BOGUS")
    assert wrong.returncode == 2 and "invalid choice: 'BOGUS'" in wrong.stderr
    for mode in APPLY_MODES[1:]:
        assert f"'{mode}'" in wrong.stderr


def test_default_in_cycles_edits_the_world_and_renders_the_preset(inputs, tmp_path):
    out = tmp_path / "cycles.blend"
    result = run("apply", inputs["preset"], inputs["blend"], "--out", out)
    assert result.returncode == 0, result.stderr
    assert "Edit World" in result.stdout and "world 'Sky' edited" in result.stdout
    assert hidden_files(tmp_path) == []
    scene, grey = _opened(out)
    assert scene.render.engine == "CYCLES"
    assert world_edit.is_edited(scene.world)
    assert not materials.is_applied(grey)  # the materials untouched
    bpy.ops.wm.read_factory_settings(use_empty=True)

    frame = tmp_path / "frame_####"
    result = run("render", out, "--output", frame, "--frame", "1", "--samples", "1")
    assert result.returncode == 0, result.stderr
    image = bpy.data.images.load(str(tmp_path / "frame_0001.exr"))
    pixels = np.empty(SIZE[0] * SIZE[1] * 4, np.float32)
    image.pixels.foreach_get(pixels)
    corner = pixels.reshape(SIZE[1], SIZE[0], 4)[0, 0, :3]
    assert_allclose(corner, SKY, rtol=1e-4)  # the world is the preset's sky now


def test_default_in_eevee_bakes_the_shadows_and_keeps_the_bsdf(inputs, tmp_path):
    blend = _variant(inputs["blend"], tmp_path / "eevee.blend",
                     lambda scene: setattr(scene.render, "engine", compat.eevee_engine_id()))
    out = tmp_path / "eevee_sh.blend"
    result = run("apply", inputs["preset"], blend, "--out", out)
    assert result.returncode == 0, result.stderr
    assert resolve_mode("AUTO", compat.eevee_engine_id()) == "TRANSFER"
    assert "Keep BSDF with Shadows" in result.stdout
    assert "Baked the transfer of 1 object(s)" in result.stdout
    assert "applied to 1 material(s), 1 with the transfer's shadows: Grey" in result.stdout
    scene, grey = _opened(out)
    assert materials.mode_of(grey) == "KEEP_BSDF" and transfer_apply.uses_transfer(grey)
    assert bake.status(scene, scene.objects["Ball"])[0] == "OK"
    assert not world_edit.is_edited(scene.world)
    # Applied again with the bake current: nothing baked, the transfer kept
    again = run("apply", inputs["preset"], out, "--out", tmp_path / "again.blend")
    assert again.returncode == 0, again.stderr
    assert "Baked" not in again.stdout and "1 with the transfer's shadows" in again.stdout


def test_edit_world_takes_the_sh_out_of_the_materials(inputs, tmp_path):
    lit = tmp_path / "lit.blend"
    result = run("apply", inputs["preset"], inputs["blend"], "--out", lit, "--mode", "EMISSION")
    assert result.returncode == 0, result.stderr
    out = tmp_path / "world.blend"
    result = run("apply", inputs["preset"], lit, "--out", out, "--mode", "WORLD")
    assert result.returncode == 0, result.stderr
    assert "taken out of 1 material(s)" in result.stdout
    scene, grey = _opened(out)
    assert world_edit.is_edited(scene.world) and not materials.is_applied(grey)
    bpy.ops.wm.read_factory_settings(use_empty=True)

    back = tmp_path / "back.blend"  # and a material mode takes the edit out of the world
    result = run("apply", inputs["preset"], out, "--out", back, "--mode", "KEEP_BSDF")
    assert result.returncode == 0, result.stderr
    scene, grey = _opened(back)
    assert not world_edit.is_edited(scene.world) and materials.mode_of(grey) == "KEEP_BSDF"


def test_edit_world_refusals_are_one_line_and_save_nothing(inputs, tmp_path):
    objects = run("apply", inputs["preset"], inputs["blend"], "--out", tmp_path / "o.blend",
                  "--objects", "Ball")
    assert objects.returncode == 1
    assert "--objects" in objects.stderr and "--mode KEEP_BSDF" in objects.stderr
    assert len(objects.stderr.strip().splitlines()) == 1

    blend = _variant(inputs["blend"], tmp_path / "no_world.blend",
                     lambda scene: setattr(scene, "world", None))
    bare = run("apply", inputs["preset"], blend, "--out", tmp_path / "o.blend")
    assert bare.returncode == 1 and "has no world" in bare.stderr
    assert "Traceback" not in bare.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["no_world.blend"]
