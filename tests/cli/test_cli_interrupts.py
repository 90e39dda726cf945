"""Interrupted and concurrent runs of the command line: Ctrl+C or
SIGTERM at any moment exits non-zero and leaves the .blend as it was; two ``apply --in-place``
on one file never break each other."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from cli_runs import HOME, ROOT, hidden_files, make_inputs

pytestmark = pytest.mark.blender


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    return make_inputs(tmp_path_factory.mktemp("cli_interrupt_inputs"))


def start(*args):
    """The command line started in its own process (not waited for)."""
    env = {**os.environ, "PYTHONPATH": str(ROOT), "HOME": HOME,
           "BLENDER_USER_RESOURCES": os.path.join(HOME, "blender")}
    return subprocess.Popen([sys.executable, "-m", "sh_lighting", *map(str, args)], cwd=ROOT,
                            env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


@pytest.fixture(scope="module")
def apply_seconds(inputs, tmp_path_factory):
    """How long an uninterrupted ``apply --in-place`` takes here (the faster of two runs): the
    signals are sent at fractions of it, so that they land during bpy's start and the work on
    a fast machine as on a loaded one (a fixed 0.9 s came after the save on an idle machine)."""
    folder = tmp_path_factory.mktemp("cli_interrupt_timing")
    times = []
    for _ in range(2):
        blend = folder / "shot.blend"
        blend.write_bytes(Path(inputs["blend"]).read_bytes())
        begin = time.monotonic()
        process = start("apply", inputs["preset"], blend, "--in-place")
        stdout, stderr = process.communicate(timeout=120)
        assert process.returncode == 0, (stdout, stderr)
        times.append(time.monotonic() - begin)
    return min(times)


@pytest.mark.parametrize("signum, fraction", [
    (signal.SIGINT, 0.1), (signal.SIGINT, 0.25), (signal.SIGINT, 0.4), (signal.SIGINT, 0.55),
    (signal.SIGTERM, 0.3),
])
def test_an_early_interrupt_of_apply_in_place_changes_nothing(inputs, tmp_path, apply_seconds,
                                                              signum, fraction):
    """Early in the run is during bpy's start: the signal was swallowed, the .blend replaced,
    exit 0."""
    blend = tmp_path / "shot.blend"
    blend.write_bytes(Path(inputs["blend"]).read_bytes())
    before = blend.read_bytes()
    process = start("apply", inputs["preset"], blend, "--in-place")
    time.sleep(fraction * apply_seconds)
    assert process.poll() is None, "the command ended before the signal: nothing tested"
    process.send_signal(signum)
    stdout, stderr = process.communicate(timeout=120)
    assert process.returncode == 128 + signum, (process.returncode, stdout, stderr)
    assert "sh_lighting: interrupted" in stderr and "Traceback" not in stderr, stderr
    assert "Saved" not in stdout
    assert blend.read_bytes() == before
    assert hidden_files(tmp_path) == []


def dead_pid():
    """The pid of a process that has ended."""
    finished = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                              capture_output=True, text=True, check=True)
    return int(finished.stdout)


def test_apply_in_place_refuses_a_blend_another_run_is_changing(inputs, tmp_path):
    """A second apply --in-place on the same file went ahead (and its
    leftover cleanup deleted the first run's in-flight .blend@)."""
    import fcntl

    blend = tmp_path / "shot.blend"
    blend.write_bytes(Path(inputs["blend"]).read_bytes())
    before = blend.read_bytes()
    with open(blend, "rb") as held:
        fcntl.flock(held, fcntl.LOCK_EX | fcntl.LOCK_NB)  # what a running apply holds
        result = subprocess.run(
            [sys.executable, "-m", "sh_lighting", "apply", str(inputs["preset"]), str(blend),
             "--in-place"], cwd=ROOT, capture_output=True, text=True, timeout=120,
            env={**os.environ, "PYTHONPATH": str(ROOT), "HOME": HOME})
    assert result.returncode == 1, (result.stdout, result.stderr)
    (line,) = result.stderr.strip().splitlines()
    assert line == (f"sh_lighting: error: .blend file '{blend}' is being changed by another "
                    "sh_lighting run: wait for it to end, then run again")
    assert blend.read_bytes() == before and hidden_files(tmp_path) == []


def test_leftover_cleanup_takes_only_files_whose_writer_is_gone(inputs, tmp_path):
    out = tmp_path / "new.blend"
    alive = tmp_path / f".new.blend.{os.getpid()}-00ff00ff00ff.blend@"  # in flight (this pid)
    gone = tmp_path / f".new.blend.{dead_pid()}-0123456789ab.blend@"  # its writer was killed
    for path in (alive, gone):
        path.write_bytes(b"BLENDER half")
    result = subprocess.run(
        [sys.executable, "-m", "sh_lighting", "apply", str(inputs["preset"]), str(inputs["blend"]),
         "--out", str(out)], cwd=ROOT, capture_output=True, text=True, timeout=120,
        env={**os.environ, "PYTHONPATH": str(ROOT), "HOME": HOME})
    assert result.returncode == 0, result.stderr
    assert f"removed {gone.name}, left in {tmp_path} by an interrupted run" in result.stdout
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([alive.name, "new.blend"])


def test_two_apply_in_place_at_once_never_break_each_other(inputs, tmp_path):
    blend = tmp_path / "shot.blend"
    blend.write_bytes(Path(inputs["blend"]).read_bytes())
    runs = [start("apply", inputs["preset"], blend, "--in-place") for _ in range(2)]
    results = [(p.returncode, *p.communicate(timeout=180)) for p in runs]
    results = [(p.returncode, out, err) for p, (_, out, err) in zip(runs, results)]
    codes = sorted(code for code, _, _ in results)
    assert codes in ([0, 0], [0, 1]), results
    for code, stdout, stderr in results:
        assert "Cannot change old file" not in stderr + stdout
        if code == 1:
            assert "is being changed by another sh_lighting run" in stderr, stderr
    assert hidden_files(tmp_path) == []
    import bpy

    from sh_lighting.blender.data import scene_data

    bpy.ops.wm.open_mainfile(filepath=str(blend))
    assert scene_data.has_coefficients(bpy.context.scene)
    bpy.ops.wm.read_factory_settings(use_empty=True)
