"""Shared by the command-line tests: running ``python -m sh_lighting`` in a fresh process with
a temporary HOME and Blender user folder, and the tiny inputs (a constant-colour EXR, a .blend
with a grey sphere lit by it, ``farm_scene``'s, and the exact preset).
"""

import atexit
import math
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from blender_files import write_exr
from farm_scene import ALBEDO, SIZE, SKY, build_scene  # noqa: F401 (the tests' constants)

from sh_lighting.formats.presets import write_preset

ROOT = Path(__file__).resolve().parents[1]
EXACT = np.zeros((9, 3))
EXACT[0] = 2.0 * math.sqrt(math.pi) * np.array(SKY)
HOME = tempfile.mkdtemp(prefix="sh_lighting_test_home_")
atexit.register(shutil.rmtree, HOME, ignore_errors=True)


def run(*args, cwd=ROOT, env_extra=None, python_args=("-m", "sh_lighting"), timeout=120):
    """Run the command line in a fresh process; returns the CompletedProcess.

    HOME and Blender's user folder are a temporary folder: nothing touches the real ones.
    """
    env = {**os.environ, "PYTHONPATH": str(ROOT), "HOME": HOME,
           "BLENDER_USER_RESOURCES": os.path.join(HOME, "blender"), **(env_extra or {})}
    env.pop("BLENDER_USER_SCRIPTS", None)
    env.pop("BLENDER_USER_CONFIG", None)
    return subprocess.run(
        [sys.executable, *python_args, *map(str, args)],
        cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout,
    )




def constant_pixels(rgb, height=8, width=16):
    pixels = np.ones((height, width, 4), dtype=np.float32)
    pixels[..., :3] = rgb
    return pixels


def table_row(stdout, name):
    """The R, G, B numbers printed for coefficient ``name``."""
    for line in stdout.splitlines():
        parts = line.split()
        if parts and parts[0] == name:
            return [float(v) for v in parts[1:4]]
    raise AssertionError(f"no {name} row in:\n{stdout}")


def hidden_files(folder):
    return [p.name for p in Path(folder).iterdir() if p.name.startswith(".")]


def make_inputs(folder):
    """{"hdri", "blend", "preset"}: the constant sky as an EXR, a scene lit by it, its preset."""
    folder = Path(folder)
    hdri = Path(write_exr(folder / "sky.exr", constant_pixels(SKY)))
    blend = build_scene(folder / "scene.blend", hdri, samples=4)
    preset = write_preset(folder / "sky.json", EXACT, {"name": "sky"})
    return {"hdri": hdri, "blend": blend, "preset": preset}
