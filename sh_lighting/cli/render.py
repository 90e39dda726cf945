"""``render [BLEND] --output PATH``: frames rendered headless, each written atomically."""

import os
import time
from pathlib import Path

from ..formats.atomic import atomic_destination
from . import interrupts
from .options import FrameRange, add_scene, positive
from .paths import file_in_way, refuse_inputs, remove_own_leftovers
from .report import CommandError, say
from .session import open_blend, pick_scene

HELP = "render a .blend (frames or a range) headless"


def add_arguments(p, prog):
    p.description = (
        "Render the .blend's scene to --output, one frame or a range. The output follows "
        "Blender's -o rules: '#' characters become the frame number (else 4 digits are "
        "appended) and the extension of the scene's file format is added. Each frame is "
        "written to a temporary file and moved into place; existing frames are replaced.")
    p.epilog = (f"example:\n  {prog} render shot_sh.blend --output renders/shot_#### "
                "--frames 1 24 --engine CYCLES --samples 64")
    p.add_argument("blend", metavar="BLEND", nargs="?",
                   help=".blend file to render (under blender -P: default the open one)")
    p.add_argument("--output", required=True, metavar="PATH",
                   help="output path pattern (absolute, relative, or // for the .blend's folder)")
    frames = p.add_mutually_exclusive_group()
    frames.add_argument("--frame", type=int, metavar="N", help="render frame N only")
    frames.add_argument("--frames", nargs="+", action=FrameRange, metavar="A B | A-B",
                        help="render frames A to B inclusive (two numbers, or a range A-B)")
    p.add_argument("--engine", choices=("CYCLES", "EEVEE"),
                   help="render engine (default: the scene's)")
    p.add_argument("--samples", type=positive, metavar="N", help="render samples")
    p.add_argument("--output-folder", metavar="DIR",
                   help="refuse, before any render, frames that --output would put outside "
                   "DIR ('..', a link): a farm job's output folder")
    p.add_argument("--skip-existing", action="store_true",
                   help="keep frames whose output file exists (a rerun resumes)")
    add_scene(p, "scene to render")


def run(args):
    from .. import api

    if not args.output.strip():
        raise CommandError("--output is empty: give a path such as renders/shot_####")
    blend = open_blend(args.blend)
    scene = pick_scene(args.scene)
    set_engine(scene, args.engine, args.samples)
    frames = frame_range(args, scene)
    if scene.render.is_movie_format:
        raise CommandError(
            f"scene '{scene.name}' writes a movie ({scene.render.image_settings.file_format}): "
            "set an image format (PNG, OpenEXR, ...) and encode the frames afterwards"
        )
    if not api.has_coefficients(scene):
        say(f"warning: scene '{scene.name}' has no SH coefficients: it renders without them")
    if args.output_folder is not None:
        for frame in {frames[0], frames[-1]}:
            check_inside(frame_target(scene, args.output, frame), args.output_folder, frame)
    start = time.perf_counter()
    for index, frame in enumerate(frames, start=1):
        t0 = time.perf_counter()
        target = frame_target(scene, args.output, frame)
        if args.output_folder is not None:
            check_inside(target, args.output_folder, frame)
        if args.skip_existing and target.exists():
            say(f"[{index}/{len(frames)}] frame {frame}: skipped ({target} exists)")
            continue
        render_frame(scene, args.output, frame, target, blend)
        say(f"[{index}/{len(frames)}] frame {frame}: {target} "
            f"({time.perf_counter() - t0:.2f} s)")
    say(f"Rendered {len(frames)} frame(s) with {scene.render.engine} in "
        f"{time.perf_counter() - start:.2f} s")
    return 0


def check_inside(target, folder, frame):
    """A CommandError unless ``target`` (links and '..' resolved) lies inside ``folder``."""
    real, inside = os.path.realpath(target), os.path.realpath(folder)
    if os.path.commonpath([real, inside]) != inside:
        raise CommandError(
            f"frame {frame} would be written to '{target}', which is outside --output-folder "
            f"'{folder}': give an --output inside it (no '..')"
        )


def frame_range(args, scene):
    """The frames to render, a range (never a list: --frames 1 3000000 costs nothing)."""
    if args.frame is not None:
        return range(args.frame, args.frame + 1)
    if args.frames is not None:
        first, last = args.frames
        if last < first:
            raise CommandError(f"--frames {first} {last}: the last frame comes before the first")
        return range(first, last + 1)
    return range(scene.frame_current, scene.frame_current + 1)


def set_engine(scene, engine, samples):
    from .. import api

    if engine is not None:
        scene.render.engine = "CYCLES" if engine == "CYCLES" else api.eevee_engine_id()
    if samples is not None:
        if scene.render.engine == "CYCLES":
            scene.cycles.samples = samples
        elif scene.render.engine == api.eevee_engine_id():
            scene.eevee.taa_render_samples = samples
        else:
            raise CommandError(f"--samples does not apply to engine {scene.render.engine}")


def frame_target(scene, output, frame):
    """The file frame ``frame`` of ``output`` goes to (Blender's -o rules), as a Path."""
    import bpy

    scene.render.filepath = output
    return Path(bpy.path.abspath(scene.render.frame_path(frame=frame)))


def check_lighting(scene, frame):
    """A CommandError naming the coefficient or gain that is not a valid number at ``frame``
    as the render evaluates it (keyed to NaN, driven beyond float32, text...), which would
    render black; nothing when the scene has no coefficients."""
    import bpy

    from .. import api

    if not api.has_coefficients(scene):
        return
    evaluated = scene.evaluated_get(bpy.context.evaluated_depsgraph_get())
    try:
        api.validate_coefficients(api.get_coefficients(evaluated))
    except ValueError as error:
        raise CommandError(f"frame {frame} not rendered: {error}") from None


def render_frame(scene, output, frame, target, blend):
    """Render ``frame`` into ``target`` atomically; a CommandError if it cannot be written."""
    import bpy

    refuse_inputs(target, "--output", {".blend file": blend})
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise CommandError(
            f"cannot create the folder of frame {frame}, '{target.parent}': "
            f"{error.strerror}{' (a file is in the way)' if file_in_way(target) else ''}"
        ) from None
    remove_own_leftovers(target)
    scene.frame_set(frame)
    check_lighting(scene, frame)
    try:
        with atomic_destination(target, overwrite=True, suffix=target.suffix,
                                what="render output") as temporary:
            scene.render.filepath = str(temporary)
            try:
                bpy.ops.render.render(write_still=True, scene=scene.name)
                interrupts.check()
            finally:
                scene.render.filepath = output
    except (OSError, RuntimeError) as error:
        raise CommandError(f"frame {frame} could not be written: {error}") from None
