"""Command line of SH Lighting: compute, apply, render and batch, headless.

Three ways to run it (``--help`` after any command shows its options):

* ``blender -c sh_lighting <command> ...`` (Blender 4.2+) with the extension installed and
  enabled: the command the extension registers (``blender/command.py``).

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
interrupted run never leaves a half-written output; a replaced file keeps its permissions,
a symbolic link is written through to its target, no output is ever one of the command's
inputs, and a path starting with ``//`` is relative to the .blend's folder, as in Blender):

* ``compute HDRI_OR_BLEND [--out PRESET] [--overwrite] [--capture-width N] [--format F]
  [--nonfinite raise|zero] [--filament-frame cmgen|gltf]``: the 9 coefficients of an
  equirectangular HDRI file, or of the world of a .blend (read only, not saved); prints the
  table and, with ``--out``, writes a preset (an HDRI's preset carries its 9-term error
  estimate) or a file for three.js, glTF (a .gltf environment with a specular cube from the
  image) or Filament.
* ``apply PRESET [BLEND] (--out NEW.blend | --in-place) [--objects NAME ...] [--overwrite]
  [--mode KEEP_BSDF|EMISSION] [--animation refuse|key|clear]``: sets the coefficients and
  applies the SH node group to the materials of all (or the named) objects of the scene
  (keeping their BSDF, or as emission only), then saves. Keyframed or driven coefficients
  or gains are refused by default (they would undo the preset at the next frame): ``key``
  keys the preset at the current frame, ``clear`` removes their animation. An output is required: ``--out`` (refused if it exists,
  unless ``--overwrite``; never the input itself) or ``--in-place`` (replaces the input).
* ``render [BLEND] --output PATH [--frame N | --frames A B | --frames A-B] [--engine E]
  [--samples N] [--skip-existing]``: renders frames headless; PATH follows Blender's ``-o``
  rules (``#`` → frame number, else 4 digits appended; the format's extension added). Existing
  frames are replaced, like Blender, or kept with ``--skip-existing`` (a rerun resumes).
* ``batch HDRI_DIR OUT_DIR [--force] [--pattern '*.exr,*.hdr'] [--nonfinite raise|zero]
  [--files A-B] [--expect-files N]``:
  one preset per HDRI, ``OUT_DIR/<stem>.json``, a progress line per file and a total;
  existing presets are kept unless ``--force`` (so an interrupted batch resumes; the
  temporary files a killed batch left are removed and reported); a bad file, and anything
  matching the pattern that is not a readable file (a folder, a broken link), is reported
  and the others are still processed. ``--files`` takes the A-th to B-th entry of the sorted
  list (one task of a farm job; only its own files' leftovers are removed, since other tasks
  may be writing theirs), ``--expect-files`` refuses a folder that does not hold the N
  entries the job was split for.

Exit status: 0 on success, 1 when a command (or any file of a batch) failed, 2 for wrong
arguments or when the package cannot be found. Errors go to stderr as ``sh_lighting: error:``.
"""

import argparse
import fnmatch
import importlib
import math
import os
import re
import sys
import tempfile
import time
from contextlib import contextmanager
from pathlib import Path

PROG = "python -m sh_lighting"
# Normals at which an HDRI's 9-term irradiance is compared with the exact one (a Fibonacci
# lattice): enough for a mean to ~1e-4, cheap next to loading the image.
ERROR_NORMALS = 256
DEFAULT_PATTERNS = "*.exr,*.hdr"
FORMAT_CHOICES = ("sh_lighting", "threejs", "gltf", "filament")
FILAMENT_FRAMES = ("cmgen", "gltf")  # preset_io.FILAMENT_FRAMES (its first is the default)


class CommandError(Exception):
    """A failure to report as one line on stderr (exit status 1)."""


def _package_name():
    """Name of the package this module belongs to ("sh_lighting", "bl_ext.….sh_lighting")."""
    return (__package__ or __name__).rpartition(".")[0]


def _module(name):
    """A submodule of this package, imported on first use (keeps --help free of bpy)."""
    return importlib.import_module(f"{_package_name()}.{name}")


