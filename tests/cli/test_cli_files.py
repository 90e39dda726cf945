"""The user's files under the command line: nothing lost, never an output over an
input, ``//`` paths, permissions and links kept, leftovers of a kill removed, one clear line
for every bad path. Each command runs in its own process with a temporary HOME and Blender
user folder (``cli_runs.run``)."""

import os
import stat
from pathlib import Path

import bpy
import numpy as np
import pytest
from blender_files import write_exr
from cli_runs import EXACT, SKY, constant_pixels, make_inputs, run
from numpy.testing import assert_allclose

from sh_lighting import cli
from sh_lighting.cli import render
from sh_lighting.blender import world_edit
from sh_lighting.blender.data import scene_data
from sh_lighting.formats.presets import read_preset, write_preset

pytestmark = pytest.mark.blender


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    return make_inputs(tmp_path_factory.mktemp("cli_files_inputs"))


def one_error_line(result):
    """The stderr of a failed run: exactly one line, ours, no traceback."""
    assert result.returncode == 1, (result.stdout, result.stderr)
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("sh_lighting: error: "), result.stderr
    return lines[0]


def dead_pid():
    """The pid of a process that has ended (what a killed run's temporary name holds)."""
    import subprocess
    import sys

    finished = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                              capture_output=True, text=True, check=True)
    return int(finished.stdout)


def copy(source, destination):
    destination.write_bytes(Path(source).read_bytes())
    return destination


def mode(path):
    return stat.S_IMODE(os.stat(path).st_mode)


# --- no output is ever one of the inputs ---------------------------------------------------


def test_compute_never_writes_over_its_input(inputs, tmp_path):
    victim = copy(inputs["hdri"], tmp_path / "victim.exr")
    (tmp_path / "sub").mkdir()
    before = victim.read_bytes()
    for out in (victim, tmp_path / "sub" / ".." / "victim.exr"):
        for extra in ((), ("--overwrite",)):  # refused first, --overwrite never advised
            line = one_error_line(run("compute", victim, "--out", out, *extra))
            assert f"--out '{out}' is the HDRI '{victim}' (the same file)" in line
            assert "--overwrite" not in line
    link = tmp_path / "link.exr"
    link.symlink_to(victim)
    line = one_error_line(run("compute", link, "--out", victim, "--overwrite"))
    assert "(the same file): an output never replaces an input" in line
    hard = tmp_path / "hard.exr"
    os.link(victim, hard)
    one_error_line(run("compute", hard, "--out", victim, "--overwrite"))
    assert victim.read_bytes() == before

    blend = copy(inputs["blend"], tmp_path / "world.blend")
    before = blend.read_bytes()
    line = one_error_line(run("compute", blend, "--out", blend, "--overwrite"))
    assert f"is the .blend file '{blend}'" in line
    assert blend.read_bytes() == before


def test_apply_never_writes_over_its_preset_or_blend(inputs, tmp_path):
    preset = copy(inputs["preset"], tmp_path / "P.json")
    blend = copy(inputs["blend"], tmp_path / "B.blend")
    before = preset.read_bytes(), blend.read_bytes()
    line = one_error_line(run("apply", preset, blend, "--out", preset, "--overwrite"))
    assert f"--out '{preset}' is the preset '{preset}'" in line
    line = one_error_line(run("apply", preset, blend, "--out", blend))
    assert "is the .blend file" in line and "use --in-place to replace it" in line
    assert "--overwrite" not in line
    assert (preset.read_bytes(), blend.read_bytes()) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["B.blend", "P.json"]


# --- the user's files: layout, permissions, links --------------------------------------------


