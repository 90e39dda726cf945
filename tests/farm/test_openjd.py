"""The Open Job Description bundles in farm/openjd, run for real by ``openjd run`` (openjd-cli).

Each job is run as a farm would: ``python -m openjd run farm/openjd/<bundle>/template.yaml``
with the bundle's own parameter file (converted from the Deadline Cloud format) plus the
folders of the test. The Blender command of the bundles (job parameter BlenderCommand) is a
shell script running ``tests/farm/blender_stand_in.py``, which takes Blender's ``-c ID ARGS``
and calls the command that ``sh_lighting.register()`` registered with
``bpy.utils.register_cli_command``, in the bpy module of the Python running the tests (there
is no Blender program here; tests/farm/test_blender_command.py runs the real Blender 4.3).

Checked: every task's log (its chunk, its files or frames, its exit status) and every output
(the presets' coefficients, the frames' pixels), nothing written outside the output folder
(the inputs, HOME and TMPDIR are left as they were), a rerun that skips what is done, a bad
file failing its own task with its one-line error, and a job killed mid-task completed by a
rerun.
"""

import hashlib
import json
import math
import os
import re
import shlex
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import yaml
from blender_files import write_constant_exr
from numpy.testing import assert_allclose
from farm_scene import ALBEDO, SIZE, SKY, SKY_COEFFICIENTS, WORLD, build_scene, read_exr

from sh_lighting.core.presets import read_preset, write_preset

pytestmark = [pytest.mark.blender, pytest.mark.slow]

ROOT = Path(__file__).resolve().parents[2]
BUNDLES = ROOT / "farm" / "openjd"
FLOAT32_TOL = 1e-6  # presets of float32 EXRs
RENDER_TOL = 1e-4  # Cycles' float32 shading of the node group's polynomial
MAPS = {"a": (0.1, 0.2, 0.3), "b": (1.0, 0.5, 0.25), "C": (2.0, 2.0, 2.0),
        "d": (0.0, 0.3, 0.6), "e": (4.0, 1.0, 0.0)}  # sorted by name, any case: a b C d e


@pytest.fixture(scope="module")
def blender_command(tmp_path_factory):
    """The BlenderCommand of the tests: a script running the bpy-module stand-in."""
    path = tmp_path_factory.mktemp("bin") / "blender"
    path.write_text(
        "#!/bin/sh\n"
        f"PYTHONPATH={shlex.quote(str(ROOT))} exec {shlex.quote(sys.executable)} "
        f"{shlex.quote(str(ROOT / 'tests' / 'farm' / 'blender_stand_in.py'))} \"$@\"\n"
    )
    path.chmod(0o755)
    return path


class Job:
    """One job's folders: inputs, the output folder, HOME and TMPDIR of the run."""

    def __init__(self, root, bundle, blender_command):
        self.root, self.bundle, self.blender = root, bundle, blender_command
        self.inputs, self.out = root / "inputs", root / "out"
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
        return {**os.environ, "HOME": str(self.home), "TMPDIR": str(self.tmp)}

    def run(self, params, *extra):
        """``openjd run`` to the end; returns (exit status, the tasks' logs)."""
        process = subprocess.run(self.command(params, *extra), env=self.env(),
                                 capture_output=True, text=True, timeout=600)
        return process.returncode, parse_log(process.stdout + process.stderr)

    def snapshot(self):
        """Every file outside the output folder: its size and content hash."""
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


# --- prefilter -------------------------------------------------------------------------------


def write_maps(folder):
    for name, rgb in MAPS.items():
        write_constant_exr(folder / f"{name}.exr", rgb, width=16, height=8)


def check_preset(path, rgb):
    coeffs, metadata = read_preset(path)
    expected = np.zeros((9, 3))
    expected[0] = 2.0 * math.sqrt(math.pi) * np.array(rgb)  # a constant map: L00 only
    assert_allclose(coeffs, expected, rtol=FLOAT32_TOL, atol=FLOAT32_TOL)
    assert metadata["name"] == path.stem