def _print(*args, **kwargs):
    print(*args, **kwargs, flush=True)


# --- shared helpers --------------------------------------------------------------------------


@contextmanager
def library_output_captured():
    """Send what C libraries print on stderr (file descriptor 2) during the block to a
    temporary file instead of the terminal ("EXR_ERR_READ_IO", "libpng error" beside our own
    one-line message); yields a function returning that text."""
    sys.stderr.flush()
    saved = os.dup(2)
    with tempfile.TemporaryFile() as capture:
        os.dup2(capture.fileno(), 2)
        try:
            yield lambda: (capture.seek(0), capture.read().decode("utf-8", "replace"))[1]
        finally:
            sys.stderr.flush()
            os.dup2(saved, 2)
            os.close(saved)


def hdri_coefficients(path, nonfinite="raise", keep_pixels=False):
    """(coefficients (9, 3), metadata) of the equirectangular image file at ``path``; with
    ``keep_pixels``, (coefficients, metadata, pixels).

    ``nonfinite``: "raise" refuses NaN/Inf texels, "zero" treats them as black.
    """
    from datetime import date

    import numpy as np

    from ..core.coefficients import check_coefficients
    from ..core.equirect import NonFiniteError
    from ..core.irradiance import error_estimate
    from ..core.projection import project_equirect

    images = _module("blender.world.images")
    try:
        with library_output_captured():
            pixels = images.load_image_pixels(path)
        if nonfinite == "zero" and not np.isfinite(pixels[..., :3]).all():
            pixels = np.where(np.isfinite(pixels), pixels, np.float32(0.0))  # for the estimate
        coeffs = check_coefficients(project_equirect(pixels, nonfinite=nonfinite))
    except NonFiniteError as error:
        raise CommandError(
            f"{path}: the image has {error.description}: repair the image, or pass "
            "--nonfinite zero to treat those texels as black"
        ) from None
    except ValueError as error:
        raise CommandError(f"{path}: {error}") from None
    metadata = {
        "name": Path(path).stem,
        "source": Path(path).name,  # the file name only, never a local absolute path
        "mapping": [0.0, 0.0, 0.0],
        "strength": 1.0,
        "created": date.today().isoformat(),
        "notes": f"Projected exactly from the {pixels.shape[1]}x{pixels.shape[0]} image.",
    }
    estimate = error_estimate(pixels, coeffs, ERROR_NORMALS)
    if estimate is not None:
        metadata["error_estimate"] = estimate
        metadata["notes"] += (
            f" Error estimate at {ERROR_NORMALS} normals against the exact irradiance."
        )
    return (coeffs, metadata, pixels) if keep_pixels else (coeffs, metadata)


# --- paths: inputs, outputs, // and leftovers -----------------------------------------------


def input_file(path, what, hint):
    """``path`` as a Path if it is an existing regular file, else a CommandError saying what
    it is instead (missing, a folder, a broken link, a device) and ``hint``."""
    path = Path(path)
    if path.is_file():
        return path
    if path.is_dir():
        raise CommandError(f"{what} '{path}' is a folder, not a file: {hint}")
    if path.is_symlink():
        raise CommandError(f"{what} '{path}' is a broken symbolic link (its target "
                           f"'{os.readlink(path)}' does not exist): {hint}")
    if path.exists():
        raise CommandError(f"{what} '{path}' is not a regular file: {hint}")
    raise CommandError(f"{what} '{path}' does not exist: {hint}")


def open_file():
    """The path of the .blend Blender has open (under ``blender file.blend -P``), or None."""
    import bpy

    return Path(bpy.data.filepath) if bpy.data.filepath else None


def blend_relative(path, blend, flag):
    """``path`` (text) as a Path, a leading ``//`` taken relative to the folder of the .blend
    ``blend`` as Blender does; a CommandError when there is no .blend to be relative to."""
    if path is None:
        return None
    text = os.fspath(path)
    if not text.startswith("//"):
        return Path(text)
    if blend is None:
        raise CommandError(
            f"{flag} '{text}' starts with //, Blender's 'relative to the .blend file', but "
            "there is no .blend here: give the path without //"
        )
    return Path(os.path.dirname(os.path.abspath(blend))) / text[2:]