def test_apply_keeps_the_users_workspaces(inputs, tmp_path):
    bpy.ops.wm.open_mainfile(filepath=str(inputs["blend"]), load_ui=True)
    bpy.data.workspaces["Layout"].name = "My Layout"
    bpy.data.batch_remove([bpy.data.workspaces["Shading"]])
    blend = tmp_path / "ui.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend), copy=True)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    out = tmp_path / "ui_sh.blend"
    result = run("apply", inputs["preset"], blend, "--out", out)
    assert result.returncode == 0, result.stderr
    bpy.ops.wm.open_mainfile(filepath=str(out), load_ui=True)
    names = {w.name for w in bpy.data.workspaces}
    assert "My Layout" in names and "Layout" not in names and "Shading" not in names
    assert world_edit.is_edited(bpy.context.scene.world)  # the default in Cycles


def test_in_place_through_a_symlink_keeps_the_link_and_the_mode(inputs, tmp_path):
    (tmp_path / "store").mkdir()
    target = copy(inputs["blend"], tmp_path / "store" / "shot.blend")
    os.chmod(target, 0o600)
    link = tmp_path / "shot.blend"
    link.symlink_to(os.path.join("store", "shot.blend"))
    result = run("apply", inputs["preset"], link, "--in-place")
    assert result.returncode == 0, result.stderr
    assert link.is_symlink() and os.readlink(link) == os.path.join("store", "shot.blend")
    assert mode(target) == 0o600
    assert sorted(p.name for p in (tmp_path / "store").iterdir()) == ["shot.blend"]
    bpy.ops.wm.open_mainfile(filepath=str(target))
    assert_allclose(scene_data.get_coefficients(bpy.context.scene), EXACT, rtol=0, atol=0)


@pytest.mark.parametrize("permissions", [0o600, 0o444])
def test_overwrite_keeps_the_mode(inputs, tmp_path, permissions):
    out = tmp_path / "p.json"
    write_preset(out, np.zeros((9, 3)))
    os.chmod(out, permissions)
    result = run("compute", inputs["hdri"], "--out", out, "--overwrite")
    assert result.returncode == 0, result.stderr
    assert mode(out) == permissions
    assert_allclose(read_preset(out)[0], EXACT, atol=1e-6)


# --- // paths ------------------------------------------------------------------------------


def test_blend_relative_paths(inputs, tmp_path):
    line = one_error_line(run("compute", inputs["hdri"], "--out", "//rel.json"))
    assert "--out '//rel.json' starts with //" in line and "there is no .blend here" in line
    assert not Path("/rel.json").exists()

    folder = tmp_path / "shots"
    folder.mkdir()
    blend = copy(inputs["blend"], folder / "shot.blend")
    copy(inputs["hdri"], folder / "sky.exr")  # the world's image, relative to the .blend
    copy(inputs["preset"], folder / "sky.json")
    result = run("compute", blend, "--out", "//from_world.json")
    assert result.returncode == 0, result.stderr
    assert_allclose(read_preset(folder / "from_world.json")[0], EXACT, atol=1e-6)
    result = run("apply", "//sky.json", blend, "--out", "//applied.blend")
    assert result.returncode == 0, result.stderr
    assert (folder / "applied.blend").is_file()


def test_export_preset_resolves_blend_relative_paths(addon, tmp_path):
    from sh_lighting import api

    scene = bpy.context.scene
    api.set_coefficients(scene, EXACT)
    with pytest.raises(ValueError, match=r"'//rel.json' is relative to the .blend file .*never "
                       "saved"):
        api.export_preset(scene, "//rel.json")
    assert not Path("/rel.json").exists()
    bpy.ops.wm.save_as_mainfile(filepath=str(tmp_path / "saved.blend"))
    path = api.export_preset(scene, "//rel.json")
    assert path == tmp_path / "rel.json"
    assert_allclose(read_preset(tmp_path / "rel.json")[0], EXACT, rtol=0, atol=0)
    assert_allclose(api.import_preset(scene, "//rel.json"), EXACT, rtol=0, atol=0)


# --- what a kill leaves is removed at the next run -------------------------------------------


