"""`python -m benchmarks.bench_commands [--max-width 16384]`: the commands as a user runs them,
timed end to end in fresh processes against Blender's own decode + readback of the same file.

For each size (1K, 4K, 8K, and 16K with ``--max-width 16384``) the benchmark map of
``bench_sizes`` (a smooth sky, noise, a sun, a window) is written as a 32-bit float ZIP
OpenEXR; then, ``REPEATS`` times in alternation, each in a fresh ``python`` process:

* baseline: ``import bpy``, ``bpy.data.images.load`` + ``Image.size`` (Blender's decode) and
  ``images.linear_pixels`` (the readback); its wall time, and inside it decode + readback;
* ``python -m sh_lighting compute MAP --out`` to each format (sh_lighting JSON, three.js,
  Filament, glTF with its specular cube), ``compute --lights 2``, and ``apply`` of the preset
  to a small .blend (a plane and a sphere; it reads no image: its time does not grow).

Each process's wall time and peak RSS (``os.wait4``'s rusage: that process's own peak). The
minimum over the repeats is reported, its ratios to decode + readback (measured inside the
baseline process) and to the baseline process's wall time (which, like a command, includes
starting Python and importing bpy). Writes benchmarks/fragments/commands.md and
benchmarks/commands.json.
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
FRAGMENT = HERE / "fragments" / "commands.md"
WIDTHS = (1024, 4096, 8192, 16384)
REPEATS = 3  # 2 at 16K (each of its processes takes about 20 s)
COMMANDS = {  # name: the arguments after ``python -m sh_lighting`` ({map}, {out}, {blend})
    "compute json": ["compute", "{map}", "--out", "{out}.json"],
    "compute threejs": ["compute", "{map}", "--out", "{out}.three.json", "--format", "threejs"],
    "compute filament": ["compute", "{map}", "--out", "{out}.txt", "--format", "filament"],
    "compute gltf": ["compute", "{map}", "--out", "{out}.gltf", "--format", "gltf"],
    "compute --lights 2": ["compute", "{map}", "--out", "{out}.lights.json", "--lights", "2"],
    "apply": ["apply", "{out}.json", "{blend}", "--out", "{out}.blend"],
}
GOALS = "compute ≤ 1.3× decode + readback (8K, 16K); peak ≤ 3× the image; gltf ≤ 1.5× compute; " \
        "--lights 2 ≤ 2× compute"


def baseline(path):
    """Blender's decode + readback of ``path`` in this (fresh) process: {decode, readback} s."""
    import bpy

    from sh_lighting.blender.world import images

    start = time.perf_counter()
    image = bpy.data.images.load(str(path), check_existing=False)
    image.size[:]  # reading the values makes Blender decode the file
    decoded = time.perf_counter()
    images.linear_pixels(image)
    return {"decode": decoded - start, "readback": time.perf_counter() - decoded}


def write_blend(path):
    """The .blend ``apply`` changes: a plane and a UV sphere, each with a Principled BSDF."""
    import bpy

    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.mesh.primitive_plane_add(size=4)
    bpy.ops.mesh.primitive_uv_sphere_add(location=(0, 0, 1))
    for obj in bpy.context.scene.objects:
        material = bpy.data.materials.new(obj.name)
        material.use_nodes = True
        obj.data.materials.append(material)
    bpy.ops.wm.save_as_mainfile(filepath=str(path))


class _Popen(subprocess.Popen):
    """A Popen that keeps its child's own rusage (``os.wait4``) when it reaps it."""

    rusage = None

    def _try_wait(self, wait_flags):
        try:
            pid, status, self.rusage = os.wait4(self.pid, wait_flags)
        except ChildProcessError:
            pid, status = self.pid, 0
        return pid, status


def timed(argv, env=None):
    """(wall seconds, peak RSS bytes, stdout) of ``argv`` run to the end in a new process."""
    start = time.perf_counter()
    process = _Popen(argv, cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                     text=True)
    out, err = process.communicate()
    seconds = time.perf_counter() - start
    if process.returncode != 0:
        raise RuntimeError(f"{argv} failed ({process.returncode}): {err.strip()}")
    return seconds, process.rusage.ru_maxrss * 1024, out


