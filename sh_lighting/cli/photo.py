"""``from-photo IMAGE --circle CX CY R``: the 9 coefficients from a photo of a grey ball
(``api.coefficients_from_photo``), printed with the fit's report, optionally written as a
preset or an interop file."""

import math

from ..choices import FORMATS, PHOTO_PRIORS
from .options import add_scene
from .paths import blend_relative, check_new_file, input_file, refuse_inputs, remove_own_leftovers
from .report import CommandError, say
from .session import open_blend, open_file, pick_scene

HELP = "coefficients from a photo of a grey (matte) ball; print them, write a preset"
DEFAULT_ALBEDO, DEFAULT_MARGIN = 0.18, 0.05  # core.photo's (no numpy import for --help)


def add_arguments(p, prog):
    p.description = (
        "Fit the 9 lighting coefficients L_lm to the pixels of a grey ball in a photo (8-bit "
        "sRGB PNG/JPEG decoded as Blender decodes it, or linear EXR/HDR). The camera is the "
        "scene camera of --blend (orientation, lens, sensor, orthographic or perspective), "
        "or --direction with --roll and --projection. Prints the coefficients and the fit's "
        "residual, condition, poorly constrained terms and clipped pixels.")
    p.epilog = (f"example:\n  {prog} from-photo ball.png --circle 640 360 120 --blend shot.blend "
                "--out ball.json")
    p.add_argument("image", metavar="IMAGE", help="the photo of the grey ball")
    where = p.add_mutually_exclusive_group(required=True)
    where.add_argument("--circle", nargs=3, type=float, metavar=("CX", "CY", "R"),
                       help="the ball's centre and radius in pixels from the top-left corner")
    where.add_argument("--detect", action="store_true",
                       help="find the ball's circle in the photo (printed: check it, and pass "
                       "--circle to correct it)")
    p.add_argument("--blend", metavar="BLEND",
                   help=".blend whose scene camera took the photo (under blender -P: default "
                   "the open one)")
    add_scene(p)
    p.add_argument("--direction", nargs=3, type=float, metavar=("X", "Y", "Z"),
                   help="instead of a camera: the world direction the photo looks along")
    p.add_argument("--roll", type=float, default=0.0, metavar="DEGREES",
                   help="roll about --direction (default 0: up as close to +Z as it can be)")
    p.add_argument("--projection", choices=("ortho", "persp"), default="ortho",
                   help="with --direction: orthographic (default) or perspective")
    p.add_argument("--lens", type=float, default=85.0, metavar="MM",
                   help="with --direction --projection persp: focal length (default 85)")
    p.add_argument("--sensor", type=float, default=36.0, metavar="MM",
                   help="with --direction --projection persp: sensor size along the photo's "
                   "longer side (default 36)")
    p.add_argument("--albedo", type=float, default=DEFAULT_ALBEDO,
                   help=f"the ball's diffuse reflectance (default {DEFAULT_ALBEDO})")
    p.add_argument("--margin", type=float, default=DEFAULT_MARGIN,
                   help=f"fraction of the radius left out at the rim (default {DEFAULT_MARGIN})")
    p.add_argument("--prior", choices=PHOTO_PRIORS, default=PHOTO_PRIORS[0],
                   help="what lights the unseen side: mirror (the seen side mirrored, the "
                   "default), ambient (its mean), chrome (a chrome ball: --chrome, or the "
                   "--blend's world), photo (a second photo: --second), none (the fit "
                   "extrapolated)")
    p.add_argument("--chrome", metavar="IMAGE",
                   help="a chrome ball's mirror-ball image of the same place: the grey ball's "
                   "exposure is compared with it (printed), and it is --prior chrome's")
    p.add_argument("--second", metavar="IMAGE",
                   help="for --prior photo: a photo of the same ball from another side, same "
                   "exposure")
    p.add_argument("--second-circle", nargs=3, type=float, metavar=("CX", "CY", "R"),
                   help="the ball's circle in --second, in pixels")
    p.add_argument("--second-direction", nargs=3, type=float, metavar=("X", "Y", "Z"),
                   help="the world direction --second looks along (its lens and projection: "
                   "the first photo's)")
    p.add_argument("--second-roll", type=float, default=0.0, metavar="DEGREES",
                   help="roll of --second about --second-direction")
    p.add_argument("--second-camera", metavar="NAME",
                   help="instead of --second-direction: the camera object of --blend that "
                   "took --second")
    p.add_argument("--clip", type=float, metavar="VALUE",
                   help="also leave out pixels with a linear channel at or above VALUE")
    p.add_argument("--out", metavar="PRESET", help="write the coefficients to this file")
    p.add_argument("--overwrite", action="store_true", help="replace an existing --out file")
    p.add_argument("--format", choices=tuple(f for f in FORMATS if f != "gltf"),
                   default="sh_lighting", help="file format of --out (as for compute; a "
                   "photo has no environment image for gltf)")


