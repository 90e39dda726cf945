"""``compute HDRI_OR_BLEND``: the 9 coefficients of an HDRI file or of a .blend's world,
printed, optionally written as a preset or an interop file."""

import math
import time
from pathlib import Path

from ..choices import FILAMENT_FRAMES, FORMATS
from . import interrupts
from .options import add_nonfinite, add_scene, positive
from .paths import blend_relative, check_new_file, input_file, refuse_inputs, remove_own_leftovers
from .report import CommandError, before_long, say, stage_line, timed_stage
from .session import open_blend, open_file, pick_scene

HELP = "coefficients of an HDRI or of a .blend's world; print them, write a preset"
NONFINITE_ADVICE = "repair the image, or pass --nonfinite zero to treat those texels as black"


def add_arguments(p, prog):
    p.description = (
        "Project an equirectangular HDRI (EXR, HDR, any image Blender reads), or the world of "
        "a .blend (read only, the file is not saved), onto the 9 lighting coefficients L_lm; "
        "print them and optionally write a preset.")
    p.epilog = f"example:\n  {prog} compute forest.exr --out forest.json"
    p.add_argument("input", metavar="HDRI_OR_BLEND", nargs="?",
                   help="equirectangular image file, or a .blend file (its scene's world); "
                   "under blender -P it defaults to the open .blend")
    p.add_argument("--out", metavar="PRESET", help="write the coefficients to this file")
    p.add_argument("--overwrite", action="store_true", help="replace an existing --out file")
    p.add_argument("--format", choices=tuple(FORMATS), default="sh_lighting",
                   help="file format of --out: sh_lighting (our preset JSON, the default), "
                   "threejs (a LightProbe for three.js's ObjectLoader), gltf (a .gltf "
                   "EXT_lights_image_based environment: irradiance coefficients and a "
                   "specular cube prefiltered from the image, as Babylon.js reads it), "
                   "filament (a cmgen-style sh.txt)")
    frames = tuple(FILAMENT_FRAMES)
    p.add_argument("--filament-frame", choices=frames, default=frames[0],
                   help="axes of --format filament: cmgen (the default) lines up with what "
                   "cmgen writes for the same equirect image (its specular KTX); gltf lines "
                   "up with a glTF export of the Blender scene. Not windowed (cmgen's "
                   "default is --sh-window=auto)")
    p.add_argument("--capture-width", type=positive, metavar="N",
                   help="width of the Cycles capture of a procedural world (default: the "
                   "scene's setting, else 256)")
    add_scene(p)
    add_nonfinite(p)
    p.add_argument("--projection", choices=("equirect", "mirror_ball"),
                   help="how an HDRI image maps to directions: equirect (the default: a "
                   "latitude-longitude map, twice as wide as high) or mirror_ball (a "
                   "chrome-ball photo filling the image); the line after the command says "
                   "which was used")
    p.add_argument(
        "--lights", type=int, metavar="K", choices=range(0, 9),
        help="take up to K (0-8) compact bright sources out of the world image as Sun lights "
        "(printed); the coefficients (and --out) then hold the rest of the world")


def run(args):
    args.projection_given = args.projection is not None
    args.projection = args.projection or "equirect"
    from .. import api
    from ..api import HDRI_ERROR_NORMALS as ERROR_NORMALS
    from ..api import hdri_metadata
    from ..core.sh import coefficient_table

    is_blend = args.input is None or Path(args.input).suffix.lower() == ".blend"
    if args.input is not None:
        hint = "give a .blend file" if is_blend else "give an HDRI image or a .blend file"
        source = input_file(args.input, ".blend file" if is_blend else "HDRI", hint)
    else:
        source = open_file()
    out = blend_relative(args.out, source if is_blend else open_file(), "--out")
    if out is not None:
        refuse_inputs(out, "--out", {".blend file" if is_blend else "HDRI": source})
        check_new_file(out, args.overwrite, what="--out")
    start = time.perf_counter()
    if is_blend:
        source, scene, coeffs, metadata = _world(args)
        hdri = None
        environment = api.world_environment(scene) if args.format == "gltf" else None
    else:
        if args.lights is not None and args.projection == "mirror_ball":
            raise CommandError("--lights takes equirectangular images only: leave out "
                               "--projection mirror_ball, or --lights")
        hdri = read_hdri_file(source, args.nonfinite, args.projection)
        coeffs, metadata, scene = hdri.coefficients, hdri_metadata(hdri), None
        # the specular cube of a glTF export is prefiltered from an equirect map only
        environment = (hdri.pixels, 1.0, None) if hdri.projection == "equirect" else None
        say(how_read(source, hdri, args.projection_given))
    texels = 0 if hdri is None else hdri.pixels.shape[0] * hdri.pixels.shape[1]
    if args.lights is not None:
        before_long("extracting lights", texels / PASS_TEXELS_PER_SECOND)
        with timed_stage("Extract Lights"):
            coeffs, count = _lights(source, scene, hdri, args.lights, args.nonfinite)
        metadata["notes"] = (metadata.get("notes", "") + f" {count} light(s) extracted: these "
                             "coefficients hold the rest of the world.").strip()
        metadata.pop("error_estimate", None)  # it was the whole world's
    elapsed = time.perf_counter() - start
    say("Lighting coefficients L_lm (raw radiance, Blender world axes, z up):")
    for line in coefficient_table(coeffs):
        say(line)
    estimate = metadata.get("error_estimate")
    if estimate is not None:
        say(f"9-term irradiance error (fraction of the total light, {ERROR_NORMALS} normals): "
            f"mean {100 * estimate['mean']:.2f} %, max {100 * estimate['max']:.2f} %")
    say(f"Computed in {elapsed:.2f} s")
    if out is not None:
        remove_own_leftovers(out)
        interrupts.check()
        if args.format == "gltf" and environment is not None:
            before_long("prefiltering the specular cube", texels / PASS_TEXELS_PER_SECOND)
        try:
            with timed_stage("writing (with the specular cube)" if args.format == "gltf"
                             else "writing"):
                path = api.export_coefficients(
                    coeffs, out, args.format, args.overwrite, metadata, environment,
                    args.filament_frame,
                )
        except (OSError, ValueError) as error:
            raise CommandError(str(error)) from None
        say(f"Wrote {FORMATS[args.format][0]} {path}")
    return 0


