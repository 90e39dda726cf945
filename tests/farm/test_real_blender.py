"""The real Blender program: Debian's Blender 4.3 in /opt/blender-gui-root (a chroot built by
tools/blender_gui_root.sh setup; $BLENDER_GUI_ROOT elsewhere), with the extension zip built by tools/package.py and
installed by Blender's own ``blender -b --command extension install-file``.

Run there: ``blender -c sh_lighting --help`` and ``compute`` directly, then both job bundles
under ``openjd run`` with BlenderCommand = a script that runs that Blender in the chroot,
mapping paths (the job lives in ROOT/tmp/..., which Blender sees as /tmp/...), the way a farm
maps a submitter's paths to a worker's. The scene is built by Blender 4.3 itself (4.3 refuses
a .blend saved by 5.0: "incomplete header"). Needs root and the chroot; skipped without them,
and in the 4.2 LTS suite, since it tests the same Blender 4.3 whatever bpy the suite has.
About a minute.
"""

import math
import os
import secrets
import shlex
import shutil
import subprocess
from pathlib import Path

import bpy
import numpy as np
import pytest
from blender_files import write_constant_exr
from farm_scene import SKY_COEFFICIENTS
from numpy.testing import assert_allclose
from farm_jobs import (
    MAPS, ROOT, Job, check_frame, check_preset, error_lines, frame_names, tasks, write_maps,
)

from sh_lighting.formats.presets import write_preset
from tools import package

CHROOT = Path(os.environ.get("BLENDER_GUI_ROOT", "/opt/blender-gui-root"))

pytestmark = [
    pytest.mark.blender,
    pytest.mark.slow,
    pytest.mark.skipif(
        os.geteuid() != 0 or not (CHROOT / "usr" / "bin" / "blender").is_file()
        or not (CHROOT / "proc" / "self").exists() or not (CHROOT / "dev" / "null").exists(),
        reason=f"needs root and Debian's Blender in {CHROOT}: run tools/blender_gui_root.sh "
        "setup (it builds the root and mounts its /proc and /dev)"),
    pytest.mark.skipif(bpy.app.version < (5, 0, 0),
                       reason="the Blender 4.3 test runs once, in the 5.0 suite"),
]


@pytest.fixture(scope="module")
def blender(tmp_path_factory):
    """(a folder under CHROOT/tmp, the BlenderCommand script for it) with the extension
    installed for that folder's HOME; the folder is removed afterwards."""
    folder = CHROOT / "tmp" / f"sh-farm-{secrets.token_hex(4)}"
    (folder / "home").mkdir(parents=True)
    try:
        inner = f"/{folder.relative_to(CHROOT)}"
        script = folder / "blender"
        # Arguments and the session variables that start with CHROOT lose that prefix.
        script.write_text(
            "#!/bin/sh\n"
            f"root={shlex.quote(str(CHROOT))}\n"
            'for a in "$@"; do\n'
            '  case "$a" in "$root"/*) a="${a#"$root"}" ;; esac\n'
            '  set -- "$@" "$a"; shift\n'
            "done\n"
            'TMPDIR="${TMPDIR#"$root"}" XDG_CACHE_HOME="${XDG_CACHE_HOME#"$root"}" '
            f'exec chroot "$root" /usr/bin/env -u PYTHONPATH -u PYTHONHOME '
            "-u BLENDER_USER_RESOURCES -u BLENDER_USER_CONFIG -u BLENDER_USER_SCRIPTS "
            "-u BLENDER_USER_DATAFILES -u BLENDER_USER_EXTENSIONS "
            f'HOME={shlex.quote(inner)}/home blender "$@"\n'
        )
        script.chmod(0o755)
        built = package.build(tmp_path_factory.mktemp("dist"))
        shutil.copy2(built, folder / "sh_lighting.zip")
        run = subprocess.run(
            [str(script), "-b", "--command", "extension", "install-file", "-r", "user_default",
             "-e", str(folder / "sh_lighting.zip")],
            capture_output=True, text=True, timeout=300,
        )
        assert run.returncode == 0, run.stdout + run.stderr
        assert (folder / "home/.config/blender/4.3/extensions/user_default/sh_lighting"
                "/__init__.py").is_file()
        yield folder, script
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def run_blender(script, *args):
    return subprocess.run([str(script), *map(str, args)], capture_output=True, text=True,
                          timeout=300)