def test_prefilter_bundle_every_task_then_a_rerun_skips(tmp_path, blender_command):
    job = Job(tmp_path, "prefilter", blender_command)
    write_maps(job.inputs)
    before = job.snapshot()
    params = job.params(HdriFolder=str(job.inputs), OutputFolder=str(job.out),
                        FileCount=len(MAPS), FilesPerTask=2)

    status, blocks = job.run(params)
    assert status == 0, blocks
    run = tasks(blocks)
    assert list(run) == ["1-2", "3-4", "5-5"]  # 5 files, 2 per task
    names = sorted(MAPS, key=str.lower)
    for chunk, block in run.items():
        first, last = map(int, chunk.split("-"))
        assert block["exit"] == 0, block["lines"]
        for index in range(first, last + 1):
            name = names[index - 1]
            assert any(line.startswith(f"[{index}/5] {name}.exr: ok") for line in block["lines"])
        assert f"{last - first + 1} file(s): {last - first + 1} ok, 0 skipped, 0 failed" in (
            " ".join(block["lines"]))
    assert sorted(p.name for p in job.out.iterdir()) == sorted(f"{n}.json" for n in MAPS)
    for name, rgb in MAPS.items():
        check_preset(job.out / f"{name}.json", rgb)
    job.check_nothing_outside(before)

    # A rerun finds every preset done: each task skips its files and writes nothing.
    stamps = {p.name: p.stat().st_mtime_ns for p in job.out.iterdir()}
    status, blocks = job.run(params)
    assert status == 0, blocks
    for block in tasks(blocks).values():
        assert block["exit"] == 0
        assert not any(": ok" in line for line in block["lines"] if line.startswith("["))
        assert any(": skipped" in line for line in block["lines"])
    assert {p.name: p.stat().st_mtime_ns for p in job.out.iterdir()} == stamps
    job.check_nothing_outside(before)


def test_prefilter_bad_file_fails_its_task_with_its_error(tmp_path, blender_command):
    job = Job(tmp_path, "prefilter", blender_command)
    write_maps(job.inputs)
    (job.inputs / "c_broken.exr").write_bytes(b"not an EXR at all")  # 4th: a b C c_broken d e
    before = job.snapshot()

    # Submitted for another number of files: every task refuses before any work.
    params = job.params(HdriFolder=str(job.inputs), OutputFolder=str(job.out),
                        FileCount=5, FilesPerTask=2)
    status, blocks = job.run(params)
    assert status != 0
    (block,) = tasks(blocks).values()  # openjd run stops at the first failed task
    assert block["exit"] == 1
    assert error_lines(block) == [
        f"sh_lighting: error: '{job.inputs}' holds 6 file(s) matching *.exr,*.hdr, not the 5 "
        "expected: nothing done (submit the job again for this folder)"
    ]
    assert not job.out.exists()

    params = job.params(HdriFolder=str(job.inputs), OutputFolder=str(job.out),
                        FileCount=6, FilesPerTask=2)
    status, blocks = job.run(params)
    assert status != 0
    run = tasks(blocks)
    assert list(run) == ["1-2", "3-4"]  # the session ends with the failed task
    assert run["1-2"]["exit"] == 0
    bad = run["3-4"]
    assert bad["exit"] == 1
    errors = error_lines(bad)
    assert len(errors) == 2, bad["lines"]
    assert errors[0].startswith("sh_lighting: error: c_broken.exr: ")
    assert "could not read" in errors[0]
    assert errors[1] == "sh_lighting: error: 1 file(s) failed: c_broken.exr"
    assert any(line.startswith("[3/6] C.exr: ok") for line in bad["lines"])
    assert any(line.startswith("[4/6] c_broken.exr: FAILED") for line in bad["lines"])
    # The task's good file is written, the bad one has no preset, the next chunk is not run yet.
    assert sorted(p.name for p in job.out.iterdir()) == ["C.json", "a.json", "b.json"]

    # The remaining task on its own (as another worker would run it): it succeeds.
    status, blocks = job.run(params, "--task-param", "Files=5-6")
    assert status == 0
    assert tasks(blocks)["5-6"]["exit"] == 0
    assert sorted(p.name for p in job.out.iterdir()) == sorted(f"{n}.json" for n in MAPS)
    for name, rgb in MAPS.items():
        check_preset(job.out / f"{name}.json", rgb)
    job.check_nothing_outside(before)


# --- render ----------------------------------------------------------------------------------