def same_file(a, b):
    """Whether paths ``a`` and ``b`` are one file (links, .., hard links: any path to it)."""
    try:
        return os.path.samefile(a, b)
    except OSError:  # one does not exist (yet): compare where they lead
        return os.path.realpath(a) == os.path.realpath(b)


def refuse_inputs(out, flag, inputs, advice="choose another name"):
    """A CommandError when ``out`` is one of ``inputs`` ({what: path}): no output ever
    replaces an input, whatever --overwrite says (checked before any other advice)."""
    for what, path in inputs.items():
        if path is not None and same_file(out, path):
            raise CommandError(
                f"{flag} '{out}' is the {what} '{path}' (the same file): an output never "
                f"replaces an input; {advice}"
            )


def check_new_file(path, overwrite, flag="--overwrite"):
    """Fail early, before any work, when ``path`` cannot be written as a new file."""
    from ..formats.atomic import real_destination

    path = Path(path)
    if path.is_dir():
        raise CommandError(f"'{path}' is a folder: give a file name")
    if path.exists() and not overwrite:
        raise CommandError(f"'{path}' already exists: choose another name, or pass {flag}")
    folder = real_destination(path).parent
    if folder.exists() and not folder.is_dir():
        raise CommandError(f"'{folder}' is a file, not a folder: '{path}' cannot be written")
    if not folder.is_dir():
        raise CommandError(f"folder '{folder}' does not exist: create it first")


def remove_own_leftovers(path):
    """Delete the temporary files a killed run left for the output ``path``; say so."""
    from ..formats.atomic import real_destination, remove_leftovers

    real = real_destination(path)
    for leftover in remove_leftovers(real.parent, real.name):
        _print(f"removed {leftover.name}, left in {leftover.parent} by an interrupted run")


def open_blend(path, load_ui=False):
    """Open the .blend at ``path`` (None: keep the file Blender has open); returns its path.

    ``load_ui``: also load its workspaces and screens (a file that is saved again keeps the
    user's layout).
    """
    import bpy

    if path is None:
        if not bpy.data.filepath:
            raise CommandError(
                "no .blend given and none is open: pass the .blend file as an argument"
            )
        return Path(bpy.data.filepath)
    path = input_file(path, ".blend file", "give a .blend file")
    try:
        bpy.ops.wm.open_mainfile(filepath=str(path), load_ui=load_ui)
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

    from ..formats.atomic import atomic_destination

    remove_own_leftovers(path)
    with atomic_destination(path, overwrite, suffix=".blend", what=".blend file",
                            hint="pass --overwrite") as temporary:
        bpy.ops.wm.save_as_mainfile(filepath=str(temporary), copy=True)
    return Path(path)


# --- commands --------------------------------------------------------------------------------