def job_in(folder, name, bundle, script):
    root = folder / name
    root.mkdir()
    return Job(root, bundle, script)


def test_blender_command_in_blender_4_3(blender):
    folder, script = blender
    result = run_blender(script, "-c", "sh_lighting", "--help")
    assert result.returncode == 0, result.stderr
    assert "usage: blender -c sh_lighting [-h] COMMAND" in result.stdout
    assert run_blender(script, "--version").stdout.startswith("Blender 4.3")

    result = run_blender(script, "-c", "sh_lighting", "compute", folder / "missing.exr")
    assert result.returncode == 1
    errors = [line for line in result.stderr.splitlines() if "error" in line]
    assert len(errors) == 1 and errors[0].startswith("sh_lighting: error: ")
    # the path as Blender sees it inside the root
    assert f"'/{folder.relative_to(CHROOT)}/missing.exr' does not exist" in errors[0]

    rgb = (0.5, 1.0, 2.0)
    write_constant_exr(folder / "sky.exr", rgb)
    result = run_blender(script, "-c", "sh_lighting", "compute", folder / "sky.exr",
                         "--out", folder / "sky.json")
    assert result.returncode == 0, result.stdout + result.stderr
    check_preset(folder / "sky.json", rgb)
    expected_l00 = 2.0 * math.sqrt(math.pi) * np.array(rgb)
    row = next(line.split() for line in result.stdout.splitlines() if line.startswith("L00"))
    assert_allclose([float(v) for v in row[1:4]], expected_l00, rtol=1e-4)


def test_both_bundles_with_blender_4_3(blender):
    folder, script = blender

    job = job_in(folder, "prefilter", "prefilter", script)
    write_maps(job.inputs)
    (job.inputs / "zz_broken.hdr").write_bytes(b"#?RADIANCE\nnot really\n")
    params = job.params(HdriFolder=str(job.inputs), OutputFolder=str(job.out),
                        FileCount=len(MAPS) + 1, FilesPerTask=3)
    status, blocks = job.run(params)
    assert status != 0
    run = tasks(blocks)
    assert list(run) == ["1-3", "4-6"]
    assert run["1-3"]["exit"] == 0
    assert run["4-6"]["exit"] == 1
    errors = error_lines(run["4-6"])
    assert errors[0].startswith("sh_lighting: error: zz_broken.hdr: ")
    assert errors[-1] == "sh_lighting: error: 1 file(s) failed: zz_broken.hdr"
    assert sorted(p.name for p in job.out.iterdir()) == sorted(f"{n}.json" for n in MAPS)
    for name, rgb in MAPS.items():
        check_preset(job.out / f"{name}.json", rgb)

    job = job_in(folder, "render", "render", script)
    inner = f"/{job.inputs.relative_to(CHROOT)}"
    scene_code = ROOT / "tests" / "farm" / "farm_scene.py"
    shutil.copy2(scene_code, job.inputs / "farm_scene.py")
    made = run_blender(
        script, "-b", "--python-exit-code", "1", "--python-expr",
        f"import sys; sys.path.insert(0, {inner!r}); import farm_scene; "
        f"farm_scene.build_scene({inner + '/shot.blend'!r})",
    )
    assert made.returncode == 0, made.stdout + made.stderr
    (job.inputs / "farm_scene.py").unlink()
    preset = write_preset(job.inputs / "sky.json", SKY_COEFFICIENTS, {"name": "sky"})
    params = job.params(BlendFile=str(job.inputs / "shot.blend"), PresetFile=str(preset),
                        OutputFolder=str(job.out), Frames="1-3", FramesPerTask=2,
                        ApplyMode="EMISSION")
    status, blocks = job.run(params)
    assert status == 0, blocks
    (apply,) = [b for b in blocks if b["name"] == "ApplyPreset"]
    assert apply["exit"] == 0 and "SH lighting applied to 1 material(s): Grey" in apply["lines"]
    run = tasks(blocks)
    assert list(run) == ["1-2", "3-3"]
    assert all(block["exit"] == 0 for block in run.values())
    assert sorted(p.name for p in job.out.iterdir()) == frame_names(1, 3)
    for name in frame_names(1, 3):
        check_frame(job.out / name)
