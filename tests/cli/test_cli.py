"""The command line, each command run in its own process (``python -m sh_lighting ...``) on
tiny inputs: a constant-colour EXR, whose exact coefficients are L00 = 2√π c and 0 for the
rest (docs/reference.md §2), and a .blend with a grey sphere lit by that EXR as its world.

Under a constant sky of radiance c (strength 1) a Lambertian surface of albedo ρ shows ρ c,
and the 9-term lighting is exact for it, so a render of the applied file shows 0.5 c on the
sphere and c around it.
"""

import math
import os

import bpy
import numpy as np
import pytest
from blender_files import write_exr
from cli_runs import (
    ALBEDO, EXACT, ROOT, SIZE, SKY, constant_pixels, hidden_files, make_inputs, run, table_row,
)
from numpy.testing import assert_allclose

from sh_lighting.cli import script as cli_script
from sh_lighting.blender.shading import materials
from sh_lighting.blender.data import scene_data
from sh_lighting.formats.presets import read_preset

pytestmark = pytest.mark.blender

FLOAT32_TOL = 1e-6  # the EXR holds float32 texels
RENDER_TOL = 1e-4  # Cycles float32 shading of the group's polynomial


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    return make_inputs(tmp_path_factory.mktemp("cli_inputs"))


# --- help and argument errors (no bpy import: fast) -----------------------------------------


@pytest.mark.parametrize(
    "command, expected",
    [
        (None, ["compute", "apply", "render", "batch"]),
        ("compute", ["HDRI_OR_BLEND", "--out", "--overwrite", "--capture-width"]),
        ("apply", ["PRESET", "BLEND", "--objects", "--out", "--in-place"]),
        ("render", ["--output", "--frame", "--frames", "--engine", "--samples"]),
        ("batch", ["HDRI_DIR", "OUT_DIR", "--force", "--pattern"]),
    ],
)
def test_help_of_each_command(command, expected):
    result = run(*([command] if command else []), "--help")
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith("usage: python -m sh_lighting")
    for word in expected:
        assert word in result.stdout


def test_wrong_arguments_exit_2_with_usage(inputs, tmp_path):
    result = run("apply", inputs["preset"], inputs["blend"])  # neither --out nor --in-place
    assert result.returncode == 2
    assert "one of the arguments --out --in-place is required" in result.stderr
    result = run("render", inputs["blend"], "--output", tmp_path / "x", "--frame", "1",
                 "--frames", "1", "2")
    assert result.returncode == 2 and "not allowed with" in result.stderr


# --- compute ---------------------------------------------------------------------------------


def test_compute_hdri_prints_the_table_and_writes_a_preset(inputs, tmp_path):
    out = tmp_path / "sky_preset.json"
    result = run("compute", inputs["hdri"], "--out", out)
    assert result.returncode == 0, result.stderr
    assert_allclose(table_row(result.stdout, "L00"), EXACT[0], atol=1e-5)  # printed to 5 places
    assert_allclose(table_row(result.stdout, "L22"), [0, 0, 0], atol=1e-5)
    assert "9-term irradiance error" in result.stdout and f"Wrote SH Lighting preset {out}" in (
        result.stdout
    )
    coeffs, metadata = read_preset(out)
    assert_allclose(coeffs, EXACT, atol=FLOAT32_TOL)
    assert metadata["source"] == os.path.basename(inputs["hdri"])  # the file name only
    assert metadata["name"] == "sky"
    # The 9-term lighting is exact for a constant sky, and so is the reference (each texel
    # integrated exactly): what is left is rounding.
    estimate = metadata["error_estimate"]
    assert 0.0 <= estimate["mean"] <= estimate["max"] < 1e-12

    before = out.read_bytes()
    again = run("compute", inputs["hdri"], "--out", out)
    assert again.returncode == 1
    assert "already exists" in again.stderr and "--overwrite" in again.stderr
    assert out.read_bytes() == before
    assert hidden_files(tmp_path) == []