def cmd_compute(args):
    from ..core.sh import coefficient_table

    preset_io = _module("blender.presets.files")
    is_blend = args.input is None or Path(args.input).suffix.lower() == ".blend"
    if args.input is not None:
        hint = "give a .blend file" if is_blend else "give an HDRI image or a .blend file"
        source = input_file(args.input, ".blend file" if is_blend else "HDRI", hint)
    else:
        source = open_file()
    out = blend_relative(args.out, source if is_blend else open_file(), "--out")
    if out is not None:
        refuse_inputs(out, "--out", {".blend file" if is_blend else "HDRI": source})
        check_new_file(out, args.overwrite)
    start = time.perf_counter()
    if is_blend:
        api = _module("api")
        source = open_blend(args.input)
        scene = pick_scene(args.scene)
        try:
            coeffs = api.compute_from_world(scene, capture_width=args.capture_width)
        except ValueError as error:
            raise CommandError(f"{source}: {error}") from None
        metadata = preset_io.scene_metadata(scene)
        environment = preset_io.world_environment(scene) if args.format == "gltf" else None
        metadata["name"] = source.stem
        origin = metadata.get("source")
        how = f"image {origin}" if origin else "a Cycles capture"
        metadata["notes"] = f"Computed from world '{scene.world.name}' of {source.name} ({how})."
        _print(f"World '{scene.world.name}' of {source} (scene '{scene.name}', from {how})")
    else:
        coeffs, metadata, pixels = hdri_coefficients(source, args.nonfinite, keep_pixels=True)
        environment = (pixels, 1.0, None)
        scene = None
        _print(f"HDRI {source}")
    if args.lights is not None:
        coeffs = extract_lights(source, scene, args.lights, metadata,
                                getattr(args, "nonfinite", "raise"))
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
    if out is not None:
        remove_own_leftovers(out)
        try:
            path = preset_io.export_coefficients(
                coeffs, out, args.format, args.overwrite, metadata, environment,
                args.filament_frame,
            )
        except (OSError, ValueError) as error:
            raise CommandError(str(error)) from None
        _print(f"Wrote {preset_io.FORMATS[args.format][0]} {path}")
    return 0


def read_preset_argument(text, blend):
    """(path, coefficients) of the PRESET argument (``//`` relative to ``blend``)."""
    from ..formats.presets import PresetError

    path = blend_relative(text, blend, "PRESET")
    try:
        return path, _module("blender.presets.files").read_preset_file(path)[0]
    except (PresetError, OSError) as error:
        raise CommandError(str(error)) from None


def objects_to_apply(scene, names):
    """The objects named ``names`` (all of the scene's when None), or a CommandError."""
    if not names:
        return list(scene.objects)
    missing = [name for name in names if scene.objects.get(name) is None]
    if missing:
        raise CommandError(
            f"no object(s) {', '.join(map(repr, missing))} in scene '{scene.name}'"
        )
    return [scene.objects[name] for name in names]


def cmd_apply(args):
    api = _module("api")
    operators = _module("blender.ui.operators")
    if args.blend is not None:
        blend = input_file(args.blend, ".blend file", "give the .blend file to change")
    else:
        blend = open_file()
    preset, coeffs = read_preset_argument(args.preset, blend)
    out = blend if args.in_place else blend_relative(args.out, blend, "--out")
    if not args.in_place:
        refuse_inputs(out, "--out", {".blend file": blend},
                      advice="use --in-place to replace it")
        refuse_inputs(out, "--out", {"preset": preset})
        check_new_file(out, args.overwrite)
    blend = open_blend(args.blend, load_ui=True)  # saved again: keep the user's layout
    scene = pick_scene(args.scene)
    objects = objects_to_apply(scene, args.objects)
    preset_io = _module("blender.presets.files")
    provenance = preset_io.preset_provenance(preset, {})
    try:
        api.set_coefficients(scene, preset_io.from_preset_space(coeffs), provenance,
                             args.animation.upper())
    except api.AnimatedError as error:
        raise CommandError(str(error).replace("(animation='KEY', ", "(")
                           .replace("(animation='CLEAR', ", "(")) from None
    note = _module("blender.scene_data").last_note()
    if note:
        _print(f"SH lighting {note}")
    result = api.apply_to_materials(operators.materials_of(objects), scene, args.mode)
    for name, reason in result.skipped:
        _print(f"skipped material '{name}': {reason}")
    for name in operators.objects_without_material(objects):
        _print(f"skipped object '{name}': it has no material (give it one to light it)")
    if not result.changed:
        raise CommandError(
            f"no material was changed ({len(result.skipped)} skipped): nothing saved"
        )
    _print(f"SH lighting applied to {len(result.changed)} material(s): "
           + ", ".join(result.changed))
    try:
        save_blend(out, overwrite=args.in_place or args.overwrite)
    except (OSError, RuntimeError) as error:
        raise CommandError(f"could not save '{out}': {error}") from None
    _print(f"Saved {out}")
    return 0


