"""``luminaire FILE BLEND``: a measured luminaire (IES or EULUMDAT) added to a .blend's scene
(``api.add_luminaire``: exact in Cycles, fitted lamps in EEVEE), its fit printed, saved."""

import math

from .options import add_blend_output, add_scene, positive
from .paths import changed_alone, input_file
from .report import CommandError, say
from .session import open_blend, open_file, output_blend, pick_scene, save_and_say

HELP = "add a measured luminaire (IES, EULUMDAT) to a .blend; print its fit"


def add_arguments(p, prog):
    p.description = (
        "Read an IES LM-63 or EULUMDAT file and add it to the scene as a measured luminaire: "
        "a light with Blender's IES node (Cycles, exact) and up to --lamps fitted spot and "
        "point lights (EEVEE, with shadows). Prints the file's flux, the lamps and the fit's "
        "errors, then saves to --out or --in-place.")
    p.epilog = (f"example:\n  {prog} luminaire downlight.ldt room.blend --location 0 0 2.8 "
                "--temperature 3000 --out room_lit.blend")
    p.add_argument("file", metavar="FILE", help="the photometric file (.ies or .ldt)")
    p.add_argument("blend", metavar="BLEND", nargs="?",
                   help=".blend file to change (under blender -P: default the open one)")
    add_blend_output(p)
    add_scene(p, "scene to add it to")
    p.add_argument("--location", nargs=3, type=float, default=(0.0, 0.0, 3.0),
                   metavar=("X", "Y", "Z"), help="where it hangs, metres (default 0 0 3)")
    p.add_argument("--rotation", nargs=3, type=float, default=(0.0, 0.0, 0.0),
                   metavar=("X", "Y", "Z"), help="Euler XYZ in degrees (default 0 0 0: "
                   "shining down)")
    p.add_argument("--power", type=float, default=1.0, metavar="W",
                   help="its Power (default 1 W: the file's candela)")
    p.add_argument("--temperature", type=float, metavar="K",
                   help="colour it as a blackbody at K kelvin (800 to 20000)")
    p.add_argument("--lamps", type=positive, default=8, metavar="N",
                   help="most EEVEE lamps, 1 to 8 (default 8)")
    p.add_argument("--error-target", type=float, default=3.0, metavar="PERCENT",
                   help="stop adding lamps at this error (default 3)")
    p.add_argument("--near-distance", type=float, default=0.0, metavar="M",
                   help="metres to the nearest lit surface: closer than 5 x the luminous "
                   "opening, the lamps are repeated over its cells (default 0: far field)")


def run(args):
    values = (*args.location, *args.rotation, args.power, args.error_target, args.near_distance)
    if (not all(math.isfinite(v) for v in values) or args.power < 0 or args.error_target <= 0
            or args.near_distance < 0):
        raise CommandError("--location, --rotation, --power, --error-target and --near-distance "
                           "must be finite numbers (power and distance at least 0, error target "
                           "above 0)")
    if not 1 <= args.lamps <= 8:
        raise CommandError(f"--lamps {args.lamps}: from 1 to 8")
    if args.temperature is not None and not 800.0 <= args.temperature <= 20000.0:
        raise CommandError(f"--temperature {args.temperature}: from 800 to 20000 K")
    source = input_file(args.file, "photometric file", "give an .ies or .ldt file")
    from ..formats.photometric_file import read_photometry
    from ..formats.photometry import PhotometryError

    try:  # refused before Blender opens the .blend
        read_photometry(source)
    except PhotometryError as error:
        raise CommandError(str(error)) from None
    if args.blend is not None:
        blend = input_file(args.blend, ".blend file", "give the .blend file to change")
    else:
        blend = open_file()
    out = output_blend(args, blend, {"photometric file": source})
    if args.in_place:
        with changed_alone(blend, ".blend file"):
            return add_and_save(args, source, out)
    return add_and_save(args, source, out)


def add_and_save(args, source, out):
    from .. import api

    open_blend(args.blend, load_ui=True)
    scene = pick_scene(args.scene)
    fit = api.LuminaireFit(args.error_target / 100.0, args.lamps,
                           near_distance=args.near_distance)
    try:
        info = api.add_luminaire(scene, source, location=tuple(args.location),
                                 rotation=tuple(math.radians(a) for a in args.rotation),
                                 fit=fit, power=args.power)
        if args.temperature is not None:
            api.set_luminaire_temperature(info.root, args.temperature)
    except ValueError as error:
        raise CommandError(str(error)) from None
    say(info.report())
    for lamp in info.lamps:
        data = lamp.data
        cone = (f", cone {math.degrees(data.spot_size):.1f}°, blend {data.spot_blend:.2f}"
                if data.type == "SPOT" else "")
        say(f"  {lamp.name}: {data.type.lower()}{cone}")
    save_and_say(args, out)
    return 0
