"""``bake-transfer [BLEND]``: the transfer T_lm (shadows and bounce light) of a .blend's meshes
baked by Cycles (``blender.transfer``), optionally applied to their materials, saved to a new
file or in place."""

from . import interrupts
from .apply import objects_to_apply
from .options import add_blend_output, add_mode, add_scene, positive
from .report import CommandError, say
from .session import open_blend, open_file, output_blend, pick_scene, save_and_say

HELP = "bake the SH transfer (shadows, bounce light) of a .blend's meshes with Cycles"
DEFAULT_SAMPLES = 64  # blender.transfer.bake.DEFAULT_SAMPLES (no bpy import for --help)


def add_arguments(p, prog):
    p.description = (
        "Bake, for the meshes of the scene (or --objects), the nine transfer values per face "
        "corner (precomputed radiance transfer: the SH lighting with the scene's shadows and "
        "interreflection) with Cycles, then save to --out (a new file) or over the input "
        "with --in-place. --apply also puts the SH Transfer group into their materials.")
    p.epilog = (f"example:\n  {prog} bake-transfer shot.blend --objects Ground Box "
                "--samples 64 --apply --out shot_transfer.blend")
    p.add_argument("blend", metavar="BLEND", nargs="?",
                   help=".blend file to bake (under blender -P: default the open one)")
    add_blend_output(p)
    p.add_argument("--objects", nargs="+", metavar="NAME",
                   help="the meshes to bake (default: every mesh the scene renders, those "
                   "that cannot be baked skipped with the reason)")
    p.add_argument("--samples", type=positive, default=DEFAULT_SAMPLES,
                   help=f"Cycles samples per corner and basis function (default "
                   f"{DEFAULT_SAMPLES}; the noise falls as 1/sqrt(samples))")
    p.add_argument("--error-target", type=float, metavar="PERCENT",
                   help="choose the samples for this noise of the ambient transfer instead "
                   "(relative RMS over the corners, e.g. 1 for 1 %%; two probe bakes first)")
    p.add_argument("--store", choices=("auto", "corners", "texels"), default="auto",
                   help="where the transfer is stored: auto (default) per texel for meshes too "
                   "coarse to carry a shadow at their corners, such as a plain floor, per "
                   "corner for the others; corners or texels for every mesh")
    p.add_argument("--apply", action="store_true",
                   help="also light the baked objects' materials by the transfer")
    add_scene(p, "scene to bake")
    add_mode(p)


def run(args):
    from .. import api

    blend = open_file() if args.blend is None else None
    blend = open_blend(args.blend, load_ui=True) if args.blend is not None else blend
    if blend is None:
        raise CommandError("no .blend given and none is open: pass the .blend file")
    out = output_blend(args, blend)
    scene = pick_scene(args.scene)
    if args.objects:
        objects = objects_to_apply(scene, args.objects)
    else:  # every mesh the scene renders; those that cannot be baked are said and skipped
        objects = []
        for obj in (o for o in scene.objects if o.type == "MESH" and not o.hide_render):
            reason = api.transfer_refusal(scene, obj, args.store.upper())
            if reason is None:
                objects.append(obj)
            else:
                say(f"skipped: {reason}")
        if not objects:
            raise CommandError("no mesh of the scene can be baked (see above); nothing saved")
    try:
        target = None if args.error_target is None else args.error_target / 100.0
        with interrupts.at_once():  # Cycles' bake would swallow a KeyboardInterrupt
            info = api.bake_transfer(scene, objects, samples=args.samples, report=say,
                                     error_target=target, store=args.store.upper())
    except api.TransferError as error:
        raise CommandError(f"{error}; nothing saved") from None
    say(f"Baked the transfer of {len(info.objects)} object(s) ({', '.join(info.objects)}): "
        f"{info.vertices} vertices, {info.corners} corners, {info.texels} texels, "
        f"{info.samples} samples, {info.seconds:.1f} s{info.rates()}")
    for note in info.notes:
        say(f"note: {note}")
    if args.apply:
        try:
            changed, skipped = api.apply_transfer(objects, scene, args.mode)
        except ValueError as error:
            raise CommandError(f"{error}; nothing saved") from None
        for name, reason in skipped:
            say(f"skipped '{name}': {reason}")
        say(f"Transfer applied to {len(changed)} material(s): {', '.join(changed)}")
    save_and_say(args, out)
    return 0