def how_read(source, hdri, given):
    """"HDRI path (W x H, read as ...)", and for a square image read as equirect without a
    --projection, what else it may be (a mirror ball) and how to say so."""
    height, width = hdri.pixels.shape[:2]
    if hdri.projection == "mirror_ball":
        return f"HDRI {source} ({width}x{height}, read as a mirror ball)"
    line = f"HDRI {source} ({width}x{height}, read as equirectangular)"
    if width == height and not given:
        line += ("; a square image is often a mirror ball (an equirectangular map is twice "
                 "as wide as high): if it is one, pass --projection mirror_ball")
    return line


# Rough rates of this work on one core, for the line before a long step (``before_long``):
# Blender decodes a ZIP EXR or a .hdr at about 150 MB/s of file, other images at about
# 30 MB/s; the projection and the estimate take about 0.6 times the decode; Extract Lights
# and the glTF specular cube each about one pass over the map.
DECODE_BYTES_PER_SECOND = {".exr": 150e6, ".hdr": 150e6}
OTHER_BYTES_PER_SECOND = 30e6
PROJECTION_PER_DECODE = 0.6
PASS_TEXELS_PER_SECOND = 60e6  # Extract Lights, the specular cube: a pass over the map


def read_hdri_file(path, nonfinite, projection="equirect"):
    """``blender.world.hdri.read_hdri`` of ``path``, its errors as one CommandError line; a
    line on stderr before each step expected to take long (a big file)."""
    from ..api import read_hdri
    from ..core.equirect import NonFiniteError

    path = Path(path)
    size = path.stat().st_size
    rate = DECODE_BYTES_PER_SECOND.get(path.suffix.lower(), OTHER_BYTES_PER_SECOND)
    before_long(f"decoding {path.name} ({size / 1e6:.0f} MB)", size / rate)

    def progress(stage, seconds):
        stage_line(stage, seconds)
        if stage == "decode":
            before_long("projecting onto the 9 coefficients, then the error estimate",
                        PROJECTION_PER_DECODE * seconds)

    try:
        return read_hdri(path, nonfinite, progress=progress, projection=projection)
    except NonFiniteError as error:
        raise CommandError(
            f"{path}: the image has {error.description}: {NONFINITE_ADVICE}"
        ) from None
    except ValueError as error:
        raise CommandError(f"{path}: {error}") from None


def _world(args):
    """(.blend path, scene, coefficients, metadata) of the world of the .blend ``args.input``."""
    from .. import api

    source = open_blend(args.input)
    scene = pick_scene(args.scene)
    try:
        coeffs = api.compute_from_world(scene, capture_width=args.capture_width,
                                        nonfinite=args.nonfinite)
    except ValueError as error:  # the API's advice, in this command's words
        message = str(error).replace("pass nonfinite='zero'", "pass --nonfinite zero")
        raise CommandError(f"{source}: {message}") from None
    metadata = api.scene_metadata(scene)
    metadata["name"] = source.stem
    origin = metadata.get("source")
    how = f"image {origin}" if origin else "a Cycles capture"
    metadata["notes"] = f"Computed from world '{scene.world.name}' of {source.name} ({how})."
    say(f"World '{scene.world.name}' of {source} (scene '{scene.name}', from {how})")
    return source, scene, coeffs, metadata


def _lights(source, scene, hdri, count, nonfinite="raise"):
    """Up to ``count`` lights out of ``hdri`` (``scene`` None) or the world of ``scene`` (its
    NaN/Inf texels black with ``nonfinite`` "zero", as for the coefficients); prints them,
    returns the rest's (9, 3) coefficients and the number of lights."""
    try:
        if scene is None:
            from ..api import hdri_lights

            extraction, coeffs = hdri_lights(hdri, count)
            found = [(light.direction, light.angular_diameter, light.colour, light.strength,
                      light.power_fraction) for light in extraction.lights]
        else:
            from .. import api

            info = api.extract_lights(scene, count, nonfinite=nonfinite)
            extraction, coeffs = info.extraction, info.coefficients
            found = [(obj.rotation_euler.to_matrix().col[2][:], obj.data.angle,
                      obj.data.color[:], obj.data.energy, light.power_fraction)
                     for obj, light in zip((scene.objects[n] for n in info.lights),
                                           extraction.lights)]
    except ValueError as error:
        raise CommandError(f"{source}: {error}") from None
    for i, (direction, angle, colour, strength, share) in enumerate(found, 1):
        d = ", ".join(f"{v:+.4f}" for v in direction)
        c = ", ".join(f"{v:.4f}" for v in colour)
        say(f"Light {i}: Sun toward ({d}), angle {math.degrees(angle):.2f}°, colour ({c}), "
            f"strength {strength:.6g} W/m², {100 * share:.1f} % of the light")
    (before, _), (after, _) = extraction.errors[0], extraction.errors[-1]
    why = "" if extraction.stop_kind == "COUNT" else f"; no more: {extraction.stop}"
    say(f"{len(found)} light(s) extracted: mean irradiance error {100 * before:.2f} % with SH "
        f"alone, {100 * after:.2f} % with SH + lights (fraction of the total light){why}")
    return coeffs, len(found)