def test_compute_blend_world_and_other_formats(inputs, tmp_path):
    out = tmp_path / "world.txt"
    result = run("compute", inputs["blend"], "--out", out, "--format", "filament")
    assert result.returncode == 0, result.stderr
    assert "World 'Sky'" in result.stdout
    assert_allclose(table_row(result.stdout, "L00"), EXACT[0], atol=1e-5)
    from sh_lighting.formats.interop import from_filament_sh_txt

    assert_allclose(from_filament_sh_txt(out.read_text()), EXACT, atol=FLOAT32_TOL)


def test_compute_errors_are_one_clear_line(tmp_path):
    missing = run("compute", tmp_path / "nope.exr")
    assert missing.returncode == 1
    assert missing.stderr.strip().endswith("does not exist: give an HDRI image or a .blend file")
    garbage = tmp_path / "garbage.exr"
    garbage.write_bytes(b"not an image at all")
    bad = run("compute", garbage, "--out", tmp_path / "g.json")
    assert bad.returncode == 1 and "sh_lighting: error:" in bad.stderr
    assert "Traceback" not in bad.stderr
    assert not (tmp_path / "g.json").exists() and hidden_files(tmp_path) == []


# --- apply and render ------------------------------------------------------------------------


def test_apply_saves_a_new_file_with_the_group_and_render_shows_it(inputs, tmp_path):
    out = tmp_path / "applied.blend"
    # emission only: the render below is then exactly albedo · E / π
    result = run("apply", inputs["preset"], inputs["blend"], "--out", out, "--mode", "EMISSION")
    assert result.returncode == 0, result.stderr
    assert "applied to 1 material(s): Grey" in result.stdout
    assert hidden_files(tmp_path) == []

    bpy.ops.wm.open_mainfile(filepath=str(out))
    assert materials.is_applied(bpy.data.materials["Grey"])
    assert_allclose(scene_data.get_coefficients(bpy.context.scene), EXACT, rtol=0, atol=0)
    bpy.ops.wm.open_mainfile(filepath=str(inputs["blend"]))  # the input is untouched
    assert not materials.is_applied(bpy.data.materials["Grey"])
    assert not scene_data.has_coefficients(bpy.context.scene)
    bpy.ops.wm.read_factory_settings(use_empty=True)

    renders = tmp_path / "renders"
    result = run("render", out, "--output", renders / "frame_####", "--frames", "1", "2",
                 "--engine", "CYCLES", "--samples", "1")
    assert result.returncode == 0, result.stderr
    assert f"[1/2] frame 1: {renders / 'frame_0001.exr'}" in result.stdout
    assert f"[2/2] frame 2: {renders / 'frame_0002.exr'}" in result.stdout
    assert sorted(p.name for p in renders.iterdir()) == ["frame_0001.exr", "frame_0002.exr"]
    image = bpy.data.images.load(str(renders / "frame_0002.exr"))
    assert tuple(image.size) == SIZE
    pixels = np.empty(SIZE[0] * SIZE[1] * 4, np.float32)
    image.pixels.foreach_get(pixels)
    pixels = pixels.reshape(SIZE[1], SIZE[0], 4)
    centre = pixels[SIZE[1] // 2, SIZE[0] // 2, :3]
    corner = pixels[0, 0, :3]
    assert_allclose(centre, ALBEDO * np.array(SKY), rtol=RENDER_TOL)
    assert_allclose(corner, SKY, rtol=RENDER_TOL)


def test_apply_refusals_leave_no_file(inputs, tmp_path):
    taken = tmp_path / "taken.blend"
    taken.write_bytes(b"keep")
    result = run("apply", inputs["preset"], inputs["blend"], "--out", taken)
    assert result.returncode == 1 and "already exists" in result.stderr
    assert taken.read_bytes() == b"keep"

    result = run("apply", inputs["preset"], inputs["blend"], "--out", tmp_path / "o.blend",
                 "--objects", "Ball", "Nope", "--mode", "KEEP_BSDF")
    assert result.returncode == 1 and "no object(s) 'Nope'" in result.stderr

    broken = tmp_path / "broken.json"
    broken.write_text('{"format": "sh_lighting.preset", "version": 1,')
    result = run("apply", broken, inputs["blend"], "--out", tmp_path / "o.blend")
    assert result.returncode == 1 and "not valid JSON" in result.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["broken.json", "taken.blend"]


def test_apply_in_place_and_named_objects(inputs, tmp_path):
    blend = tmp_path / "copy.blend"
    blend.write_bytes(inputs["blend"].read_bytes())
    result = run("apply", inputs["preset"], blend, "--in-place", "--objects", "Ball",
                 "--mode", "KEEP_BSDF")
    assert result.returncode == 0, result.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["copy.blend"]
    bpy.ops.wm.open_mainfile(filepath=str(blend))
    assert materials.is_applied(bpy.data.materials["Grey"])


# --- batch -----------------------------------------------------------------------------------


def test_batch_progress_resume_force_and_bad_files(tmp_path):
    hdris, out = tmp_path / "hdris", tmp_path / "presets"
    hdris.mkdir()
    write_exr(hdris / "a.exr", constant_pixels((1.0, 1.0, 1.0)))
    write_exr(hdris / "b.EXR", constant_pixels((0.5, 0.25, 2.0)))
    (hdris / "bad.exr").write_bytes(b"\x00" * 64)
    (hdris / "notes.txt").write_text("not an HDRI")

    first = run("batch", hdris, out)
    assert first.returncode == 1
    lines = first.stdout.splitlines()
    assert any(line.startswith("[1/3] a.exr: ok (") for line in lines), first.stdout
    assert any(line.startswith("[2/3] b.EXR: ok (") for line in lines), first.stdout
    assert any(line.startswith("[3/3] bad.exr: FAILED (") for line in lines), first.stdout
    assert any(line.startswith("3 file(s): 2 ok, 0 skipped, 1 failed in ") for line in lines)
    assert "bad.exr" in first.stderr
    assert sorted(p.name for p in out.iterdir()) == ["a.json", "b.json"]
    assert_allclose(read_preset(out / "b.json")[0][0],
                    2.0 * math.sqrt(math.pi) * np.array([0.5, 0.25, 2.0]), rtol=1e-6)

    stamp = (out / "a.json").stat().st_mtime_ns
    (hdris / "bad.exr").unlink()
    resumed = run("batch", hdris, out)
    assert resumed.returncode == 0, resumed.stderr
    assert "[1/2] a.exr: skipped (a.json exists; --force to redo)" in resumed.stdout
    assert "2 file(s): 0 ok, 2 skipped, 0 failed" in resumed.stdout
    assert (out / "a.json").stat().st_mtime_ns == stamp

    forced = run("batch", hdris, out, "--force", "--pattern", "a.*")
    assert forced.returncode == 0, forced.stderr
    assert "[1/1] a.exr: ok (" in forced.stdout
    assert (out / "a.json").stat().st_mtime_ns != stamp
    assert hidden_files(out) == []


# --- running the file as a script (what blender -b -P cli/script.py -- ... does) ------------


def test_script_mode_finds_the_package_or_says_what_to_install(inputs, tmp_path):
    script = ROOT / "sh_lighting" / "cli" / "script.py"
    found = run(script, "--", "compute", inputs["hdri"], cwd=tmp_path, python_args=())
    assert found.returncode == 0, found.stderr
    assert_allclose(table_row(found.stdout, "L00"), EXACT[0], atol=1e-5)

    env = {"PYTHONPATH": "", "HOME": str(tmp_path), "BLENDER_USER_RESOURCES": str(tmp_path)}
    lost = run(script, "--", "compute", inputs["hdri"], cwd=tmp_path, python_args=(),
               env_extra=env)
    assert lost.returncode == 2
    assert "cannot find the sh_lighting package" in lost.stderr


def test_package_candidates_prefer_enabled_add_ons():
    assert cli_script.candidates(
        ["cycles", "bl_ext.user_default.sh_lighting"],
        ["bl_ext.blender_org.sh_lighting", "bl_ext.user_default.sh_lighting", "io_x"],
    ) == ["bl_ext.user_default.sh_lighting", "sh_lighting", "bl_ext.blender_org.sh_lighting"]