def _frames(args, scene):
    """The frames to render, a range (never a list: --frames 1 3000000 costs nothing)."""
    if args.frame is not None:
        return range(args.frame, args.frame + 1)
    if args.frames is not None:
        first, last = args.frames
        if last < first:
            raise CommandError(f"--frames {first} {last}: the last frame comes before the first")
        return range(first, last + 1)
    return range(scene.frame_current, scene.frame_current + 1)


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


def frame_target(scene, output, frame):
    """The file frame ``frame`` of ``output`` goes to (Blender's -o rules), as a Path."""
    import bpy

    scene.render.filepath = output
    return Path(bpy.path.abspath(scene.render.frame_path(frame=frame)))


def render_frame(scene, output, frame, target, blend):
    """Render ``frame`` into ``target`` atomically; a CommandError if it cannot be written."""
    import bpy

    from ..formats.atomic import atomic_destination

    refuse_inputs(target, "--output", {".blend file": blend})
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise CommandError(
            f"cannot create the folder of frame {frame}, '{target.parent}': "
            f"{error.strerror}{' (a file is in the way)' if _file_in_way(target) else ''}"
        ) from None
    remove_own_leftovers(target)
    scene.frame_set(frame)
    try:
        with atomic_destination(target, overwrite=True, suffix=target.suffix,
                                what="render output") as temporary:
            scene.render.filepath = str(temporary)
            try:
                bpy.ops.render.render(write_still=True, scene=scene.name)
            finally:
                scene.render.filepath = output
    except (OSError, RuntimeError) as error:
        raise CommandError(f"frame {frame} could not be written: {error}") from None


def _file_in_way(path):
    """Whether a file (not a folder) stands where one of ``path``'s folders should be."""
    return any(p.exists() and not p.is_dir() for p in Path(path).parents)


def cmd_render(args):
    if not args.output.strip():
        raise CommandError("--output is empty: give a path such as renders/shot_####")
    scene_data = _module("blender.scene_data")
    blend = open_blend(args.blend)
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
    start = time.perf_counter()
    for index, frame in enumerate(frames, start=1):
        t0 = time.perf_counter()
        target = frame_target(scene, args.output, frame)
        if args.skip_existing and target.exists():
            _print(f"[{index}/{len(frames)}] frame {frame}: skipped ({target} exists)")
            continue
        render_frame(scene, args.output, frame, target, blend)
        _print(f"[{index}/{len(frames)}] frame {frame}: {target} "
               f"({time.perf_counter() - t0:.2f} s)")
    _print(f"Rendered {len(frames)} frame(s) with {scene.render.engine} in "
           f"{time.perf_counter() - start:.2f} s")
    return 0


def _kind(path):
    """What a directory entry that is not a regular file is, for a message."""
    if path.is_dir():
        return "a folder, not a file"
    if path.is_symlink() and not path.exists():
        return f"a broken symbolic link (its target '{os.readlink(path)}' does not exist)"
    return "not a regular file"


def _hdri_files(folder, patterns):
    """The entries of ``folder`` matching ``patterns`` (any case), sorted by name."""
    wanted = [p.strip().lower() for p in patterns.split(",") if p.strip()]
    if not wanted:
        raise CommandError(f"--pattern {patterns!r} holds no pattern")
    return sorted(
        (p for p in folder.iterdir()
         if any(fnmatch.fnmatchcase(p.name.lower(), w) for w in wanted)),
        key=lambda p: p.name.lower(),
    )


def batch_folders(args):
    """(HDRI folder, output folder created if need be), or a CommandError saying why not."""
    folder, out_dir = Path(args.hdri_dir), Path(args.out_dir)
    if not folder.is_dir():
        what = "is a file, not a folder" if folder.exists() else "does not exist"
        raise CommandError(f"HDRI folder '{folder}' {what}: give the folder of the HDRIs")
    if out_dir.exists() and not out_dir.is_dir():
        raise CommandError(f"OUT_DIR '{out_dir}' is a file, not a folder: give a folder")
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        in_way = " (a file is in the way)" if _file_in_way(out_dir) else ""
        raise CommandError(
            f"cannot create OUT_DIR '{out_dir}': {error.strerror}{in_way}"
        ) from None
    return folder, out_dir


