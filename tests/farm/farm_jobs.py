"""What the farm tests share: the maps and checks of a job's outputs, and ``Job``, which runs
a bundle of farm/openjd with ``openjd run`` and reads its log."""

import hashlib
import json
import math
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import yaml
from blender_files import write_constant_exr
from farm_scene import ALBEDO, SIZE, SKY, WORLD, read_exr
from numpy.testing import assert_allclose

from sh_lighting.formats.presets import read_preset

ROOT = Path(__file__).resolve().parents[2]
BUNDLES = ROOT / "farm" / "openjd"
FLOAT32_TOL = 1e-6  # presets of float32 EXRs
RENDER_TOL = 1e-4  # Cycles' float32 shading of the node group's polynomial
MAPS = {"a": (0.1, 0.2, 0.3), "b": (1.0, 0.5, 0.25), "C": (2.0, 2.0, 2.0),
        "d": (0.0, 0.3, 0.6), "e": (4.0, 1.0, 0.0)}  # sorted by name, any case: a b C d e


class Job:
    """One job's folders: inputs, the output folder, HOME and TMPDIR of the run. The inputs'
    and output's names hold a space, non-ASCII letters and shell characters."""

    def __init__(self, root, bundle, blender_command):
        self.root, self.bundle, self.blender = root, bundle, blender_command
        self.inputs, self.out = root / "in puts ü", root / "out; 'ä' $HOME"
        self.home, self.tmp = root / "home", root / "tmp"
        for folder in (self.inputs, self.home, self.tmp):
            folder.mkdir()

    def params(self, **values):
        """The bundle's parameter file, then ``values``, as openjd's KEY: VALUE document."""
        document = yaml.safe_load((BUNDLES / self.bundle / "parameter_values.yaml").read_text())
        params = {p["name"]: p["value"] for p in document["parameterValues"]}
        params.update(BlenderCommand=str(self.blender), **values)
        path = self.root / "params.json"
        path.write_text(json.dumps(params))
        return path

    def command(self, params, *extra):
        return [sys.executable, "-m", "openjd", "run", str(BUNDLES / self.bundle / "template.yaml"),
                "--job-param", f"file://{params}", *extra]

    def env(self):
        """A worker's environment: this HOME and TMPDIR, Blender's default user folders (none
        of the test session's BLENDER_USER_* folders)."""
        env = {name: value for name, value in os.environ.items()
               if not name.startswith("BLENDER_USER_")}
        return {**env, "HOME": str(self.home), "TMPDIR": str(self.tmp)}

    def run(self, params, *extra):
        """``openjd run`` to the end; returns (exit status, the tasks' logs)."""
        process = subprocess.run(self.command(params, *extra), env=self.env(),
                                 capture_output=True, text=True, timeout=600)
        return process.returncode, parse_log(process.stdout + process.stderr)

    def snapshot(self):
        """Every file outside the output folder, with a hash of its content."""
        return {
            str(p.relative_to(self.root)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(self.root.rglob("*"))
            if p.is_file() and self.out not in p.parents and p.name != "params.json"
        }

    def check_nothing_outside(self, before):
        assert self.snapshot() == before
        assert list(self.home.iterdir()) == []  # nothing in HOME (Blender's config included)
        # openjd removed its session folders (Blender's temporary files were in them)
        assert [str(p.relative_to(self.tmp)) for p in self.tmp.rglob("*")] in ([], ["OpenJD"])


def parse_log(text):
    """The blocks of an ``openjd run`` log: [{"kind", "name", "lines", "exit"}], in order.

    A block starts at ``--------- Running Task`` (kind "task", its name the chunk of its
    CHUNK[INT] parameter, "" for a task without parameters) or at ``--------- Entering
    Environment: NAME`` (kind "environment"); "exit" is the exit status of its command.
    """
    blocks = []
    for raw in text.splitlines():
        line = raw.split("\t", 1)[-1]
        if line == "--------- Running Task":
            blocks.append({"kind": "task", "name": "", "lines": [], "exit": None})
        elif line.startswith("--------- Entering Environment: "):
            name = line.split(": ", 1)[1]
            blocks.append({"kind": "environment", "name": name, "lines": [], "exit": None})
        elif blocks:
            block = blocks[-1]
            block["lines"].append(line)
            if match := re.fullmatch(r"\w+\(CHUNK\[INT\]\) = (\S+)", line):
                block["name"] = match[1]
            if match := re.match(r"Process pid \d+ exited with code: (-?\d+)", line):
                block["exit"] = int(match[1])
    return blocks


def tasks(blocks):
    return {b["name"]: b for b in blocks if b["kind"] == "task"}


def error_lines(block):
    return [line for line in block["lines"] if line.startswith("sh_lighting: error:")]


def write_maps(folder):
    for name, rgb in MAPS.items():
        write_constant_exr(folder / f"{name}.exr", rgb, width=16, height=8)


def check_preset(path, rgb):
    coeffs, metadata = read_preset(path)
    expected = np.zeros((9, 3))
    expected[0] = 2.0 * math.sqrt(math.pi) * np.array(rgb)  # a constant map: L00 only
    assert_allclose(coeffs, expected, rtol=FLOAT32_TOL, atol=FLOAT32_TOL)
    assert metadata["name"] == path.stem


def check_frame(path):
    """The sphere lit by the preset's sky (not by the world), the world around it."""
    pixels = read_exr(path)
    assert pixels.shape == (SIZE[1], SIZE[0], 4)
    assert_allclose(pixels[SIZE[1] // 2, SIZE[0] // 2, :3], ALBEDO * np.array(SKY),
                    rtol=RENDER_TOL)
    assert_allclose(pixels[0, 0, :3], WORLD, rtol=RENDER_TOL)


def frame_names(first, last):
    return [f"shot_{frame:04d}.exr" for frame in range(first, last + 1)]