def test_batch_removes_and_reports_what_a_killed_run_left(tmp_path):
    hdris, out = tmp_path / "hdris", tmp_path / "presets"
    hdris.mkdir()
    out.mkdir()
    write_exr(hdris / "a.exr", constant_pixels((1.0, 1.0, 1.0)))
    left = out / f".a.json.{dead_pid()}-0123456789ab.tmp"
    left.write_text('{"format": "sh_lig')
    user = out / ".notes.tmp"
    user.write_text("the user's own")
    result = run("batch", hdris, out)
    assert result.returncode == 0, result.stderr
    assert (f"removed 1 temporary file(s) left in {out} by an interrupted run: "
            f"{left.name}") in result.stdout
    assert sorted(p.name for p in out.iterdir()) == [".notes.tmp", "a.json"]


def test_apply_removes_what_a_killed_save_left(inputs, tmp_path):
    out = tmp_path / "new.blend"
    left = tmp_path / f".new.blend.{dead_pid()}-00ff00ff00ff.blend"
    left.write_bytes(b"BLENDER half")
    result = run("apply", inputs["preset"], inputs["blend"], "--out", out)
    assert result.returncode == 0, result.stderr
    assert f"removed {left.name}, left in {tmp_path} by an interrupted run" in result.stdout
    assert sorted(p.name for p in tmp_path.iterdir()) == ["new.blend"]


# --- batch: folders, links, outputs ----------------------------------------------------------


def test_batch_counts_and_names_what_is_not_a_file(tmp_path):
    hdris = tmp_path / "hdris"
    hdris.mkdir()
    write_exr(hdris / "a.exr", constant_pixels((1.0, 1.0, 1.0)))
    (hdris / "folder.exr").mkdir()
    (hdris / "broken.exr").symlink_to(tmp_path / "gone.exr")
    result = run("batch", hdris, tmp_path / "out")
    assert result.returncode == 1
    assert "3 file(s): 1 ok, 0 skipped, 2 failed" in result.stdout
    assert "[1/3] a.exr: ok" in result.stdout
    assert f"broken.exr: a broken symbolic link (its target '{tmp_path / 'gone.exr'}'" in (
        result.stderr)
    assert "folder.exr: a folder, not a file" in result.stderr
    assert "2 file(s) failed: broken.exr, folder.exr" in result.stderr
    assert "Traceback" not in result.stderr


def test_batch_never_replaces_an_input_with_its_preset(tmp_path):
    hdris = tmp_path / "hdris"
    hdris.mkdir()
    write_exr(hdris / "a.exr", constant_pixels((1.0, 1.0, 1.0)))
    (hdris / "a.json").write_text("the user's file")
    result = run("batch", hdris, hdris, "--pattern", "*", "--force")
    assert result.returncode == 1
    assert "a.exr: its preset a.json would replace the input a.json" in result.stderr
    assert (hdris / "a.json").read_text() == "the user's file"


def test_batch_output_folder_that_cannot_be(tmp_path):
    hdris = tmp_path / "hdris"
    hdris.mkdir()
    write_exr(hdris / "a.exr", constant_pixels((1.0, 1.0, 1.0)))
    a_file = tmp_path / "file"
    a_file.write_text("x")
    line = one_error_line(run("batch", hdris, a_file))
    assert f"OUT_DIR '{a_file}' is a file, not a folder" in line
    line = one_error_line(run("batch", hdris, a_file / "sub"))
    assert f"cannot create OUT_DIR '{a_file / 'sub'}'" in line and "a file is in the way" in line
    line = one_error_line(run("batch", a_file, tmp_path / "o"))
    assert f"HDRI folder '{a_file}' is a file, not a folder" in line


# --- render outputs ----------------------------------------------------------------------------


def test_render_outputs_that_cannot_be_written(inputs, tmp_path):
    line = one_error_line(run("render", inputs["blend"], "--output", ""))
    assert "--output is empty" in line
    a_file = tmp_path / "file"
    a_file.write_text("x")
    line = one_error_line(run("render", inputs["blend"], "--output", a_file / "f_####"))
    assert f"cannot create the folder of frame 1, '{a_file}'" in line
    assert "a file is in the way" in line
    assert a_file.read_text() == "x"