def remove_batch_leftovers(out_dir):
    """Remove the temporary preset files a killed batch left in ``out_dir``; say so."""
    from ..formats.atomic import leftovers

    removed = []
    for path in leftovers(out_dir):
        if path.name.endswith(".tmp") and ".json." in path.name:
            try:
                path.unlink()
            except OSError as error:
                _print(f"could not remove {path.name}, left by an interrupted run: {error}")
                continue
            removed.append(path.name)
    if removed:
        _print(f"removed {len(removed)} temporary file(s) left in {out_dir} by an interrupted "
               f"run: {', '.join(removed)}")


def file_ids(paths):
    """{(device, inode): path} of the existing files among ``paths`` (links followed)."""
    ids = {}
    for path in paths:
        try:
            info = path.stat()
        except OSError:
            continue
        ids[info.st_dev, info.st_ino] = path
    return ids


def batch_one(path, out, args, inputs):
    """Write the preset of HDRI ``path`` to ``out``: "ok" or "skipped"; raises on failure.

    ``inputs``: ``file_ids`` of every file the batch reads (a preset never replaces one).
    """
    if not path.is_file():
        raise CommandError(_kind(path))
    try:
        info = out.stat()
        clash = inputs.get((info.st_dev, info.st_ino))
    except OSError:
        clash = None
    if clash is not None:
        raise CommandError(f"its preset {out.name} would replace the input {clash.name}")
    if out.exists() and not args.force:
        return "skipped"
    coeffs, metadata = hdri_coefficients(path, args.nonfinite)
    _module("blender.presets.files").export_coefficients(coeffs, out, "sh_lighting", True, metadata)
    return "ok"


def cmd_batch(args):
    folder, out_dir = batch_folders(args)
    files = _hdri_files(folder, args.pattern)
    if not files:
        raise CommandError(f"no file matching {args.pattern} in '{folder}'")
    if args.expect_files is not None and len(files) != args.expect_files:
        raise CommandError(
            f"'{folder}' holds {len(files)} file(s) matching {args.pattern}, not the "
            f"{args.expect_files} expected: nothing done (submit the job again for this folder)"
        )
    first, last = (1, len(files)) if args.files is None else args.files
    if not 1 <= first <= last <= len(files):
        raise CommandError(f"--files {first}-{last}: '{folder}' holds files 1-{len(files)} "
                           f"matching {args.pattern}")
    if args.files is None:
        remove_batch_leftovers(out_dir)
    else:  # one task of a farm job: other tasks may be writing their presets right now
        for path in files[first - 1:last]:
            remove_own_leftovers(out_dir / f"{path.stem}.json")
    inputs = file_ids(files)
    counts = {"ok": 0, "skipped": 0, "failed": 0}
    failed, claimed = [], {}
    for path in files[:first - 1]:  # names taken before the selection, as in a whole batch
        claimed.setdefault(f"{path.stem}.json", path.name)
    start = time.perf_counter()
    for index, path in enumerate(files[first - 1:last], start=first):
        t0 = time.perf_counter()
        out = out_dir / f"{path.stem}.json"
        prefix = f"[{index}/{len(files)}] {path.name}"
        try:
            if out.name in claimed:
                raise CommandError(f"its preset name {out.name} is taken by {claimed[out.name]}")
            claimed[out.name] = path.name
            outcome = batch_one(path, out, args, inputs)
        except (CommandError, OSError, ValueError) as error:
            counts["failed"] += 1
            failed.append(path.name)
            _print(f"{prefix}: FAILED ({time.perf_counter() - t0:.2f} s)")
            print(f"sh_lighting: error: {path.name}: {error}", file=sys.stderr, flush=True)
            continue
        counts[outcome] += 1
        if outcome == "skipped":
            _print(f"{prefix}: skipped ({out.name} exists; --force to redo)")
        else:
            _print(f"{prefix}: ok ({time.perf_counter() - t0:.2f} s)")
    _print(
        f"{last - first + 1} file(s): {counts['ok']} ok, {counts['skipped']} skipped, "
        f"{counts['failed']} failed in {time.perf_counter() - start:.2f} s"
    )
    if failed:
        raise CommandError(f"{len(failed)} file(s) failed: {', '.join(failed)}")
    return 0


