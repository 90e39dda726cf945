"""``bake-transfer`` on the command line, in its own process: bakes, applies, saves; a
refusal is one line and leaves no file."""

import os
import signal
import subprocess
import sys
import time

import bpy
import pytest
from cli_runs import HOME, ROOT, run

import transfer_scenes as ts
from sh_lighting.blender.transfer import bake, nodes

pytestmark = pytest.mark.blender


def _blend(path, modifier=False):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    ground, box = ts.ground_and_box(2, 0)
    ts.store_lighting(bpy.context.scene)
    if modifier:
        box.modifiers.new("Bevel", "BEVEL")
    bpy.ops.wm.save_as_mainfile(filepath=str(path))
    return path


def test_bake_transfer_bakes_applies_and_saves(tmp_path):
    blend = _blend(tmp_path / "scene.blend")
    out = tmp_path / "baked.blend"
    result = run("bake-transfer", blend, "--samples", "4", "--apply", "--mode", "EMISSION",
                 "--out", out, timeout=300)
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert sum(line.startswith("Transfer L") for line in lines) == 9
    assert any(line.startswith("Baked the transfer of 2 object(s) (Ground, Box):")
               for line in lines)
    assert "Transfer applied to 1 material(s): Grey" in lines
    assert lines[-1] == f"Saved {out}"
    bpy.ops.wm.open_mainfile(filepath=str(out))
    ground = bpy.data.objects["Ground"]
    assert bake.status(bpy.context.scene, ground)[0] == "OK"
    groups = [n.node_tree.name for n in bpy.data.materials["Grey"].node_tree.nodes
              if n.bl_idname == "ShaderNodeGroup"]
    assert groups == [nodes.GROUP_NAME]


def test_bake_transfer_refusal_is_one_line_and_saves_nothing(tmp_path):
    blend = _blend(tmp_path / "scene.blend", modifier=True)
    out = tmp_path / "baked.blend"
    result = run("bake-transfer", blend, "--objects", "Ground", "Box", "--error-target", "2",
                 "--out", out, timeout=300)
    assert result.returncode == 1
    assert result.stderr.strip().splitlines() == [
        "sh_lighting: error: 'Box' has modifiers (Bevel): the transfer is stored on the mesh "
        "itself, so apply them (or disable them for renders) and bake again; nothing saved"]
    assert not out.exists()


def test_bake_transfer_of_the_whole_scene_skips_what_it_cannot_bake(tmp_path):
    blend = _blend(tmp_path / "scene.blend", modifier=True)
    out = tmp_path / "baked.blend"
    result = run("bake-transfer", blend, "--samples", "1", "--out", out, timeout=300)
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert ("skipped: 'Box' has modifiers (Bevel): the transfer is stored on the mesh itself, "
            "so apply them (or disable them for renders) and bake again") in lines
    assert any(line.startswith("Baked the transfer of 1 object(s) (Ground):") for line in lines)
    bpy.ops.wm.open_mainfile(filepath=str(out))
    assert bake.record(bpy.data.objects["Ground"]) is not None
    assert bake.record(bpy.data.objects["Box"]) is None


def test_bake_transfer_help_lists_its_options():
    result = run("bake-transfer", "--help")
    assert result.returncode == 0, result.stderr
    for word in ("BLEND", "--out", "--in-place", "--objects", "--samples", "--error-target",
                 "--apply", "--mode"):
        assert word in result.stdout
    assert "bake-transfer" in run("--help").stdout


def start(*args):
    """The command line in its own process, not waited for (its output in pipes)."""
    env = {**os.environ, "PYTHONPATH": str(ROOT), "HOME": HOME,
           "BLENDER_USER_RESOURCES": os.path.join(HOME, "blender")}
    return subprocess.Popen([sys.executable, "-m", "sh_lighting", *map(str, args)], cwd=ROOT,
                            env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


@pytest.mark.slow
@pytest.mark.parametrize("signum, in_place", [(signal.SIGINT, False), (signal.SIGTERM, True)])
def test_an_interrupted_bake_stops_at_once_one_line_and_the_file_untouched(tmp_path, signum,
                                                                           in_place):
    """Cycles' bake swallowed the KeyboardInterrupt (a traceback) and baked every remaining
    basis (17-29 s) before "interrupted"."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    ts.ground_and_box(60, 10)  # 17304 corners: 1.5 s a basis at 64 samples (load 9)
    blend = tmp_path / "scene.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend))
    before = blend.read_bytes()
    out = tmp_path / "baked.blend"
    process = start("bake-transfer", blend, "--samples", "128",
                    *(("--in-place",) if in_place else ("--out", out)))
    lines = []
    while not any(line.startswith("Transfer L00") for line in lines):
        line = process.stdout.readline()
        assert line, (lines, process.stderr.read())
        lines.append(line)
    time.sleep(0.3)  # inside the next basis' bake
    assert process.poll() is None
    sent = time.monotonic()
    process.send_signal(signum)
    stdout, stderr = process.communicate(timeout=120)
    stopped = time.monotonic() - sent
    assert process.returncode == 128 + signum, (stdout, stderr)
    assert stopped < 2.0, stopped
    ours = [line for line in stderr.splitlines() if not line.startswith("OIIO")]
    assert ours == ["sh_lighting: interrupted"], stderr
    assert "Transfer L1-1" not in stdout and "Saved" not in stdout
    assert blend.read_bytes() == before and not out.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scene.blend"]


def test_bake_transfer_per_texel_saves_the_atlas_in_the_file(tmp_path):
    blend = _blend(tmp_path / "scene.blend")
    out = tmp_path / "baked.blend"
    result = run("bake-transfer", blend, "--samples", "1", "--store", "texels", "--out", out,
                 timeout=300)
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert any(line.startswith("note: 'Box' is baked per texel (asked for): ")
               for line in lines), lines
    assert not any("Baking map saved" in line for line in lines), lines  # Cycles' chatter
    baked = [line for line in lines if line.startswith("Baked the transfer of 2 object(s)")]
    assert len(baked) == 1 and " s per million texels" in baked[0], lines
    bpy.ops.wm.open_mainfile(filepath=str(out))
    scene = bpy.context.scene
    for name in ("Ground", "Box"):
        obj = bpy.data.objects[name]
        assert bake.record(obj)["store"] == "TEXELS"
        assert bake.status(scene, obj)[0] == "OK"
    assert all(bpy.data.images[name].packed_file is not None for name in bake.IMAGE_NAMES)