def run(args):
    from .. import api
    from ..core.sh import coefficient_table

    image = input_file(args.image, "photo", "give the photo's image file")
    chrome = None if args.chrome is None else input_file(args.chrome, "chrome ball",
                                                         "give its mirror-ball image file")
    second = _second_photo(args)
    blend = None
    if args.blend is not None:
        blend = open_blend(args.blend)
    elif args.direction is None:
        blend = open_file()
        if blend is None:
            raise CommandError("no camera: pass --blend (its scene camera took the photo) or "
                               "--direction X Y Z")
    out = blend_relative(args.out, blend, "--out")
    if out is not None:
        refuse_inputs(out, "--out", {"photo": image})
        check_new_file(out, args.overwrite, what="--out")
    scene = pick_scene(args.scene)
    circle = None if args.detect else tuple(args.circle)
    if circle is None:
        try:
            guess = api.detect_photo_ball(image)
        except ValueError as error:
            raise CommandError(f"{image}: {error}") from None
        circle = guess.circle
        say(f"Photo {image}: {guess.summary()}; --circle {circle[0]:.1f} {circle[1]:.1f} "
            f"{circle[2]:.1f}")
    if second is not None and args.second_camera is not None:
        camera = bpy_object(args.second_camera)
        second = api.SecondPhoto(second.path, second.circle, camera_object=camera)
    try:
        coeffs, fit = api.coefficients_from_photo(
            scene, image, circle, direction=args.direction,
            roll=math.radians(args.roll), projection=args.projection.upper(),
            focal_mm=args.lens, sensor_mm=args.sensor, albedo=args.albedo,
            margin=args.margin, prior=args.prior, clip=args.clip, chrome=chrome,
            second=second, store=False)
        exposure = (api.photo_exposure(scene, fit, chrome)
                    if chrome is not None or args.prior == "chrome" else None)
    except ValueError as error:
        raise CommandError(f"{image}: {error}") from None
    if fit.warning() is not None:  # first: a wrong circle reads as a poor fit
        say(f"warning: {image}: {fit.warning()}")
    say(f"Photo {image}: {fit.summary()}")
    if exposure is not None:
        say(f"Both balls: {exposure.summary()}")
    say("Lighting coefficients L_lm (raw radiance, Blender world axes, z up):")
    for line in coefficient_table(coeffs):
        say(line)
    if out is not None:
        remove_own_leftovers(out)
        warning = f" Warning: {fit.warning()}." if fit.warning() else ""
        metadata = {"name": image.stem, "notes": f"Fitted to a grey ball in {image.name}: "
                    f"{fit.summary()}.{warning}"}
        try:
            path = api.export_coefficients(coeffs, out, args.format, args.overwrite,
                                                 metadata)
        except (OSError, ValueError) as error:
            raise CommandError(str(error)) from None
        say(f"Wrote {FORMATS[args.format][0]} {path}")
    return 0


def _second_photo(args):
    """The ``SecondPhoto`` of --second (camera object resolved later), None without it, or a
    CommandError when --prior photo lacks it or its circle or camera."""
    if args.second is None:
        if args.prior == "photo":
            raise CommandError("--prior photo needs --second IMAGE --second-circle CX CY R and "
                               "--second-direction X Y Z (or --second-camera NAME)")
        return None
    if args.second_circle is None or (args.second_direction is None
                                      and args.second_camera is None):
        raise CommandError("--second needs --second-circle CX CY R and --second-direction X Y "
                           "Z (or --second-camera NAME)")
    from .. import api

    path = input_file(args.second, "second photo", "give the second photo's image file")
    return api.SecondPhoto(path, tuple(args.second_circle),
                           direction=args.second_direction,
                           roll=math.radians(args.second_roll))


def bpy_object(name):
    """The camera object ``name`` of the open .blend, or a CommandError."""
    import bpy

    camera = bpy.data.objects.get(name)
    if camera is None or camera.type != "CAMERA":
        raise CommandError(f"--second-camera: no camera object '{name}' in the .blend: give "
                           "one of its cameras' names, or --second-direction")
    return camera