# --- arguments -------------------------------------------------------------------------------


def _range(text):
    """(first, last) of "A-B" or "A", the form of an Open Job Description chunk ("1-8")."""
    match = re.fullmatch(r"(-?\d+)(?:-(-?\d+))?", text.strip())
    if match is None:
        raise argparse.ArgumentTypeError(f"{text!r} is not a range A-B or a whole number")
    return int(match[1]), int(match[2] if match[2] is not None else match[1])


class _FrameRange(argparse.Action):
    """``--frames A B`` or ``--frames A-B``, stored as (A, B)."""

    def __call__(self, parser, namespace, values, option_string=None):
        try:
            if len(values) == 1:
                value = _range(values[0])
            elif len(values) == 2:
                value = tuple(int(v) for v in values)
            else:
                raise ValueError
        except (ValueError, argparse.ArgumentTypeError):
            parser.error(f"{option_string} {' '.join(values)}: give frames A B, or A-B")
        setattr(namespace, self.dest, value)


def _positive(text):
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value <= 0:
        raise argparse.ArgumentTypeError(f"{text!r} is not a positive whole number")
    return value


def _add_nonfinite(parser):
    parser.add_argument("--nonfinite", choices=("raise", "zero"), default="raise",
                        help="NaN or infinite texels: refuse the image (raise, the default) "
                        "or treat them as black (zero)")


def _add_lights_option(parser):
    """``compute --lights K``: extract up to K lights; the coefficients hold the rest."""
    parser.add_argument(
        "--lights", type=int, metavar="K", choices=range(0, 9),
        help="take up to K (0-8) compact bright sources out of the world image as Sun lights "
        "(printed); the coefficients (and --out) then hold the rest of the world")


def extract_lights(source, scene, count, metadata, nonfinite="raise"):
    """Up to ``count`` lights out of the HDRI ``source`` (``scene`` None) or the world of the
    opened ``scene``; prints them, notes them in ``metadata``, returns the rest's (9, 3).
    ``nonfinite`` "zero": NaN/Inf texels of the HDRI count as black, as for the projection."""
    if scene is None:
        import numpy as np

        from ..core.lights import extract_lights as core_extract

        pixels = _module("blender.world.images").load_image_pixels(source)
        if nonfinite == "zero":
            pixels = np.where(np.isfinite(pixels), pixels, 0.0).astype(np.float32)
        try:
            extraction = core_extract(pixels, count)
        except ValueError as error:
            raise CommandError(f"{source}: {error}") from None
        from ..core.projection import project_equirect

        coeffs = project_equirect(extraction.rest)
        found = [(light.direction, light.angular_diameter, light.colour, light.strength,
                  light.power_fraction) for light in extraction.lights]
    else:
        try:
            info = _module("api").extract_lights(scene, count)
        except ValueError as error:
            raise CommandError(f"{source}: {error}") from None
        extraction, coeffs = info.extraction, info.coefficients
        found = [(obj.rotation_euler.to_matrix().col[2][:], obj.data.angle, obj.data.color[:],
                  obj.data.energy, light.power_fraction)
                 for obj, light in zip((scene.objects[n] for n in info.lights),
                                       extraction.lights)]
    for i, (direction, angle, colour, strength, share) in enumerate(found, 1):
        d = ", ".join(f"{v:+.4f}" for v in direction)
        c = ", ".join(f"{v:.4f}" for v in colour)
        _print(f"Light {i}: Sun toward ({d}), angle {math.degrees(angle):.2f}°, colour ({c}), "
               f"strength {strength:.6g} W/m², {100 * share:.1f} % of the light")
    (before, _), (after, _) = extraction.errors[0], extraction.errors[-1]
    _print(f"{len(found)} light(s) extracted: mean irradiance error {100 * before:.2f} % with SH "
           f"alone, {100 * after:.2f} % with SH + lights (fraction of the total light)")
    metadata["notes"] = (metadata.get("notes", "") + f" {len(found)} light(s) extracted: these "
                         "coefficients hold the rest of the world.").strip()
    metadata.pop("error_estimate", None)  # it was the whole world's
    return coeffs


