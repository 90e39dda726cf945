"""Command line of SH Lighting: compute, apply, render and batch, headless.

Two ways to run it (``--help`` after any command shows its options):

* ``python -m sh_lighting <command> ...`` with a Python where ``bpy`` (Blender as a module) and
  this package are importable, e.g. ``.venv/bin/python -m sh_lighting`` from the repository.
* ``blender -b [FILE.blend] -P /path/to/sh_lighting/cli.py -- <command> ...``: Blender runs
  this file as a plain script (no package), so it first finds the package: an enabled add-on
  or extension whose module is ``sh_lighting`` or ends in ``.sh_lighting``
  (``bl_ext.user_default.sh_lighting``), else ``import sh_lighting`` (a folder on
  PYTHONPATH), else an installed but disabled extension; without any it stops with a message
  saying what to install. The arguments are those after ``--``. With a .blend already opened
  by Blender, the BLEND argument of ``compute``, ``apply`` and ``render`` may be left out.
  Add ``--python-exit-code 1`` so that an unexpected Python error also fails the process.

Commands (all write their files atomically: a temporary file moved into place, so an
interrupted run never leaves a half-written output):

* ``compute HDRI_OR_BLEND [--out PRESET] [--overwrite] [--capture-width N] [--format F]``:
  the 9 coefficients of an equirectangular HDRI file, or of the world of a .blend (read only,
  not saved); prints the table and, with ``--out``, writes a preset (an HDRI's preset carries
  its 9-term error estimate).
* ``apply PRESET [BLEND] (--out NEW.blend | --in-place) [--objects NAME ...] [--overwrite]``:
  sets the coefficients and applies the SH node group to the materials of all (or the named)
  objects of the scene, then saves. An output is required: ``--out`` (refused if it exists,
  unless ``--overwrite``; never the input itself) or ``--in-place`` (replaces the input).
* ``render [BLEND] --output PATH [--frame N | --frames A B] [--engine E] [--samples N]``:
  renders frames headless; PATH follows Blender's ``-o`` rules (``#`` → frame number, else 4
  digits appended; the format's extension added). Existing frames are replaced, like Blender.
* ``batch HDRI_DIR OUT_DIR [--force] [--pattern '*.exr,*.hdr']``: one preset per HDRI,
  ``OUT_DIR/<stem>.json``, a progress line per file and a total; existing presets are kept
  unless ``--force`` (so an interrupted batch resumes); a bad file is reported and the others
  are still processed.

Exit status: 0 on success, 1 when a command (or any file of a batch) failed, 2 for wrong
arguments or when the package cannot be found. Errors go to stderr as ``sh_lighting: error:``.
"""

import argparse
import fnmatch
import importlib
import os
import sys
import time
from pathlib import Path

PROG = "python -m sh_lighting"
# Normals at which an HDRI's 9-term irradiance is compared with the exact one (a Fibonacci
# lattice): enough for a mean to ~1e-4, cheap next to loading the image.
ERROR_NORMALS = 256
DEFAULT_PATTERNS = "*.exr,*.hdr"
FORMAT_CHOICES = ("sh_lighting", "threejs", "gltf", "filament")


class CommandError(Exception):
    """A failure to report as one line on stderr (exit status 1)."""


def _package_name():
    """Name of the package this module belongs to ("sh_lighting", "bl_ext.….sh_lighting")."""
    return __package__ or __name__.rpartition(".")[0]


def _module(name):
    """A submodule of this package, imported on first use (keeps --help free of bpy)."""
    return importlib.import_module(f"{_package_name()}.{name}")


def _print(*args, **kwargs):
    print(*args, **kwargs, flush=True)


# --- shared helpers --------------------------------------------------------------------------


def coefficient_table(coeffs):
    """The lines of the coefficient table: name, R, G, B and what the coefficient does."""
    from .core.sh import COEFFICIENT_NAMES

    phrases = _module("blender.properties").COEFFICIENT_PHRASES
    lines = [f"{'':5} {'R':>11} {'G':>11} {'B':>11}   what it does"]
    for name, rgb, phrase in zip(COEFFICIENT_NAMES, coeffs, phrases):
        lines.append(f"{name:5} {rgb[0]:11.5f} {rgb[1]:11.5f} {rgb[2]:11.5f}   {phrase}")
    return lines