def test_render_frames_are_a_range_not_a_list():
    """--frames 1 3000000 must not build 3 million paths before frame 1: the frames are a
    range and each output path is made when its frame is rendered."""
    args = cli.build_parser().parse_args(
        ["render", "x.blend", "--output", "o", "--frames", "1", "3000000"]
    )
    frames = render.frame_range(args, None)
    assert isinstance(frames, range) and len(frames) == 3_000_000 and frames[-1] == 3_000_000


# --- messages --------------------------------------------------------------------------------


@pytest.mark.slow
def test_folders_and_missing_files_are_told_apart(inputs, tmp_path):
    folder = tmp_path / "looks.exr"
    folder.mkdir()
    line = one_error_line(run("compute", folder))
    assert f"HDRI '{folder}' is a folder, not a file" in line
    blend_folder = tmp_path / "scene.blend"
    blend_folder.mkdir()
    line = one_error_line(run("compute", blend_folder))
    assert f".blend file '{blend_folder}' is a folder, not a file" in line
    line = one_error_line(run("apply", inputs["preset"], blend_folder, "--out", tmp_path / "o"))
    assert "is a folder, not a file" in line
    line = one_error_line(run("apply", tmp_path / "absent.json", inputs["blend"],
                              "--out", tmp_path / "o.blend"))
    assert f"preset file '{tmp_path / 'absent.json'}' does not exist" in line
    assert "Errno" not in line
    line = one_error_line(run("batch", tmp_path / "nowhere", tmp_path / "o"))
    assert "does not exist" in line


def test_argument_errors_say_what_is_wrong(inputs):
    result = run("compute", inputs["hdri"], "--capture-width", "abc")
    assert result.returncode == 2
    assert "'abc' is not a positive whole number" in result.stderr
    assert "_positive" not in result.stderr


def test_nonfinite_texels_name_the_cli_option_and_it_works(tmp_path):
    pixels = constant_pixels(SKY)
    pixels[2, 3, 1] = np.nan
    hdri = write_exr(tmp_path / "nan.exr", pixels)
    line = one_error_line(run("compute", hdri))
    assert "1 non-finite (NaN or Inf) texels at (row 2, column 3)" in line
    assert "pass --nonfinite zero to treat those texels as black" in line
    assert "nonfinite='zero'" not in line
    result = run("compute", hdri, "--nonfinite", "zero", "--out", tmp_path / "nan.json")
    assert result.returncode == 0, result.stderr
    assert read_preset(tmp_path / "nan.json")[0][0, 1] < EXACT[0, 1]  # one texel black


def test_library_noise_does_not_reach_stderr(tmp_path):
    for name, data in (("truncated.exr", b"v/1\x01" + b"\x00" * 200), ("bad.png", b"\x89PNG\r\n"
                                                                          b"\x1a\n" + b"\x00" * 64)):
        path = tmp_path / name
        path.write_bytes(data)
        line = one_error_line(run("compute", path))
        assert str(path) in line


def test_hostile_presets_are_one_line_each(inputs, tmp_path):
    valid = Path(inputs["preset"]).read_text()
    deep = tmp_path / "deep.json"
    deep.write_text(valid.rstrip()[:-1] + ', "metadata": {"x": ' + "[" * 2000 + "]" * 2000
                    + "}}")
    digits = tmp_path / "digits.json"
    start = valid.index('"L00": [') + len('"L00": [')
    digits.write_text(valid[:start] + "9" * 5000 + valid[valid.index(",", start):])
    fifo = tmp_path / "fifo.json"
    os.mkfifo(fifo)
    for preset, expected in ((deep, "nested too deeply"), (digits, "cannot be read"),
                             ("/dev/zero", "is not a regular file"),
                             (fifo, "is not a regular file")):
        line = one_error_line(run("apply", preset, inputs["blend"], "--out", tmp_path / "o.blend",
                                  timeout=60))
        assert expected in line and str(preset) in line
    assert not (tmp_path / "o.blend").exists()


