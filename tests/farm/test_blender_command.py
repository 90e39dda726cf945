"""``blender -c sh_lighting``: the command the extension registers with
``bpy.utils.register_cli_command``, as far as the bpy module shows it.

The bpy module has ``register_cli_command`` and ``unregister_cli_command`` but nothing that
runs a registered command (Blender's ``-c`` is handled by the program's argument parser, not
by Python), so these tests check the registration through Blender's own registry (a second
registration of the same id is refused with a warning while ours is registered; our handle
is dead after unregister) and run the callback that was registered. test_openjd.py runs it
under ``openjd run`` through the same callback, and test_real_blender.py with Blender 4.3.
"""

import math

import bpy
import numpy as np
import pytest
from blender_files import write_constant_exr
from numpy.testing import assert_allclose

import sh_lighting
from sh_lighting.formats.presets import read_preset

pytestmark = pytest.mark.blender


@pytest.fixture
def registered(monkeypatch):
    """{id: (execute, handle)} of what sh_lighting.register() registers; unregistered after."""
    found = {}
    real = bpy.utils.register_cli_command

    def recording(identifier, execute):
        handle = real(identifier, execute)
        found[identifier] = (execute, handle)
        return handle

    monkeypatch.setattr(bpy.utils, "register_cli_command", recording)
    sh_lighting.register()
    monkeypatch.undo()
    yield found
    sh_lighting.unregister()


def duplicate_warning(capfd):
    """Register "sh_lighting" once more, remove it again; Blender's warning if it was taken."""
    probe = bpy.utils.register_cli_command("sh_lighting", lambda argv: 0)
    bpy.utils.unregister_cli_command(probe)
    captured = capfd.readouterr()
    return 'registered duplicate command "sh_lighting"' in captured.out + captured.err


def test_register_adds_the_command_and_unregister_removes_it(capfd):
    real = bpy.utils.register_cli_command
    handles = []

    def recording(identifier, execute):
        handles.append(real(identifier, execute))
        return handles[-1]

    assert not duplicate_warning(capfd)
    for _ in range(3):  # enable and disable, several times
        bpy.utils.register_cli_command = recording
        try:
            sh_lighting.register()
        finally:
            bpy.utils.register_cli_command = real
        assert duplicate_warning(capfd)  # "sh_lighting" is taken: ours
        sh_lighting.unregister()
        assert not duplicate_warning(capfd)  # and free again
    assert len(handles) == 3
    for handle in handles:
        with pytest.raises(ValueError, match="already been removed"):
            bpy.utils.unregister_cli_command(handle)


def test_the_command_runs_the_command_line(registered, tmp_path, capsys):
    (name,) = registered
    assert name == "sh_lighting"
    execute, _handle = registered[name]

    assert execute(["--help"]) == 0  # argparse's exit becomes the status, no SystemExit
    assert "usage: blender -c sh_lighting [-h] COMMAND" in capsys.readouterr().out
    assert execute(["render", "--frames", "1", "2", "3"]) == 2
    assert "give frames A B, or A-B" in capsys.readouterr().err
    assert execute(["compute", str(tmp_path / "missing.exr")]) == 1
    error = capsys.readouterr().err
    assert error.startswith("sh_lighting: error: ") and error.count("\n") == 1  # one line
    assert f"'{tmp_path / 'missing.exr'}' does not exist" in error

    rgb = (0.25, 1.0, 3.0)
    hdri = write_constant_exr(tmp_path / "sky.exr", rgb)
    out = tmp_path / "sky.json"
    assert execute(["compute", hdri, "--out", str(out)]) == 0
    coeffs, _metadata = read_preset(out)
    expected = np.zeros((9, 3))
    expected[0] = 2.0 * math.sqrt(math.pi) * np.array(rgb)
    assert_allclose(coeffs, expected, rtol=1e-6, atol=1e-6)


def test_batch_chunks_see_the_whole_folder(registered, tmp_path, capsys):
    """``--files A-B`` (a farm task) names files by their place in the whole sorted list: a
    preset name taken by an earlier file fails in the chunk too, and a chunk past the end or a
    changed folder is refused before any work."""
    execute, _handle = registered["sh_lighting"]
    hdris, out = tmp_path / "hdris", tmp_path / "out"
    hdris.mkdir()
    for name in ("a.exr", "a.hdr", "b.exr"):  # a.hdr's preset would be a.json, taken by a.exr
        write_constant_exr(hdris / name, (1.0, 1.0, 1.0))
    assert execute(["batch", str(hdris), str(out), "--files", "2-3"]) == 1
    captured = capsys.readouterr()
    assert "[2/3] a.hdr: FAILED" in captured.out and "[3/3] b.exr: ok" in captured.out
    assert "sh_lighting: error: a.hdr: its preset name a.json is taken by a.exr" in captured.err
    assert sorted(p.name for p in out.iterdir()) == ["b.json"]

    assert execute(["batch", str(hdris), str(out), "--files", "3-4"]) == 1
    assert capsys.readouterr().err == (
        f"sh_lighting: error: --files 3-4: '{hdris}' holds files 1-3 matching *.exr,*.hdr\n")
    assert execute(["batch", str(hdris), str(out), "--expect-files", "2"]) == 1
    assert "holds 3 file(s) matching *.exr,*.hdr, not the 2 expected" in capsys.readouterr().err
    assert execute(["batch", str(hdris), str(out), "--files", "x"]) == 2
    assert sorted(p.name for p in out.iterdir()) == ["b.json"]