def error_estimate(pixels, coeffs, count=ERROR_NORMALS):
    """{"mean", "max"} 9-term irradiance error / total power ∫L dω, or None (no power).

    The paper's measure (``core.irradiance.relative_error``): |E9 − E| at ``count`` normals
    (``spread_normals``), divided per channel by the channel's power 2√π L00; mean is the worst
    channel's mean, max the largest over normals and channels.
    """
    from .core.irradiance import irradiance, reference_irradiance, relative_error, total_power
    from .core.sh import spread_normals

    power = total_power(coeffs)
    if not (power > 0.0).all():
        return None
    normals = spread_normals(count)
    mean, largest = relative_error(
        irradiance(coeffs, normals), reference_irradiance(pixels, normals), power
    )
    return {"mean": mean, "max": largest}


def hdri_coefficients(path):
    """(coefficients (9, 3), metadata) of the equirectangular image file at ``path``."""
    from datetime import date

    from .core.coefficients import check_coefficients
    from .core.projection import project_equirect

    images = _module("blender.images")
    try:
        pixels = images.load_image_pixels(path)
        coeffs = check_coefficients(project_equirect(pixels))  # within what Blender renders
    except ValueError as error:
        raise CommandError(f"{path}: {error}") from None
    metadata = {
        "name": Path(path).stem,
        "source": str(Path(path).resolve()),
        "mapping": [0.0, 0.0, 0.0],
        "strength": 1.0,
        "created": date.today().isoformat(),
        "notes": f"Projected exactly from the {pixels.shape[1]}x{pixels.shape[0]} image.",
    }
    estimate = error_estimate(pixels, coeffs)
    if estimate is not None:
        metadata["error_estimate"] = estimate
        metadata["notes"] += (
            f" Error estimate at {ERROR_NORMALS} normals against the exact irradiance."
        )
    return coeffs, metadata


def _check_new_file(path, overwrite, flag="--overwrite"):
    """Fail early, before any work, when ``path`` exists or its folder is missing."""
    path = Path(path)
    if path.is_dir():
        raise CommandError(f"'{path}' is a folder: give a file name")
    if path.exists() and not overwrite:
        raise CommandError(f"'{path}' already exists: choose another name, or pass {flag}")
    if not path.parent.is_dir():
        raise CommandError(f"folder '{path.parent}' does not exist: create it first")


def open_blend(path):
    """Open the .blend at ``path`` (None: keep the file Blender has open); returns its path."""
    import bpy

    if path is None:
        if not bpy.data.filepath:
            raise CommandError(
                "no .blend given and none is open: pass the .blend file as an argument"
            )
        return Path(bpy.data.filepath)
    path = Path(path)
    if not path.is_file():
        raise CommandError(f".blend file '{path}' does not exist")
    try:
        bpy.ops.wm.open_mainfile(filepath=str(path), load_ui=False)
    except RuntimeError as error:
        raise CommandError(f"Blender could not open '{path}': {error}") from None
    return path


def pick_scene(name):
    """The scene called ``name``, or the file's active scene."""
    import bpy

    if name is None:
        scene = bpy.context.scene
        if scene is None:
            raise CommandError("the file has no scene")
        return scene
    scene = bpy.data.scenes.get(name)
    if scene is None:
        names = ", ".join(s.name for s in bpy.data.scenes)
        raise CommandError(f"no scene '{name}' in the file (scenes: {names})")
    return scene


def save_blend(path, overwrite):
    """Save the open file as ``path`` atomically (a copy: the session keeps its file path)."""
    import bpy

    from .core.atomic import atomic_destination

    with atomic_destination(path, overwrite, suffix=".blend", what=".blend file",
                            hint="pass --overwrite") as temporary:
        bpy.ops.wm.save_as_mainfile(filepath=str(temporary), copy=True)
    return Path(path)


