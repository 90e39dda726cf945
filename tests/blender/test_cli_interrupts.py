"""Interrupted and concurrent runs of the command line (issue 20 items 3 and 20): Ctrl+C or
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


@pytest.mark.parametrize("signum, delay", [
    (signal.SIGINT, 0.15), (signal.SIGINT, 0.3), (signal.SIGINT, 0.5), (signal.SIGINT, 0.9),
    (signal.SIGTERM, 0.4),
])
def test_an_early_interrupt_of_apply_in_place_changes_nothing(inputs, tmp_path, signum, delay):
    """0.15-0.9 s is during bpy's start: the signal was swallowed, the .blend replaced, exit 0."""
    blend = tmp_path / "shot.blend"
    blend.write_bytes(Path(inputs["blend"]).read_bytes())
    before = blend.read_bytes()
    process = start("apply", inputs["preset"], blend, "--in-place")
    time.sleep(delay)
    assert process.poll() is None, "the command ended before the signal: nothing tested"
    process.send_signal(signum)
    stdout, stderr = process.communicate(timeout=120)
    assert process.returncode == 128 + signum, (process.returncode, stdout, stderr)
    assert "sh_lighting: interrupted" in stderr and "Traceback" not in stderr, stderr
    assert "Saved" not in stdout
    assert blend.read_bytes() == before
    assert hidden_files(tmp_path) == []