def test_the_error_estimate_of_a_constant_1x1_map_is_exact(tmp_path):
    """Nine terms are exact for constant light: the stored estimate is 0 (it said 28 % mean,
    75 % max when the reference sampled the one texel at its centre)."""
    hdri = write_exr(tmp_path / "one.exr", constant_pixels(SKY, height=1, width=1))
    result = run("compute", hdri, "--out", tmp_path / "one.json")
    assert result.returncode == 0, result.stderr
    coeffs, metadata = read_preset(tmp_path / "one.json")
    assert_allclose(coeffs, EXACT, atol=1e-6)
    assert metadata["error_estimate"]["max"] < 1e-12
    assert "mean 0.00 %, max 0.00 %" in result.stdout


def test_an_hdri_beyond_float32_is_refused_not_rendered_black(tmp_path):
    """1e38 texels: L00 = 2√π·1e38 = 3.5e38 would be infinite in Blender's float32."""
    hdri = write_exr(tmp_path / "huge.exr", constant_pixels((1e38, 1e38, 1e38)))
    line = one_error_line(run("compute", hdri, "--out", tmp_path / "huge.json"))
    assert "coefficient L00 channel R is 3.54491e+38, beyond the float32 range" in line
    assert not (tmp_path / "huge.json").exists()


def _gltf_specular_levels(path):
    """The decoded radiance of every specular image of a .gltf written by ``compute``."""
    import base64
    import json
    import zlib

    from sh_lighting.formats import gltf as env

    document = json.loads(Path(path).read_text())
    (light,) = document["extensions"]["EXT_lights_image_based"]["lights"]
    levels = []
    for faces in light["specularImages"]:
        decoded = []
        for index in faces:
            png = base64.b64decode(document["images"][index]["uri"].split(",", 1)[1])
            width, height = int.from_bytes(png[16:20], "big"), int.from_bytes(png[20:24], "big")
            pos, idat = 8, b""
            while pos < len(png):
                length, kind = int.from_bytes(png[pos:pos + 4], "big"), png[pos + 4:pos + 8]
                if kind == b"IDAT":
                    idat += png[pos + 8:pos + 8 + length]
                pos += 12 + length
            rows = np.frombuffer(zlib.decompress(idat), np.uint8).reshape(height, -1)
            assert (rows[:, 0] == 0).all()  # no PNG filter: the bytes are the texels
            decoded.append(env.rgbd_decode(rows[:, 1:].reshape(height, width, 4)))
        levels.append(np.stack(decoded))
    return levels


@pytest.mark.parametrize("height, width", [(1, 1), (8, 1)])
def test_gltf_export_of_a_map_one_texel_wide_lights_the_whole_cube(tmp_path, height, width):
    """Specular levels 1-3 were black on about half the cube (0/0 -> NaN
    -> 0) with a numpy RuntimeWarning, exit 0. A constant map prefilters to itself."""
    hdri = write_exr(tmp_path / "thin.exr", constant_pixels(SKY, height=height, width=width))
    out = tmp_path / "thin.gltf"
    result = run("compute", hdri, "--format", "gltf", "--out", out)
    assert result.returncode == 0, result.stderr
    assert "Warning" not in result.stderr, result.stderr
    for level, faces in enumerate(_gltf_specular_levels(out)):
        # RGBD's 8-bit steps: within 3 % of the dim channel (0.2), 0.6 % of the others
        assert_allclose(faces.reshape(-1, 3).min(axis=0), SKY, rtol=0.03, err_msg=f"{level}")
        assert_allclose(faces.reshape(-1, 3).max(axis=0), SKY, rtol=0.03, err_msg=f"{level}")