def kill_tree(pid):
    """SIGKILL ``pid`` and every process below it (openjd starts each action in its own
    process group), then wait until none of them runs any more."""
    parents = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue  # ended meanwhile
        parents[int(stat.parent.name)] = int(fields[1])
    tree, added = {pid}, True
    while added:
        below = {child for child, parent in parents.items() if parent in tree} - tree
        tree |= below
        added = bool(below)
    for member in tree:
        try:
            os.kill(member, signal.SIGKILL)
        except ProcessLookupError:
            pass
    for member in tree - {pid}:  # pid itself is reaped by the caller's wait()
        stat = Path(f"/proc/{member}/stat")
        while True:
            try:
                if stat.read_text().rsplit(")", 1)[1].split()[0] == "Z":
                    break
            except OSError:
                break
            time.sleep(0.005)


def render_job(tmp_path, blender_command):
    job = Job(tmp_path, "render", blender_command)
    blend = build_scene(job.inputs / "shot.blend")
    preset = write_preset(job.inputs / "sky.json", SKY_COEFFICIENTS, {"name": "sky"})
    return job, blend, preset


def check_frame(path):
    """The sphere lit by the preset's sky (not by the world), the world around it."""
    pixels = read_exr(path)
    assert pixels.shape == (SIZE[1], SIZE[0], 4)
    assert_allclose(pixels[SIZE[1] // 2, SIZE[0] // 2, :3], ALBEDO * np.array(SKY),
                    rtol=RENDER_TOL)
    assert_allclose(pixels[0, 0, :3], WORLD, rtol=RENDER_TOL)


def frame_names(first, last):
    return [f"shot_{frame:04d}.exr" for frame in range(first, last + 1)]


def test_render_bundle_every_task(tmp_path, blender_command):
    job, blend, preset = render_job(tmp_path, blender_command)
    before = job.snapshot()
    params = job.params(BlendFile=str(blend), PresetFile=str(preset),
                        OutputFolder=str(job.out), Frames="1-5", FramesPerTask=2)
    status, blocks = job.run(params)
    assert status == 0, blocks

    (apply,) = [b for b in blocks if b["name"] == "ApplyPreset"]
    assert apply["exit"] == 0
    assert "SH lighting applied to 1 material(s): Grey" in apply["lines"]
    run = tasks(blocks)
    assert list(run) == ["1-2", "3-4", "5-5"]
    for chunk, block in run.items():
        first, last = map(int, chunk.split("-"))
        assert block["exit"] == 0, block["lines"]
        for index, frame in enumerate(range(first, last + 1), start=1):
            target = job.out / f"shot_{frame:04d}.exr"
            assert any(line.startswith(f"[{index}/{last - first + 1}] frame {frame}: {target} (")
                       for line in block["lines"]), block["lines"]
    assert sorted(p.name for p in job.out.iterdir()) == frame_names(1, 5)
    for path in job.out.iterdir():
        check_frame(path)
    job.check_nothing_outside(before)  # the input .blend and preset unchanged


def test_render_rerun_after_a_killed_task_completes_the_job(tmp_path, blender_command):
    job, blend, preset = render_job(tmp_path, blender_command)
    params = job.params(BlendFile=str(blend), PresetFile=str(preset),
                        OutputFolder=str(job.out), Frames="1-20", FramesPerTask=10)
    process = subprocess.Popen(job.command(params), env=job.env(),
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 300
    try:
        while not (job.out / "shot_0002.exr").exists():
            assert process.poll() is None and time.monotonic() < deadline
            time.sleep(0.005)
    finally:
        kill_tree(process.pid)  # openjd and the task's Blender (its own process group): a dead
        process.wait()  # worker
    done = sorted(p.name for p in job.out.iterdir() if not p.name.startswith("."))
    assert frame_names(1, 2) == done[:2] and len(done) < 10, done  # killed in the first task
    for name in done:
        check_frame(job.out / name)  # what is there is whole
    stamps = {name: (job.out / name).stat().st_mtime_ns for name in done}

    status, blocks = job.run(params)
    assert status == 0, blocks
    run = tasks(blocks)
    assert list(run) == ["1-10", "11-20"]
    skipped = [line for line in run["1-10"]["lines"] if ": skipped (" in line]
    assert len(skipped) == len(done)
    assert sorted(p.name for p in job.out.iterdir() if not p.name.startswith(".")) == (
        frame_names(1, 20))
    for name in frame_names(1, 20):
        check_frame(job.out / name)
    assert {name: (job.out / name).stat().st_mtime_ns for name in done} == stamps
    # The frame being written when the kill came was a hidden temporary file, never a frame;
    # its task, run again, removed it.
    assert sorted(job.out.iterdir()) == sorted(job.out / name for name in frame_names(1, 20))