# --- commands --------------------------------------------------------------------------------


def cmd_compute(args):
    preset_io = _module("blender.preset_io")
    if args.out is not None:
        _check_new_file(args.out, args.overwrite)
    start = time.perf_counter()
    if args.input is None or Path(args.input).suffix.lower() == ".blend":
        api = _module("api")
        source = open_blend(args.input)
        scene = pick_scene(args.scene)
        try:
            coeffs = api.compute_from_world(scene, capture_width=args.capture_width)
        except ValueError as error:
            raise CommandError(f"{source}: {error}") from None
        metadata = preset_io.scene_metadata(scene)
        metadata["name"] = source.stem
        origin = metadata.get("source")
        how = f"image {origin}" if origin else "a Cycles capture"
        metadata["notes"] = f"Computed from world '{scene.world.name}' of {source.name} ({how})."
        _print(f"World '{scene.world.name}' of {source} (scene '{scene.name}', from {how})")
    else:
        source = Path(args.input)
        if not source.is_file():
            raise CommandError(f"'{source}' does not exist: give an HDRI image or a .blend file")
        coeffs, metadata = hdri_coefficients(source)
        _print(f"HDRI {source}")
    elapsed = time.perf_counter() - start
    _print("Lighting coefficients L_lm (raw radiance, Blender world axes, z up):")
    for line in coefficient_table(coeffs):
        _print(line)
    estimate = metadata.get("error_estimate")
    if estimate is not None:
        _print(
            f"9-term irradiance error (fraction of the total light, {ERROR_NORMALS} normals): "
            f"mean {100 * estimate['mean']:.2f} %, max {100 * estimate['max']:.2f} %"
        )
    _print(f"Computed in {elapsed:.2f} s")
    if args.out is not None:
        try:
            path = preset_io.export_coefficients(
                coeffs, args.out, args.format, args.overwrite, metadata
            )
        except (OSError, ValueError) as error:
            raise CommandError(str(error)) from None
        _print(f"Wrote {args.format} preset {path}")
    return 0


def cmd_apply(args):
    from .core.presets import PresetError

    api = _module("api")
    preset_io = _module("blender.preset_io")
    operators = _module("blender.operators")
    try:
        coeffs, _metadata = preset_io.read_preset_file(args.preset)
    except (PresetError, OSError) as error:
        raise CommandError(str(error)) from None
    if args.out is not None:
        _check_new_file(args.out, args.overwrite)
    blend = open_blend(args.blend)
    if args.out is not None and Path(args.out).exists() and os.path.samefile(blend, args.out):
        raise CommandError("--out is the input file: use --in-place to replace it")
    scene = pick_scene(args.scene)
    if args.objects:
        missing = [name for name in args.objects if scene.objects.get(name) is None]
        if missing:
            raise CommandError(
                f"no object(s) {', '.join(map(repr, missing))} in scene '{scene.name}'"
            )
        objects = [scene.objects[name] for name in args.objects]
    else:
        objects = list(scene.objects)
    api.set_coefficients(scene, coeffs)
    result = api.apply_to_materials(operators.materials_of(objects), scene)
    for name, reason in result.skipped:
        _print(f"skipped material '{name}': {reason}")
    if not result.changed:
        raise CommandError(
            f"no material was changed ({len(result.skipped)} skipped): nothing saved"
        )
    _print(f"SH lighting applied to {len(result.changed)} material(s): "
           + ", ".join(result.changed))
    out = blend if args.in_place else Path(args.out)
    try:
        save_blend(out, overwrite=args.in_place or args.overwrite)
    except (OSError, RuntimeError) as error:
        raise CommandError(f"could not save '{out}': {error}") from None
    _print(f"Saved {out}")
    return 0


def _frames(args, scene):
    if args.frame is not None:
        return [args.frame]
    if args.frames is not None:
        first, last = args.frames
        if last < first:
            raise CommandError(f"--frames {first} {last}: the last frame comes before the first")
        return list(range(first, last + 1))
    return [scene.frame_current]