def run(max_width, folder):
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    blend = folder / "scene.blend"
    subprocess.run([sys.executable, "-m", "benchmarks.bench_commands", "--blend", str(blend)],
                   cwd=ROOT, env=env, check=True, capture_output=True)
    rows = []
    for width in (w for w in WIDTHS if w <= max_width):
        path = folder / f"sky_{width}.exr"
        subprocess.run([sys.executable, "-m", "benchmarks.bench_sizes", "--write", str(path),
                        str(width)], cwd=ROOT, env=env, check=True, capture_output=True)
        times = {}
        for repeat in range(REPEATS if width < 16384 else 2):
            seconds, rss, out = timed([sys.executable, "-m", "benchmarks.bench_commands",
                                       "--baseline", str(path)], env)
            inside = json.loads(out.strip().splitlines()[-1])
            times.setdefault("baseline", []).append(
                {"time": seconds, "rss": rss, "decode_readback": inside["decode"] +
                 inside["readback"], **inside})
            for name, args in COMMANDS.items():
                argv = [a.format(map=path, out=folder / f"out_{width}", blend=blend)
                        for a in args]
                seconds, rss, _ = timed([sys.executable, "-m", "sh_lighting", *argv,
                                         "--overwrite"], env)
                times.setdefault(name, []).append({"time": seconds, "rss": rss})
            print(f"{width}: run {repeat + 1} " + ", ".join(
                f"{n} {t[-1]['time']:.2f} s" for n, t in times.items()), flush=True)
        path.unlink()
        best = {name: min(runs, key=lambda r: r["time"]) for name, runs in times.items()}
        # each run against its own baseline (the load of a shared machine drifts): medians
        paired = {name: {
            "base": _median([r["time"] / b["time"] for r, b in zip(runs, times["baseline"])]),
            "d+r": _median([r["time"] / b["decode_readback"]
                            for r, b in zip(runs, times["baseline"])]),
            "compute": _median([r["time"] / c["time"]
                                for r, c in zip(runs, times["compute json"])]),
        } for name, runs in times.items()}
        rows.append({"width": width, "height": width // 2, "image": width * width // 2 * 16,
                     "best": best, "paired": paired, "runs": times})
    return rows


def _median(values):
    values = sorted(values)
    middle = len(values) // 2
    return values[middle] if len(values) % 2 else 0.5 * (values[middle - 1] + values[middle])


def fragment(rows, load):
    intro = textwrap.wrap(
        f"`python -m benchmarks.bench_commands` ({time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}; "
        f"load average {load}; 2 shared cores, CPU only). Each command as a user runs it "
        "(`python -m sh_lighting ...`) in a fresh process, on a 32-bit float ZIP EXR of the "
        f"size given, {REPEATS} runs (2 at 16K) in alternation with a baseline process "
        "(import bpy, Blender's decode of the same file and the readback of its pixels). Time: "
        "the minimum of each; the ratios are the medians of each run against the same run's "
        "baseline (or compute), which the machine's load, drifting, affects less. Peak: the "
        "process's own peak RSS (`os.wait4`), against the decoded image (H × W × 4 float32). "
        "d+r: decode + readback as timed inside the baseline process; base: the baseline "
        "process's wall time (it starts Python and bpy as a command does).",
        95, break_long_words=False, break_on_hyphens=False)
    lines = [
        "## Commands end to end: compute to each format, --lights 2, apply (1K-16K)", "",
        *intro, "", f"Goals: {GOALS}.", "",
        "| size | what | time s | × d+r | × base | × compute | peak MB | × image |",
        "|---|---|---|---|---|---|---|---|"]
    for row in rows:
        best, image = row["best"], row["image"]
        base = best["baseline"]
        floor, compute = base["decode_readback"], best["compute json"]["time"]
        size = f"{row['width']}×{row['height']}"
        lines.append(f"| {size} | baseline (d+r {floor:.2f} s) | {base['time']:.2f} | "
                     f"{base['time'] / floor:.2f} | 1.00 | | {base['rss'] / 2**20:.0f} | "
                     f"{base['rss'] / image:.2f} |")
        for name in COMMANDS:
            r, q = best[name], row["paired"][name]
            lines.append(f"| {size} | {name} | {r['time']:.2f} | {q['d+r']:.2f} | "
                         f"{q['base']:.2f} | {q['compute']:.2f} | "
                         f"{r['rss'] / 2**20:.0f} | {r['rss'] / image:.2f} |")
    lines += ["", "What it means:", ""]
    for row in rows:
        best, image, q = row["best"], row["image"], row["paired"]
        compute = best["compute json"]
        lines.append(
            f"- {row['width']}×{row['height']}: compute {compute['time']:.2f} s = "
            f"{q['compute json']['d+r']:.2f}× decode + readback "
            f"({q['compute json']['base']:.2f}× the baseline process), peak "
            f"{compute['rss'] / image:.2f}× the image; gltf "
            f"{q['compute gltf']['compute']:.2f}× compute; --lights 2 "
            f"{q['compute --lights 2']['compute']:.2f}× compute.")
    return "\n".join(lines) + "\n"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--max-width", type=int, default=8192,
                        help="largest map width (16384: the 16K maps, about 3 GB per process)")
    parser.add_argument("--baseline", metavar="FILE", help=argparse.SUPPRESS)
    parser.add_argument("--blend", metavar="FILE", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.baseline:
        print(json.dumps(baseline(Path(args.baseline))))
        return
    if args.blend:
        write_blend(Path(args.blend))
        return
    load = ", ".join(f"{v:.1f}" for v in os.getloadavg())
    with tempfile.TemporaryDirectory(prefix="sh_bench_commands_") as folder:
        rows = run(args.max_width, Path(folder))
    load = f"{load} at the start, " + ", ".join(f"{v:.1f}" for v in os.getloadavg()) + " at the end"
    text = fragment(rows, load)
    FRAGMENT.parent.mkdir(exist_ok=True)
    FRAGMENT.write_text(text, encoding="utf-8")
    (HERE / "commands.json").write_text(json.dumps(rows, indent=1), encoding="utf-8")
    print(text)


if __name__ == "__main__":
    main()