@pytest.mark.parametrize("refusal", [
    ("--pattern", "*.png"),  # no file matches
    ("--expect-files", "5"),  # the job was split for another folder
    ("--pattern", ","),  # no pattern at all
    ("--files", "3-4"),  # beyond the folder
])
def test_a_batch_refused_before_any_work_creates_no_folder(tmp_path, refusal):
    """OUT_DIR and its parents were created before the refusal."""
    hdris = tmp_path / "hdris"
    hdris.mkdir()
    write_exr(hdris / "a.exr", constant_pixels((1.0, 1.0, 1.0)))
    out = tmp_path / "new" / "deeper" / "presets"
    one_error_line(run("batch", hdris, out, *refusal))
    assert not (tmp_path / "new").exists()


def test_compute_of_a_blend_takes_nonfinite_zero_and_names_the_option(tmp_path):
    """--nonfinite was ignored for a .blend and the error said "pass
    nonfinite='zero'", which neither the command line nor the API accepted."""
    from farm_scene import build_scene

    pixels = constant_pixels(SKY)
    pixels[2, 3, 1] = np.nan
    blend = build_scene(tmp_path / "nan.blend", write_exr(tmp_path / "nan.exr", pixels), 4)
    line = one_error_line(run("compute", blend))
    assert "1 non-finite (NaN or Inf) texels at (row 2, column 3)" in line
    assert "pass --nonfinite zero to treat those texels as black" in line
    assert "nonfinite='zero'" not in line
    result = run("compute", blend, "--nonfinite", "zero", "--out", tmp_path / "nan.json")
    assert result.returncode == 0, result.stderr
    coeffs = read_preset(tmp_path / "nan.json")[0]
    assert 0.9 * EXACT[0, 1] < coeffs[0, 1] < EXACT[0, 1]  # one texel of 128 black
    assert_allclose(coeffs[0, [0, 2]], EXACT[0, [0, 2]], rtol=1e-6)


def test_compute_of_a_blend_with_lights_takes_nonfinite_zero_as_without(tmp_path):
    """``--nonfinite zero --lights 2`` on a .blend was refused ("repair the image first")
    although ``--nonfinite zero`` alone worked: the lights are taken from the same repaired
    image, as for an HDRI file."""
    from farm_scene import build_scene

    pixels = constant_pixels(SKY)
    pixels[2, 3, 1] = np.nan
    hdri = write_exr(tmp_path / "nan.exr", pixels)
    blend = build_scene(tmp_path / "nan.blend", hdri)
    line = one_error_line(run("compute", blend, "--lights", "2"))
    assert "pass --nonfinite zero to treat those texels as black" in line
    outs = []
    for source in (blend, hdri):
        out = tmp_path / f"{Path(source).suffix[1:]}.json"
        result = run("compute", source, "--nonfinite", "zero", "--lights", "2", "--out", out)
        assert result.returncode == 0, result.stderr
        assert "light(s) extracted" in result.stdout
        outs.append(read_preset(out)[0])
    assert_allclose(outs[0], outs[1], rtol=1e-5, atol=1e-7)


def test_a_truncated_exr_is_one_error_line_and_the_batch_goes_on(tmp_path):
    """The EXR reader of bpy 5.0.1 crashed the process (SIGSEGV) on an EXR cut
    short, and batch died after its first file with no summary."""
    hdris, out = tmp_path / "hdris", tmp_path / "presets"
    hdris.mkdir()
    full = Path(write_exr(tmp_path / "full.exr", constant_pixels(SKY, height=64, width=128)))
    data = full.read_bytes()
    (hdris / "a_cut.exr").write_bytes(data[:int(len(data) * 0.45)])  # inside its chunks
    write_exr(hdris / "b.exr", constant_pixels(SKY))
    result = run("batch", hdris, out)
    assert result.returncode == 1, (result.returncode, result.stdout, result.stderr)
    errors = [line for line in result.stderr.splitlines() if line]
    assert len(errors) == 2, result.stderr  # the file's line, then the total's
    assert "a_cut.exr" in errors[0] and "is damaged (chunk" in errors[0]
    assert "probably truncated" in errors[0]
    assert "[2/2] b.exr: ok" in result.stdout
    assert "2 file(s): 1 ok, 0 skipped, 1 failed" in result.stdout
    assert sorted(p.name for p in out.iterdir()) == ["b.json"]
    line = one_error_line(run("compute", hdris / "a_cut.exr"))
    assert str(hdris / "a_cut.exr") in line and "is damaged" in line