def _set_engine(scene, engine, samples):
    compat = _module("blender.compat")
    if engine is not None:
        scene.render.engine = "CYCLES" if engine == "CYCLES" else compat.eevee_engine_id()
    if samples is not None:
        if scene.render.engine == "CYCLES":
            scene.cycles.samples = samples
        elif scene.render.engine == compat.eevee_engine_id():
            scene.eevee.taa_render_samples = samples
        else:
            raise CommandError(f"--samples does not apply to engine {scene.render.engine}")


def cmd_render(args):
    import bpy

    from .core.atomic import atomic_destination

    scene_data = _module("blender.scene_data")
    open_blend(args.blend)
    scene = pick_scene(args.scene)
    _set_engine(scene, args.engine, args.samples)
    frames = _frames(args, scene)
    if scene.render.is_movie_format:
        raise CommandError(
            f"scene '{scene.name}' writes a movie ({scene.render.image_settings.file_format}): "
            "set an image format (PNG, OpenEXR, ...) and encode the frames afterwards"
        )
    if not scene_data.has_coefficients(scene):
        _print(f"warning: scene '{scene.name}' has no SH coefficients: it renders without them")
    render = scene.render
    render.filepath = args.output
    targets = [Path(bpy.path.abspath(render.frame_path(frame=f))) for f in frames]
    start = time.perf_counter()
    for index, (frame, target) in enumerate(zip(frames, targets), start=1):
        t0 = time.perf_counter()
        target.parent.mkdir(parents=True, exist_ok=True)
        scene.frame_set(frame)
        with atomic_destination(target, overwrite=True, suffix=target.suffix,
                                what="render output") as temporary:
            render.filepath = str(temporary)
            try:
                bpy.ops.render.render(write_still=True, scene=scene.name)
            finally:
                render.filepath = args.output
        _print(f"[{index}/{len(frames)}] frame {frame}: {target} "
               f"({time.perf_counter() - t0:.2f} s)")
    _print(f"Rendered {len(frames)} frame(s) with {render.engine} in "
           f"{time.perf_counter() - start:.2f} s")
    return 0


def _hdri_files(folder, patterns):
    wanted = [p.strip().lower() for p in patterns.split(",") if p.strip()]
    if not wanted:
        raise CommandError(f"--pattern {patterns!r} holds no pattern")
    return sorted(
        (p for p in folder.iterdir()
         if p.is_file() and any(fnmatch.fnmatchcase(p.name.lower(), w) for w in wanted)),
        key=lambda p: p.name.lower(),
    )


def cmd_batch(args):
    preset_io = _module("blender.preset_io")
    folder, out_dir = Path(args.hdri_dir), Path(args.out_dir)
    if not folder.is_dir():
        raise CommandError(f"HDRI folder '{folder}' does not exist")
    files = _hdri_files(folder, args.pattern)
    if not files:
        raise CommandError(f"no file matching {args.pattern} in '{folder}'")
    out_dir.mkdir(parents=True, exist_ok=True)
    counts = {"ok": 0, "skipped": 0, "failed": 0}
    failed, claimed = [], {}
    start = time.perf_counter()
    for index, path in enumerate(files, start=1):
        t0 = time.perf_counter()
        out = out_dir / f"{path.stem}.json"
        prefix = f"[{index}/{len(files)}] {path.name}"
        try:
            if out.name in claimed:
                raise CommandError(f"its preset name {out.name} is taken by {claimed[out.name]}")
            claimed[out.name] = path.name
            if out.exists() and not args.force:
                counts["skipped"] += 1
                _print(f"{prefix}: skipped ({out.name} exists; --force to redo)")
                continue
            coeffs, metadata = hdri_coefficients(path)
            preset_io.export_coefficients(coeffs, out, "sh_lighting", True, metadata)
        except (CommandError, OSError, ValueError) as error:
            counts["failed"] += 1
            failed.append(path.name)
            _print(f"{prefix}: FAILED ({time.perf_counter() - t0:.2f} s)")
            print(f"sh_lighting: error: {path.name}: {error}", file=sys.stderr, flush=True)
            continue
        counts["ok"] += 1
        _print(f"{prefix}: ok ({time.perf_counter() - t0:.2f} s)")
    _print(
        f"{len(files)} file(s): {counts['ok']} ok, {counts['skipped']} skipped, "
        f"{counts['failed']} failed in {time.perf_counter() - start:.2f} s"
    )
    if failed:
        raise CommandError(f"{len(failed)} file(s) failed: {', '.join(failed)}")
    return 0