APPLY_MODES = ("KEEP_BSDF", "EMISSION")  # blender.materials.MODES (this module needs no bpy)


def _add_mode_option(parser):
    """``apply --mode``: keep the BSDF (default) or drive the surface by the SH emission."""
    parser.add_argument(
        "--mode", choices=APPLY_MODES, default=APPLY_MODES[0],
        help="KEEP_BSDF (default): materials keep their BSDF (lamps, shadows, reflections) and "
        "SH replaces the world's diffuse light, which the world then no longer gives to "
        "diffuse rays (Cycles); EMISSION: the SH emission alone drives the surface")


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
                   help="file format of --out: sh_lighting (our preset JSON, the default), "
                   "threejs (a LightProbe for three.js's ObjectLoader), gltf (a .gltf "
                   "EXT_lights_image_based environment: irradiance coefficients and a "
                   "specular cube prefiltered from the image, as Babylon.js reads it), "
                   "filament (a cmgen-style sh.txt)")
    p.add_argument("--filament-frame", choices=FILAMENT_FRAMES, default=FILAMENT_FRAMES[0],
                   help="axes of --format filament: cmgen (the default) lines up with what "
                   "cmgen writes for the same equirect image (its specular KTX); gltf lines "
                   "up with a glTF export of the Blender scene. Not windowed (cmgen's "
                   "default is --sh-window=auto)")
    p.add_argument("--capture-width", type=_positive, metavar="N",
                   help="width of the Cycles capture of a procedural world (default: the "
                   "scene's setting, else 256)")
    p.add_argument("--scene", metavar="NAME", help="scene of the .blend (default: active)")
    _add_nonfinite(p)
    _add_lights_option(p)
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
    _add_mode_option(p)
    p.add_argument(
        "--animation", choices=("refuse", "key", "clear"), default="refuse",
        help="when the scene's sh_L.. coefficients or gains are keyframed or driven: refuse "
        "(default, nothing saved), key the preset's values at the scene's current frame "
        "(the rest of the animation kept; a driven one is refused), or clear their "
        "animation so that the preset renders at every frame")
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
    frames.add_argument("--frames", nargs="+", action=_FrameRange, metavar="A B | A-B",
                        help="render frames A to B inclusive (two numbers, or a range A-B)")
    p.add_argument("--engine", choices=("CYCLES", "EEVEE"),
                   help="render engine (default: the scene's)")
    p.add_argument("--samples", type=_positive, metavar="N", help="render samples")
    p.add_argument("--skip-existing", action="store_true",
                   help="keep frames whose output file exists (a rerun resumes)")
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
    p.add_argument("--files", type=_range, metavar="A-B",
                   help="only the A-th to B-th matching files, counted from 1 in the order "
                   "listed (names, any case): one task of a farm job")
    p.add_argument("--expect-files", type=_positive, metavar="N",
                   help="fail before any work unless the folder holds exactly N matching "
                   "files (the count a farm job was split for)")
    p.add_argument("--pattern", default=DEFAULT_PATTERNS, metavar="GLOBS",
                   help=f"comma-separated file name patterns, any case (default: "
                   f"{DEFAULT_PATTERNS})")
    _add_nonfinite(p)
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


def run_blender_command(argv):
    """``blender -c sh_lighting ARGS``: ``main`` on ARGS (registered by blender/command.py).

    argparse's own exits (``--help``, wrong arguments) become the return value, which Blender
    makes its exit status, instead of a SystemExit raised inside Blender's command runner.
    """
    try:
        return main(list(argv), prog="blender -c sh_lighting")
    except SystemExit as exit_:
        return exit_.code if isinstance(exit_.code, int) else 0 if exit_.code is None else 2


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