def test_apply_records_the_preset_as_the_ui_does(inputs, tmp_path):
    """The review: cli apply rebuilt import_preset without the preset's metadata, so the
    recorded name was the file's stem ("noon") where the UI records "Forest Noon"."""
    from sh_lighting import api

    preset = write_preset(tmp_path / "noon.json", EXACT, {"name": "Forest Noon"})
    out = tmp_path / "lit.blend"
    result = run("apply", preset, inputs["blend"], "--out", out)
    assert result.returncode == 0, result.stderr
    bpy.ops.wm.open_mainfile(filepath=str(out))
    try:
        cli_record = api.get_provenance(bpy.context.scene)
        bpy.ops.wm.open_mainfile(filepath=str(inputs["blend"]))
        from sh_lighting.blender.presets import preset_io

        preset_io.import_preset(bpy.context.scene, preset)  # what Load and Import call
        ui_record = api.get_provenance(bpy.context.scene)
    finally:
        bpy.ops.wm.read_factory_settings(use_empty=True)
    assert cli_record["preset"] == "Forest Noon"
    assert {k: cli_record[k] for k in ("source", "preset", "path")} == {
        k: ui_record[k] for k in ("source", "preset", "path")}


def test_a_blend_blender_cannot_open_is_said_once_in_one_line(tmp_path):
    """Our line embedded Blender's whole message ("Error: Loading ... failed:
    ...") and a blank line, and Blender printed the same message again."""
    bad = tmp_path / "bad.blend"
    bad.write_bytes(b"BLENDER-v600RENDH" + bytes(range(256)) * 8)
    result = run("compute", bad)
    line = one_error_line(result)
    assert result.stderr == line + "\n"  # no blank line after it
    assert line.startswith(f"sh_lighting: error: Blender could not open '{bad}': ")
    assert "Error:" not in line.removeprefix("sh_lighting: error:") and "Loading" not in line
    assert "Missing DNA block" in line or "Failed to read" in line
    assert "failed" not in result.stdout.lower(), result.stdout  # said once, by us


def test_a_square_image_says_how_it_was_read_and_takes_a_projection(tmp_path):
    """A square image was taken as equirect without a word."""
    square = write_exr(tmp_path / "square64.exr", constant_pixels(SKY, height=64, width=64))
    result = run("compute", square)
    assert result.returncode == 0, result.stderr
    assert f"HDRI {square} (64x64, read as equirectangular); a square image" in result.stdout
    assert "pass --projection mirror_ball" in result.stdout

    ball = run("compute", square, "--projection", "mirror_ball", "--out", tmp_path / "b.json")
    assert ball.returncode == 0, ball.stderr
    assert f"HDRI {square} (64x64, read as a mirror ball)" in ball.stdout
    coeffs, metadata = read_preset(tmp_path / "b.json")
    # a constant ball: the same constant light from every direction, to the 64-texel disk's
    # rim (measured 4.1e-3 of L00's 5.3 at worst)
    assert_allclose(coeffs, EXACT, atol=1e-3 * EXACT.max())
    assert "mirror-ball" in metadata["notes"] and "error_estimate" not in metadata

    wide = write_exr(tmp_path / "wide.exr", constant_pixels(SKY, height=8, width=16))
    plain = run("compute", wide)
    assert f"HDRI {wide} (16x8, read as equirectangular)\n" in plain.stdout  # no note
    refused = one_error_line(run("compute", square, "--projection", "mirror_ball",
                                 "--lights", "1"))
    assert "--lights takes equirectangular images only" in refused