# --- arguments -------------------------------------------------------------------------------


def _positive(text):
    value = int(text)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"{text} is not a positive whole number")
    return value


def build_parser(prog=PROG):
    parser = argparse.ArgumentParser(
        prog=prog,
        description="SH Lighting: 9 spherical-harmonic lighting coefficients (Ramamoorthi and "
        "Hanrahan 2001) from HDRIs and .blend worlds, applied and rendered headless.",
        epilog="Run '<command> --help' for the options of a command.",
    )
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    raw = argparse.RawDescriptionHelpFormatter

    p = commands.add_parser(
        "compute", formatter_class=raw,
        help="coefficients of an HDRI or of a .blend's world; print them, write a preset",
        description="Project an equirectangular HDRI (EXR, HDR, any image Blender reads), or "
        "the world of a .blend (read only, the file is not saved), onto the 9 lighting "
        "coefficients L_lm; print them and optionally write a preset.",
        epilog=f"example:\n  {prog} compute forest.exr --out forest.json",
    )
    p.add_argument("input", metavar="HDRI_OR_BLEND", nargs="?",
                   help="equirectangular image file, or a .blend file (its scene's world); "
                   "under blender -P it defaults to the open .blend")
    p.add_argument("--out", metavar="PRESET", help="write the coefficients to this file")
    p.add_argument("--overwrite", action="store_true", help="replace an existing --out file")
    p.add_argument("--format", choices=FORMAT_CHOICES, default="sh_lighting",
                   help="file format of --out (default: sh_lighting preset JSON)")
    p.add_argument("--capture-width", type=_positive, metavar="N",
                   help="width of the Cycles capture of a procedural world (default: the "
                   "scene's setting, else 256)")
    p.add_argument("--scene", metavar="NAME", help="scene of the .blend (default: active)")
    p.set_defaults(run=cmd_compute)

    p = commands.add_parser(
        "apply", formatter_class=raw,
        help="set a preset in a .blend and apply the SH node group to its materials",
        description="Set the scene's coefficients from PRESET and add the SH Irradiance node "
        "group to the materials of all objects of the scene (or of --objects), then save to "
        "--out (a new file) or over the input with --in-place.",
        epilog=f"example:\n  {prog} apply forest.json shot.blend --out shot_sh.blend",
    )
    p.add_argument("preset", metavar="PRESET", help="SH Lighting preset (.json)")
    p.add_argument("blend", metavar="BLEND", nargs="?",
                   help=".blend file to change (under blender -P: default the open one)")
    where = p.add_mutually_exclusive_group(required=True)
    where.add_argument("--out", metavar="NEW.blend", help="save the result to this new file")
    where.add_argument("--in-place", action="store_true", help="replace the input .blend")
    p.add_argument("--overwrite", action="store_true", help="replace an existing --out file")
    p.add_argument("--objects", nargs="+", metavar="NAME",
                   help="only the materials of these objects (default: every object)")
    p.add_argument("--scene", metavar="NAME", help="scene to change (default: active)")
    p.set_defaults(run=cmd_apply)

    p = commands.add_parser(
        "render", formatter_class=raw,
        help="render a .blend (frames or a range) headless",
        description="Render the .blend's scene to --output, one frame or a range. The output "
        "follows Blender's -o rules: '#' characters become the frame number (else 4 digits "
        "are appended) and the extension of the scene's file format is added. Each frame is "
        "written to a temporary file and moved into place; existing frames are replaced.",
        epilog=f"example:\n  {prog} render shot_sh.blend --output renders/shot_#### "
        "--frames 1 24 --engine CYCLES --samples 64",
    )
    p.add_argument("blend", metavar="BLEND", nargs="?",
                   help=".blend file to render (under blender -P: default the open one)")
    p.add_argument("--output", required=True, metavar="PATH",
                   help="output path pattern (absolute, relative, or // for the .blend's folder)")
    frames = p.add_mutually_exclusive_group()
    frames.add_argument("--frame", type=int, metavar="N", help="render frame N only")
    frames.add_argument("--frames", type=int, nargs=2, metavar=("A", "B"),
                        help="render frames A to B inclusive")
    p.add_argument("--engine", choices=("CYCLES", "EEVEE"),
                   help="render engine (default: the scene's)")
    p.add_argument("--samples", type=_positive, metavar="N", help="render samples")
    p.add_argument("--scene", metavar="NAME", help="scene to render (default: active)")
    p.set_defaults(run=cmd_render)

    p = commands.add_parser(
        "batch", formatter_class=raw,
        help="one preset per HDRI of a folder; resumable",
        description="Write OUT_DIR/<stem>.json for every HDRI of HDRI_DIR matching --pattern, "
        "with a progress line per file and a total. Existing presets are kept (an interrupted "
        "batch resumes) unless --force; a file that fails is reported and the others are "
        "still processed; the exit status is 1 if any failed.",
        epilog=f"example:\n  {prog} batch ~/hdris presets/ --pattern '*.exr,*.hdr'",
    )
    p.add_argument("hdri_dir", metavar="HDRI_DIR", help="folder of equirectangular HDRIs")
    p.add_argument("out_dir", metavar="OUT_DIR", help="folder of the presets (created)")
    p.add_argument("--force", action="store_true", help="recompute presets that exist")
    p.add_argument("--pattern", default=DEFAULT_PATTERNS, metavar="GLOBS",
                   help=f"comma-separated file name patterns, any case (default: "
                   f"{DEFAULT_PATTERNS})")
    p.set_defaults(run=cmd_batch)
    return parser


