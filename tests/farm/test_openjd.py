"""The Open Job Description bundles in farm/openjd, run for real by ``openjd run`` (openjd-cli).

Each job runs as a farm would, with the bundle's own parameter file; its Blender command is
``tests/farm/blender_stand_in.py`` on the bpy module (tests/farm/test_real_blender.py runs the
real Blender). Checked: every task's log and output (the presets' coefficients, the frames'
pixels), nothing written outside the output folder, a rerun that skips what is done, a bad file
failing its own task with one line, and a job killed mid-task completed by a rerun.
"""

import os
import shlex
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from farm_jobs import (
    MAPS, ROOT, Job, check_frame, check_preset, error_lines, frame_names, tasks, write_maps,
)
from farm_scene import SKY, SKY_COEFFICIENTS, build_scene, read_exr
from numpy.testing import assert_allclose

from sh_lighting.formats.presets import write_preset

pytestmark = [pytest.mark.blender, pytest.mark.slow]


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


# --- prefilter -------------------------------------------------------------------------------


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
    assert not job.out.exists()  # refused before any work: not even the folder (item 24)

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


def test_render_bundle_every_task(tmp_path, blender_command):
    job, blend, preset = render_job(tmp_path, blender_command)
    before = job.snapshot()
    params = job.params(BlendFile=str(blend), PresetFile=str(preset),
                        OutputFolder=str(job.out), Frames="1-5", FramesPerTask=2,
                        ApplyMode="EMISSION")
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


def test_render_bundle_default_mode_edits_the_world_in_cycles(tmp_path, blender_command):
    """The bundle's own ApplyMode (AUTO, apply's default): the Cycles shot gets Edit World, its
    world the preset's sky (the preset has no coefficients of the world: they replace it)."""
    job, blend, preset = render_job(tmp_path, blender_command)
    params = job.params(BlendFile=str(blend), PresetFile=str(preset),
                        OutputFolder=str(job.out), Frames="1-1", FramesPerTask=1)
    status, blocks = job.run(params)
    assert status == 0, blocks
    (apply,) = [b for b in blocks if b["name"] == "ApplyPreset"]
    assert apply["exit"] == 0
    assert any(line.startswith("Edit World: world 'Plain' edited") for line in apply["lines"])
    (task,) = tasks(blocks).values()
    assert task["exit"] == 0, task["lines"]
    pixels = read_exr(job.out / "shot_0001.exr")
    assert_allclose(pixels[0, 0, :3], SKY, rtol=1e-4)  # not farm_scene.WORLD


def test_render_output_name_cannot_leave_the_output_folder(tmp_path, blender_command):
    """OutputName=../escaped wrote its frames beside OutputFolder, exit 0."""
    job, blend, preset = render_job(tmp_path, blender_command)
    before = job.snapshot()
    params = job.params(BlendFile=str(blend), PresetFile=str(preset),
                        OutputFolder=str(job.out), Frames="1-1", FramesPerTask=1,
                        OutputName="../escaped", ApplyMode="EMISSION")
    status, blocks = job.run(params)
    assert status != 0
    (task,) = tasks(blocks).values()
    assert task["exit"] == 1
    (line,) = error_lines(task)
    assert "is outside --output-folder" in line and str(job.out) in line, line
    job.check_nothing_outside(before)


# A worker that keeps the processes it orphans unreaped until told: it makes itself their
# "child subreaper" (prctl PR_SET_CHILD_SUBREAPER), starts the command, prints its pid, and
# reaps nothing until its stdin closes. What a loaded machine does for a second or more (the
# killed Blender a zombie, its pid still answering kill(pid, 0)), made to last the whole rerun.
HOLDER = """
import ctypes, os, subprocess, sys
ctypes.CDLL(None, use_errno=True).prctl(36, 1, 0, 0, 0)  # PR_SET_CHILD_SUBREAPER
child = subprocess.Popen(sys.argv[1:], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
print(child.pid, flush=True)
sys.stdin.read()
while True:
    try:
        os.wait()
    except ChildProcessError:
        break
"""

BUSY = "import time\nend = time.monotonic() + 600\nwhile time.monotonic() < end: pass\n"


def zombies_below(pid):
    """The pids of zombie processes whose parent is ``pid``."""
    found = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if fields[0] == "Z" and int(fields[1]) == pid:
            found.append(int(stat.parent.name))
    return found


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs Linux's /proc")
def test_render_rerun_after_a_killed_task_completes_the_job(tmp_path, blender_command):
    # The kill comes while frame 4 is a hidden temporary file (the stand-in Blender stops
    # there). The machine is loaded on purpose (a busy process per core), and the killed
    # processes stay unreaped zombies until the rerun has ended, as a loaded machine can leave
    # them for seconds (their pids still answer kill(pid, 0)).
    job, blend, preset = render_job(tmp_path, blender_command)
    params = job.params(BlendFile=str(blend), PresetFile=str(preset),
                        OutputFolder=str(job.out), Frames="1-40", FramesPerTask=20,
                        ApplyMode="EMISSION")
    busy = [subprocess.Popen([sys.executable, "-c", BUSY]) for _ in range(os.cpu_count() or 2)]
    holder = subprocess.Popen([sys.executable, "-c", HOLDER, *job.command(params)],
                              env={**job.env(), "BLENDER_STAND_IN_STALL_AFTER_FRAME": "3"},
                              stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    try:
        worker = int(holder.stdout.readline())
        deadline = time.monotonic() + 300
        try:  # frame 4 written to its temporary file, not yet moved into place
            while not list(job.out.glob(".shot_0004.exr.*-*.exr")):
                assert holder.poll() is None and time.monotonic() < deadline
                time.sleep(0.005)
        finally:
            kill_tree(worker)  # openjd and the task's Blender (its own process group): a dead
        done = sorted(p.name for p in job.out.iterdir() if not p.name.startswith("."))
        assert done == frame_names(1, 3), done  # killed in the first task, writing frame 4
        for name in done:
            check_frame(job.out / name)  # what is there is whole
        stamps = {name: (job.out / name).stat().st_mtime_ns for name in done}
        assert zombies_below(holder.pid)  # the killed processes, not reaped

        status, blocks = job.run(params)
        assert status == 0, blocks
        assert zombies_below(holder.pid)  # still not reaped while the rerun ran
    finally:
        holder.communicate("", timeout=60)  # reaps them
        for process in busy:
            process.kill()
            process.wait()
    run = tasks(blocks)
    assert list(run) == ["1-20", "21-40"]
    skipped = [line for line in run["1-20"]["lines"] if ": skipped (" in line]
    assert len(skipped) == len(done)
    assert sorted(p.name for p in job.out.iterdir() if not p.name.startswith(".")) == (
        frame_names(1, 40))
    for name in frame_names(1, 40):
        check_frame(job.out / name)
    assert {name: (job.out / name).stat().st_mtime_ns for name in done} == stamps
    # The frame being written when the kill came was a hidden temporary file, never a frame;
    # its task, run again, removed it although its writer's pid still answered.
    assert sorted(job.out.iterdir()) == sorted(job.out / name for name in frame_names(1, 40))