def main(argv=None, prog=PROG):
    """Run one command; returns the exit status (0 ok, 1 failed, 2 wrong arguments)."""
    parser = build_parser(prog)
    args = parser.parse_args(sys.argv[1:] if argv is None else argv)
    try:
        return args.run(args)
    except CommandError as error:
        print(f"sh_lighting: error: {error}", file=sys.stderr, flush=True)
        return 1
    except KeyboardInterrupt:
        print("sh_lighting: interrupted", file=sys.stderr, flush=True)
        return 130


# --- run as a script (blender -b -P cli.py -- ...) -------------------------------------------


def _candidates(enabled, importable):
    """Package names to try, in order: enabled add-ons, a plain import, installed ones."""
    ours = [n for n in enabled if n == "sh_lighting" or n.endswith(".sh_lighting")]
    ours.append("sh_lighting")
    ours += [n for n in importable if n.endswith(".sh_lighting") and n not in ours]
    return ours


def find_package():
    """The name of an importable sh_lighting package whose ``cli`` module loads."""
    enabled, installed = [], []
    try:
        import addon_utils
        import bpy

        enabled = list(bpy.context.preferences.addons.keys())
        installed = [module.__name__ for module in addon_utils.modules()]
    except Exception:  # noqa: BLE001 - not inside Blender: only the plain import is tried
        pass
    for name in _candidates(enabled, installed):
        try:
            importlib.import_module(f"{name}.cli")
        except ImportError:
            continue
        return name
    raise ImportError(
        "cannot find the sh_lighting package: install and enable the SH Lighting extension "
        "(Preferences > Get Extensions > Install from Disk), or put the folder that contains "
        "sh_lighting/ on PYTHONPATH"
    )


def _run_as_script():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    try:
        name = find_package()
    except ImportError as error:
        print(f"sh_lighting: error: {error}", file=sys.stderr, flush=True)
        return 2
    cli = importlib.import_module(f"{name}.cli")
    return cli.main(argv, prog="blender -b [FILE.blend] -P cli.py --")


if __name__ == "__main__":
    sys.exit(main() if __package__ else _run_as_script())
